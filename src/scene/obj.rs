//! Wavefront OBJ as a plain mesh (positions and faces; materials and normals are not read,
//! normals are recomputed): parsed by `tobj`, polygons triangulated, every object in the file
//! merged, degenerate triangles dropped and counted.

use glam::Vec3;

use super::limits::{MAX_TRIANGLES, MAX_VERTICES};
use super::mesh::push_fan;
use super::RawMesh;

#[derive(Debug, thiserror::Error, PartialEq)]
pub enum ObjError {
    #[error("OBJ: {0}")]
    Parse(String),
    #[error("OBJ has no faces")]
    NoFaces,
    #[error("OBJ has {count} {what}; the limit is {limit}")]
    TooMany {
        what: &'static str,
        count: usize,
        limit: usize,
    },
    #[error("OBJ vertex {0} has a non-finite coordinate")]
    NonFinite(usize),
}

pub fn parse_obj(bytes: &[u8]) -> Result<RawMesh, ObjError> {
    let options = tobj::LoadOptions {
        triangulate: true,
        single_index: false,
        ..Default::default()
    };
    // Material libraries are not followed: an OBJ is geometry here, its material comes from
    // the scene file.
    let (models, _) = tobj::load_obj_buf(&mut std::io::Cursor::new(bytes), &options, |_| {
        Err(tobj::LoadError::OpenFileFailed)
    })
    .map_err(|e| ObjError::Parse(e.to_string()))?;
    let mut out = RawMesh::default();
    for model in models {
        let m = model.mesh;
        let base = out.positions.len();
        let count = base + m.positions.len() / 3;
        if count > MAX_VERTICES {
            return Err(ObjError::TooMany {
                what: "vertices",
                count,
                limit: MAX_VERTICES,
            });
        }
        for (i, p) in m.positions.chunks_exact(3).enumerate() {
            let p = Vec3::new(p[0], p[1], p[2]);
            if !p.is_finite() {
                return Err(ObjError::NonFinite(base + i));
            }
            out.positions.push(p);
        }
        for tri in m.indices.chunks_exact(3) {
            let corners = [tri[0], tri[1], tri[2]].map(|i| i + base as u32);
            if corners.iter().any(|&i| i as usize >= out.positions.len()) {
                return Err(ObjError::Parse("face vertex index out of bounds".into()));
            }
            let before = out.indices.len();
            push_fan(&corners, &out.positions, &mut out.indices);
            if out.indices.len() == before {
                out.dropped_degenerate += 1;
            }
        }
        if out.indices.len() / 3 > MAX_TRIANGLES {
            return Err(ObjError::TooMany {
                what: "triangles",
                count: out.indices.len() / 3,
                limit: MAX_TRIANGLES,
            });
        }
    }
    if out.indices.is_empty() {
        return Err(ObjError::NoFaces);
    }
    Ok(out)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_quad_and_a_triangle_from_two_objects() {
        let text = b"o a\nv 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nf 1 2 3 4\n\
o b\nv 0 0 1\nv 1 0 1\nv 0 1 1\nf -3 -2 -1\n";
        let m = parse_obj(text).unwrap();
        assert_eq!(m.positions.len(), 7);
        assert_eq!(m.indices.len(), 9);
        assert!(m.indices.iter().all(|&i| (i as usize) < m.positions.len()));
    }

    #[test]
    fn bad_obj_files_are_errors() {
        assert!(matches!(
            parse_obj(b"v 0 0 0\nv 1 0 0\nf 1 2 9\n"),
            Err(ObjError::Parse(_))
        ));
        assert_eq!(parse_obj(b"v 0 0 0\n"), Err(ObjError::NoFaces));
        assert!(matches!(
            parse_obj(b"v 0 0 0\nv nan 0 0\nv 0 1 0\nf 1 2 3\n"),
            Err(ObjError::NonFinite(1))
        ));
        let m = parse_obj(b"v 0 0 0\nv 1 0 0\nv 2 0 0\nv 0 1 0\nf 1 2 3\nf 1 2 4\n").unwrap();
        assert_eq!(m.dropped_degenerate, 1);
        assert!(parse_obj(b"\xff\xfe garbage").is_err());
    }
}
