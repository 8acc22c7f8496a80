//! One glTF primitive as world-space triangles: its accessors checked (types, counts, index
//! range, finite positions) before they are read, strips and fans triangulated, degenerate
//! triangles dropped, vertex colours kept as a tint, and texture coordinates for the base
//! colour map and the normal/occlusion maps, each from its own set and transformed.

use glam::{Mat3, Mat4, Vec3};

use super::texture::UvMap;
use super::Part;
use crate::scene::limits::{MAX_TRIANGLES, MAX_VERTICES};
use crate::scene::mesh::push_fan;
use crate::scene::RawMesh;

pub fn read_primitive(
    prim: &gltf::Primitive,
    buffers: &[Vec<u8>],
    world: Mat4,
    [base, detail]: [Option<UvMap>; 2],
    needs_tangents: bool,
    material: usize,
) -> Result<Option<Part>, String> {
    use gltf::mesh::Mode;
    let mode = prim.mode();
    if !matches!(
        mode,
        Mode::Triangles | Mode::TriangleStrip | Mode::TriangleFan
    ) {
        return Ok(None);
    }
    let check =
        |sem: gltf::Semantic, dims: gltf::accessor::Dimensions| -> Result<Option<usize>, String> {
            let Some(a) = prim.get(&sem) else {
                return Ok(None);
            };
            if a.count() == 0 {
                return Err(format!("{sem:?} accessor is empty"));
            }
            let float = a.data_type() == gltf::accessor::DataType::F32;
            if a.dimensions() != dims
                || (!float
                    && !matches!(
                        sem,
                        gltf::Semantic::Colors(_) | gltf::Semantic::TexCoords(_)
                    ))
            {
                return Err(format!(
                    "{sem:?} is {:?} {:?}; Fovea reads float {dims:?} (dequantize the file)",
                    a.data_type(),
                    a.dimensions()
                ));
            }
            Ok(Some(a.count()))
        };
    let count = check(gltf::Semantic::Positions, gltf::accessor::Dimensions::Vec3)?
        .ok_or("no POSITION attribute")?;
    if count > MAX_VERTICES {
        return Err(format!(
            "{count} vertices is over the limit of {MAX_VERTICES}"
        ));
    }
    let reader = prim.reader(|b| buffers.get(b.index()).map(Vec::as_slice));
    let local: Vec<Vec3> = reader
        .read_positions()
        .ok_or("POSITION data lies outside its buffer")?
        .map(Vec3::from)
        .collect();
    if local.len() != count {
        return Err("POSITION data lies outside its buffer".into());
    }
    let positions: Vec<Vec3> = local.iter().map(|p| world.transform_point3(*p)).collect();
    if let Some(i) = positions.iter().position(|p| !p.is_finite()) {
        return Err(format!("vertex {i} has a non-finite position"));
    }
    let normal_matrix = Mat3::from_mat4(world).inverse().transpose();
    let normals = match check(gltf::Semantic::Normals, gltf::accessor::Dimensions::Vec3) {
        Ok(Some(n)) if n == count => reader.read_normals().map(|it| {
            it.map(|n| {
                (normal_matrix * Vec3::from(n))
                    .try_normalize()
                    .unwrap_or(Vec3::Y)
            })
            .collect::<Vec<_>>()
        }),
        _ => None,
    }
    .filter(|n| n.len() == count);
    let order: Vec<u32> = match prim.indices() {
        Some(a) => {
            if a.count() == 0 || a.dimensions() != gltf::accessor::Dimensions::Scalar {
                return Err("indices must be a non-empty scalar accessor".into());
            }
            if a.count() > MAX_TRIANGLES * 3 {
                return Err(format!("{} indices is over the limit", a.count()));
            }
            let idx: Vec<u32> = reader
                .read_indices()
                .ok_or("indices lie outside their buffer")?
                .into_u32()
                .collect();
            if idx.len() != a.count() {
                return Err("indices lie outside their buffer".into());
            }
            if let Some(bad) = idx.iter().find(|&&i| i as usize >= count) {
                return Err(format!("index {bad} is out of range ({count} vertices)"));
            }
            idx
        }
        None => (0..count as u32).collect(),
    };
    let flip = world.determinant() < 0.0;
    let mut mesh = RawMesh {
        positions,
        ..Default::default()
    };
    let tri = |a: u32, b: u32, c: u32, mesh: &mut RawMesh| {
        let t = if flip { [a, c, b] } else { [a, b, c] };
        let before = mesh.indices.len();
        push_fan(&t, &mesh.positions, &mut mesh.indices);
        if mesh.indices.len() == before {
            mesh.dropped_degenerate += 1;
        }
    };
    match mode {
        Mode::TriangleStrip => {
            for k in 0..order.len().saturating_sub(2) {
                let (a, b, c) = (order[k], order[k + 1], order[k + 2]);
                if k % 2 == 0 {
                    tri(a, b, c, &mut mesh)
                } else {
                    tri(b, a, c, &mut mesh)
                }
            }
        }
        Mode::TriangleFan => {
            for k in 1..order.len().saturating_sub(1) {
                tri(order[0], order[k], order[k + 1], &mut mesh);
            }
        }
        _ => {
            for t in order.chunks_exact(3) {
                tri(t[0], t[1], t[2], &mut mesh);
            }
        }
    }
    let colours: Option<Vec<[f32; 4]>> = reader
        .read_colors(0)
        .map(|c| c.into_rgba_f32().collect::<Vec<_>>())
        .filter(|c| c.len() == count);
    let read_set = |set: u32| -> Option<Vec<[f32; 2]>> {
        let sem = gltf::Semantic::TexCoords(set);
        check(sem, gltf::accessor::Dimensions::Vec2)
            .ok()
            .flatten()?;
        let uv: Vec<[f32; 2]> = reader
            .read_tex_coords(set)?
            .into_f32()
            .map(|t| {
                if t.iter().all(|x| x.is_finite()) {
                    t
                } else {
                    [0.0; 2]
                }
            })
            .collect();
        (uv.len() == count).then_some(uv)
    };
    // Each map's coordinates, transformed; a map without its set reads the other's.
    let coords = |map: Option<UvMap>| -> Option<Vec<[f32; 2]>> {
        let map = map?;
        let raw = read_set(map.set)?;
        Some(raw.into_iter().map(|t| map.apply(t)).collect())
    };
    let (base_uv, detail_uv) = (coords(base), coords(detail));
    let uv: Option<Vec<[f32; 4]>> = match (&base_uv, &detail_uv) {
        (None, None) => None,
        (b, d) => {
            let (b, d) = (b.as_ref().or(d.as_ref()), d.as_ref().or(b.as_ref()));
            b.zip(d).map(|(b, d)| {
                b.iter()
                    .zip(d)
                    .map(|(b, d)| [b[0], b[1], d[0], d[1]])
                    .collect()
            })
        }
    };
    let tint = colours.map(|c| {
        c.into_iter()
            .map(|v| v.map(|x| x.clamp(0.0, 1.0)))
            .collect()
    });
    // Tangents: the file's (moved with the model), else made from the UVs, for normal maps.
    let tangents = if needs_tangents {
        let given = match check(gltf::Semantic::Tangents, gltf::accessor::Dimensions::Vec4) {
            Ok(Some(n)) if n == count => reader.read_tangents().map(|it| {
                let m3 = Mat3::from_mat4(world);
                let flip = if world.determinant() < 0.0 { -1.0 } else { 1.0 };
                it.map(|t| {
                    let v = (m3 * Vec3::new(t[0], t[1], t[2])).normalize_or_zero();
                    [v.x, v.y, v.z, t[3].signum() * flip]
                })
                .collect::<Vec<_>>()
            }),
            _ => None,
        };
        given.or_else(|| {
            // From the normal map's own (transformed) coordinates.
            detail_uv
                .as_ref()
                .map(|uv| crate::scene::mesh::tangents(&mesh.positions, uv, &mesh.indices))
        })
    } else {
        None
    };
    Ok(Some(Part {
        mesh,
        normals,
        tint,
        uv,
        tangents,
        material,
    }))
}
