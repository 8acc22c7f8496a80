//! Binary little-endian PLY reader: enough of the format for scanned meshes (any vertex
//! properties, polygon faces triangulated as fans), with errors that name what is wrong.

use glam::Vec3;

#[derive(Debug, thiserror::Error, PartialEq)]
pub enum PlyError {
    #[error("not a PLY file (it must start with the line `ply`)")]
    NotPly,
    #[error("PLY header is not terminated by `end_header`")]
    NoEndHeader,
    #[error("PLY format {0:?} is not supported; convert to binary_little_endian 1.0")]
    Format(String),
    #[error("PLY header line {line}: {message}")]
    Header { line: usize, message: String },
    #[error("PLY has no vertex element with x, y and z properties")]
    NoPositions,
    #[error("PLY has no face element with a vertex_indices list")]
    NoFaces,
    #[error("PLY data ends early while reading {0}")]
    Truncated(&'static str),
    #[error("face {face} refers to vertex {index}, but there are only {count} vertices")]
    IndexOutOfRange {
        face: usize,
        index: i64,
        count: usize,
    },
    #[error("face {face} has {count} corners; a face needs at least 3")]
    DegenerateFace { face: usize, count: usize },
    #[error("vertex {0} has a non-finite coordinate")]
    NonFinite(usize),
}

#[derive(Debug, Clone, Copy, PartialEq)]
enum Scalar {
    I8,
    U8,
    I16,
    U16,
    I32,
    U32,
    F32,
    F64,
}

impl Scalar {
    fn parse(name: &str) -> Option<Scalar> {
        Some(match name {
            "char" | "int8" => Scalar::I8,
            "uchar" | "uint8" => Scalar::U8,
            "short" | "int16" => Scalar::I16,
            "ushort" | "uint16" => Scalar::U16,
            "int" | "int32" => Scalar::I32,
            "uint" | "uint32" => Scalar::U32,
            "float" | "float32" => Scalar::F32,
            "double" | "float64" => Scalar::F64,
            _ => return None,
        })
    }

    fn size(self) -> usize {
        match self {
            Scalar::I8 | Scalar::U8 => 1,
            Scalar::I16 | Scalar::U16 => 2,
            Scalar::I32 | Scalar::U32 | Scalar::F32 => 4,
            Scalar::F64 => 8,
        }
    }

    fn read(self, b: &[u8]) -> f64 {
        match self {
            Scalar::I8 => f64::from(b[0] as i8),
            Scalar::U8 => f64::from(b[0]),
            Scalar::I16 => f64::from(i16::from_le_bytes([b[0], b[1]])),
            Scalar::U16 => f64::from(u16::from_le_bytes([b[0], b[1]])),
            Scalar::I32 => f64::from(i32::from_le_bytes([b[0], b[1], b[2], b[3]])),
            Scalar::U32 => f64::from(u32::from_le_bytes([b[0], b[1], b[2], b[3]])),
            Scalar::F32 => f64::from(f32::from_le_bytes([b[0], b[1], b[2], b[3]])),
            Scalar::F64 => f64::from_le_bytes([b[0], b[1], b[2], b[3], b[4], b[5], b[6], b[7]]),
        }
    }
}

#[derive(Debug)]
enum Property {
    Scalar {
        name: String,
        ty: Scalar,
    },
    List {
        name: String,
        count: Scalar,
        item: Scalar,
    },
}

#[derive(Debug)]
struct Element {
    name: String,
    count: usize,
    properties: Vec<Property>,
}

/// Triangles and positions as stored in the file, before normals are computed.
#[derive(Debug, Clone, PartialEq)]
pub struct PlyMesh {
    pub positions: Vec<Vec3>,
    pub indices: Vec<u32>,
}

struct Cursor<'a> {
    data: &'a [u8],
    at: usize,
}

impl<'a> Cursor<'a> {
    fn take(&mut self, n: usize, what: &'static str) -> Result<&'a [u8], PlyError> {
        let end = self.at.checked_add(n).filter(|&e| e <= self.data.len());
        let end = end.ok_or(PlyError::Truncated(what))?;
        let s = &self.data[self.at..end];
        self.at = end;
        Ok(s)
    }

    fn scalar(&mut self, ty: Scalar, what: &'static str) -> Result<f64, PlyError> {
        Ok(ty.read(self.take(ty.size(), what)?))
    }
}

pub fn parse_ply(bytes: &[u8]) -> Result<PlyMesh, PlyError> {
    let (elements, body) = parse_header(bytes)?;
    let mut cur = Cursor { data: body, at: 0 };
    let mut positions = Vec::new();
    let mut indices = Vec::new();
    let mut saw_faces = false;
    for el in &elements {
        match el.name.as_str() {
            "vertex" => positions = read_vertices(&mut cur, el)?,
            "face" => {
                saw_faces = true;
                indices = read_faces(&mut cur, el, positions.len())?;
            }
            _ => skip_element(&mut cur, el)?,
        }
    }
    if positions.is_empty() {
        return Err(PlyError::NoPositions);
    }
    if !saw_faces {
        return Err(PlyError::NoFaces);
    }
    Ok(PlyMesh { positions, indices })
}

fn parse_header(bytes: &[u8]) -> Result<(Vec<Element>, &[u8]), PlyError> {
    const END: &[u8] = b"end_header";
    if !bytes.starts_with(b"ply") {
        return Err(PlyError::NotPly);
    }
    let end = bytes
        .windows(END.len())
        .position(|w| w == END)
        .ok_or(PlyError::NoEndHeader)?;
    let mut body_start = end + END.len();
    if bytes.get(body_start) == Some(&b'\r') {
        body_start += 1;
    }
    if bytes.get(body_start) == Some(&b'\n') {
        body_start += 1;
    }
    let text = String::from_utf8_lossy(&bytes[..end]);
    let mut elements: Vec<Element> = Vec::new();
    for (i, line) in text.lines().enumerate() {
        let line_no = i + 1;
        let bad = |message: String| PlyError::Header {
            line: line_no,
            message,
        };
        let words: Vec<&str> = line.split_whitespace().collect();
        match words.as_slice() {
            ["ply"] | [] => {}
            ["comment", ..] | ["obj_info", ..] => {}
            ["format", fmt, _version] => {
                if *fmt != "binary_little_endian" {
                    return Err(PlyError::Format((*fmt).to_string()));
                }
            }
            ["element", name, count] => {
                let count = count
                    .parse()
                    .map_err(|_| bad(format!("bad element count {count:?}")))?;
                elements.push(Element {
                    name: (*name).to_string(),
                    count,
                    properties: vec![],
                });
            }
            ["property", "list", count, item, name] => {
                let count =
                    Scalar::parse(count).ok_or_else(|| bad(format!("unknown type {count}")))?;
                let item =
                    Scalar::parse(item).ok_or_else(|| bad(format!("unknown type {item}")))?;
                let el = elements
                    .last_mut()
                    .ok_or_else(|| bad("property before element".into()))?;
                el.properties.push(Property::List {
                    name: (*name).to_string(),
                    count,
                    item,
                });
            }
            ["property", ty, name] => {
                let ty = Scalar::parse(ty).ok_or_else(|| bad(format!("unknown type {ty}")))?;
                let el = elements
                    .last_mut()
                    .ok_or_else(|| bad("property before element".into()))?;
                el.properties.push(Property::Scalar {
                    name: (*name).to_string(),
                    ty,
                });
            }
            _ => return Err(bad(format!("cannot read {line:?}"))),
        }
    }
    Ok((elements, &bytes[body_start..]))
}

fn read_vertices(cur: &mut Cursor, el: &Element) -> Result<Vec<Vec3>, PlyError> {
    let slot = |axis: &str| {
        el.properties
            .iter()
            .position(|p| matches!(p, Property::Scalar { name, .. } if name == axis))
    };
    let (Some(xi), Some(yi), Some(zi)) = (slot("x"), slot("y"), slot("z")) else {
        return Err(PlyError::NoPositions);
    };
    let mut out = Vec::with_capacity(el.count);
    let mut values = vec![0.0f64; el.properties.len()];
    for v in 0..el.count {
        for (k, p) in el.properties.iter().enumerate() {
            values[k] = match p {
                Property::Scalar { ty, .. } => cur.scalar(*ty, "vertices")?,
                Property::List { count, item, .. } => {
                    let n = cur.scalar(*count, "vertices")? as usize;
                    cur.take(n * item.size(), "vertices")?;
                    0.0
                }
            };
        }
        let p = Vec3::new(values[xi] as f32, values[yi] as f32, values[zi] as f32);
        if !p.is_finite() {
            return Err(PlyError::NonFinite(v));
        }
        out.push(p);
    }
    Ok(out)
}

fn read_faces(cur: &mut Cursor, el: &Element, vertex_count: usize) -> Result<Vec<u32>, PlyError> {
    let is_indices = |name: &str| name == "vertex_indices" || name == "vertex_index";
    if !el
        .properties
        .iter()
        .any(|p| matches!(p, Property::List { name, .. } if is_indices(name)))
    {
        return Err(PlyError::NoFaces);
    }
    let mut out = Vec::with_capacity(el.count * 3);
    let mut corners = Vec::new();
    for face in 0..el.count {
        for p in &el.properties {
            match p {
                Property::Scalar { ty, .. } => {
                    cur.take(ty.size(), "faces")?;
                }
                Property::List { name, count, item } => {
                    let n = cur.scalar(*count, "faces")? as usize;
                    if !is_indices(name) {
                        cur.take(n * item.size(), "faces")?;
                        continue;
                    }
                    if n < 3 {
                        return Err(PlyError::DegenerateFace { face, count: n });
                    }
                    corners.clear();
                    for _ in 0..n {
                        let index = cur.scalar(*item, "faces")? as i64;
                        if index < 0 || index as usize >= vertex_count {
                            return Err(PlyError::IndexOutOfRange {
                                face,
                                index,
                                count: vertex_count,
                            });
                        }
                        corners.push(index as u32);
                    }
                    for k in 1..n - 1 {
                        out.extend_from_slice(&[corners[0], corners[k], corners[k + 1]]);
                    }
                }
            }
        }
    }
    Ok(out)
}

fn skip_element(cur: &mut Cursor, el: &Element) -> Result<(), PlyError> {
    for _ in 0..el.count {
        for p in &el.properties {
            match p {
                Property::Scalar { ty, .. } => {
                    cur.take(ty.size(), "an extra element")?;
                }
                Property::List { count, item, .. } => {
                    let n = cur.scalar(*count, "an extra element")? as usize;
                    cur.take(n * item.size(), "an extra element")?;
                }
            }
        }
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    fn quad_ply(face_index: i32) -> Vec<u8> {
        let mut b = b"ply\nformat binary_little_endian 1.0\ncomment test\nelement vertex 4\n\
property float x\nproperty float y\nproperty float z\nproperty uchar red\n\
element face 1\nproperty list uchar int vertex_indices\nend_header\n"
            .to_vec();
        for (x, y) in [(0.0f32, 0.0f32), (1.0, 0.0), (1.0, 1.0), (0.0, 1.0)] {
            for c in [x, y, 0.0] {
                b.extend_from_slice(&c.to_le_bytes());
            }
            b.push(255);
        }
        b.push(4);
        for i in [0, 1, 2, face_index] {
            b.extend_from_slice(&i.to_le_bytes());
        }
        b
    }

    #[test]
    fn quad_becomes_two_triangles_and_extra_properties_are_skipped() {
        let m = parse_ply(&quad_ply(3)).unwrap();
        assert_eq!(m.positions.len(), 4);
        assert_eq!(m.positions[2], Vec3::new(1.0, 1.0, 0.0));
        assert_eq!(m.indices, vec![0, 1, 2, 0, 2, 3]);
    }

    #[test]
    fn bad_files_say_what_is_wrong() {
        assert_eq!(parse_ply(b"solid stl"), Err(PlyError::NotPly));
        assert_eq!(
            parse_ply(&quad_ply(9)),
            Err(PlyError::IndexOutOfRange {
                face: 0,
                index: 9,
                count: 4
            })
        );
        let mut short = quad_ply(3);
        short.truncate(short.len() - 3);
        assert_eq!(parse_ply(&short), Err(PlyError::Truncated("faces")));
        let ascii = b"ply\nformat ascii 1.0\nelement vertex 0\nend_header\n";
        assert_eq!(parse_ply(ascii), Err(PlyError::Format("ascii".into())));
    }

    #[test]
    fn shipped_bunny_matches_its_credit_line() {
        let m = parse_ply(include_bytes!("../../assets/meshes/bunny.ply")).unwrap();
        assert_eq!(m.positions.len(), 1839);
        assert_eq!(m.indices.len(), 3674 * 3);
    }
}
