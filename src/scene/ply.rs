//! PLY reader (ASCII and binary, either byte order): enough of the format for scanned meshes
//! (any vertex properties, polygon faces triangulated as fans), with errors that name what is
//! wrong. Counts are checked against `limits` and against the bytes left before anything is
//! allocated; faces with repeated corners or zero area are dropped and counted.

use glam::Vec3;

use super::limits::{MAX_POLYGON_CORNERS, MAX_TRIANGLES, MAX_VERTICES};

#[derive(Debug, thiserror::Error, PartialEq)]
pub enum PlyError {
    #[error("not a PLY file (it must start with the line `ply`)")]
    NotPly,
    #[error("PLY header is not terminated by `end_header`")]
    NoEndHeader,
    #[error("PLY format {0:?} is not supported (ascii, binary_little_endian, binary_big_endian)")]
    Format(String),
    #[error("PLY header line {line}: {message}")]
    Header { line: usize, message: String },
    #[error("PLY has no vertex element with x, y and z properties")]
    NoPositions,
    #[error("PLY has no face element with a vertex_indices list")]
    NoFaces,
    #[error("PLY data ends early while reading {0}")]
    Truncated(&'static str),
    #[error("PLY value {token:?} in {what} is not a number")]
    BadNumber { what: &'static str, token: String },
    #[error("PLY declares {count} {what}; the limit is {limit}")]
    TooMany {
        what: &'static str,
        count: usize,
        limit: usize,
    },
    #[error("face {face} refers to vertex {index}, but there are only {count} vertices")]
    IndexOutOfRange {
        face: usize,
        index: i64,
        count: usize,
    },
    #[error("face {face} has {count} corners; a face needs 3 to {MAX_POLYGON_CORNERS}")]
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

    /// Decodes `b` (exactly `size()` bytes) stored little- or big-endian.
    fn read(self, b: &[u8], big: bool) -> f64 {
        let mut a = [0u8; 8];
        a[..b.len()].copy_from_slice(b);
        if big {
            a[..b.len()].reverse();
        }
        match self {
            Scalar::I8 => f64::from(a[0] as i8),
            Scalar::U8 => f64::from(a[0]),
            Scalar::I16 => f64::from(i16::from_le_bytes([a[0], a[1]])),
            Scalar::U16 => f64::from(u16::from_le_bytes([a[0], a[1]])),
            Scalar::I32 => f64::from(i32::from_le_bytes([a[0], a[1], a[2], a[3]])),
            Scalar::U32 => f64::from(u32::from_le_bytes([a[0], a[1], a[2], a[3]])),
            Scalar::F32 => f64::from(f32::from_le_bytes([a[0], a[1], a[2], a[3]])),
            Scalar::F64 => f64::from_le_bytes(a),
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

#[derive(Debug, Clone, Copy, PartialEq)]
enum Encoding {
    Ascii,
    Binary { big: bool },
}

/// Triangles and positions as stored in the file, before normals are computed.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct RawMesh {
    pub positions: Vec<Vec3>,
    pub indices: Vec<u32>,
    /// Faces dropped because two corners coincide or the triangle has no area.
    pub dropped_degenerate: usize,
}

/// The body after the header: binary values of one byte order, or whitespace-separated text.
struct Values<'a> {
    data: &'a [u8],
    at: usize,
    encoding: Encoding,
}

impl<'a> Values<'a> {
    fn next(&mut self, ty: Scalar, what: &'static str) -> Result<f64, PlyError> {
        match self.encoding {
            Encoding::Binary { big } => {
                let end = self
                    .at
                    .checked_add(ty.size())
                    .filter(|&e| e <= self.data.len());
                let end = end.ok_or(PlyError::Truncated(what))?;
                let v = ty.read(&self.data[self.at..end], big);
                self.at = end;
                Ok(v)
            }
            Encoding::Ascii => {
                let rest = &self.data[self.at..];
                let start = rest
                    .iter()
                    .position(|b| !b.is_ascii_whitespace())
                    .ok_or(PlyError::Truncated(what))?;
                let len = rest[start..]
                    .iter()
                    .position(|b| b.is_ascii_whitespace())
                    .unwrap_or(rest.len() - start);
                let token = &rest[start..start + len];
                self.at += start + len;
                let text = std::str::from_utf8(token).unwrap_or("");
                text.parse::<f64>().map_err(|_| PlyError::BadNumber {
                    what,
                    token: String::from_utf8_lossy(token).into_owned(),
                })
            }
        }
    }

    /// Bytes (binary) or characters (ASCII) left: an upper bound on the values still to come.
    fn left(&self) -> usize {
        self.data.len() - self.at
    }

    /// The fewest bytes one record of `el` takes: a declared count larger than the bytes left
    /// divided by this is a lie, refused before allocating for it.
    fn min_record(&self, el: &Element) -> usize {
        let per = |ty: Scalar| match self.encoding {
            Encoding::Ascii => 2, // one digit and a separator
            Encoding::Binary { .. } => ty.size(),
        };
        el.properties
            .iter()
            .map(|p| match p {
                Property::Scalar { ty, .. } => per(*ty),
                Property::List { count, .. } => per(*count),
            })
            .sum::<usize>()
            .max(1)
    }
}

pub fn parse_ply(bytes: &[u8]) -> Result<RawMesh, PlyError> {
    let (elements, encoding, body) = parse_header(bytes)?;
    let mut values = Values {
        data: body,
        at: 0,
        encoding,
    };
    let mut mesh = RawMesh::default();
    let mut saw_faces = false;
    for el in &elements {
        let fits = el.count.saturating_mul(values.min_record(el)) <= values.left();
        let (what, limit) = match el.name.as_str() {
            "vertex" => ("vertices", MAX_VERTICES),
            "face" => ("faces", MAX_TRIANGLES),
            _ => ("records", usize::MAX),
        };
        if el.count > limit {
            return Err(PlyError::TooMany {
                what,
                count: el.count,
                limit,
            });
        }
        if !fits {
            return Err(PlyError::Truncated(what));
        }
        match el.name.as_str() {
            "vertex" => mesh.positions = read_vertices(&mut values, el)?,
            "face" => {
                saw_faces = true;
                read_faces(&mut values, el, &mut mesh)?;
            }
            _ => skip_element(&mut values, el)?,
        }
    }
    if mesh.positions.is_empty() {
        return Err(PlyError::NoPositions);
    }
    if !saw_faces {
        return Err(PlyError::NoFaces);
    }
    Ok(mesh)
}

fn parse_header(bytes: &[u8]) -> Result<(Vec<Element>, Encoding, &[u8]), PlyError> {
    const END: &[u8] = b"end_header";
    if !bytes.starts_with(b"ply") {
        return Err(PlyError::NotPly);
    }
    // The header is text and short; a missing end within 64 KB means this is not one.
    let window = &bytes[..bytes.len().min(1 << 16)];
    let end = window
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
    let mut encoding = None;
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
                encoding = Some(match *fmt {
                    "ascii" => Encoding::Ascii,
                    "binary_little_endian" => Encoding::Binary { big: false },
                    "binary_big_endian" => Encoding::Binary { big: true },
                    other => return Err(PlyError::Format(other.to_string())),
                });
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
    let encoding = encoding.ok_or_else(|| PlyError::Format("(no format line)".into()))?;
    Ok((elements, encoding, &bytes[body_start..]))
}

/// A list's length, refused when negative, absurd or longer than the data left.
fn list_len(values: &mut Values, count: Scalar, what: &'static str) -> Result<usize, PlyError> {
    let n = values.next(count, what)?;
    if !(n >= 0.0 && n <= values.left() as f64) {
        return Err(PlyError::Truncated(what));
    }
    Ok(n as usize)
}

fn read_vertices(values: &mut Values, el: &Element) -> Result<Vec<Vec3>, PlyError> {
    let slot = |axis: &str| {
        el.properties
            .iter()
            .position(|p| matches!(p, Property::Scalar { name, .. } if name == axis))
    };
    let (Some(xi), Some(yi), Some(zi)) = (slot("x"), slot("y"), slot("z")) else {
        return Err(PlyError::NoPositions);
    };
    let mut out = Vec::with_capacity(el.count);
    let mut row = vec![0.0f64; el.properties.len()];
    for v in 0..el.count {
        for (k, p) in el.properties.iter().enumerate() {
            row[k] = match p {
                Property::Scalar { ty, .. } => values.next(*ty, "vertices")?,
                Property::List { count, item, .. } => {
                    for _ in 0..list_len(values, *count, "vertices")? {
                        values.next(*item, "vertices")?;
                    }
                    0.0
                }
            };
        }
        let p = Vec3::new(row[xi] as f32, row[yi] as f32, row[zi] as f32);
        if !p.is_finite() {
            return Err(PlyError::NonFinite(v));
        }
        out.push(p);
    }
    Ok(out)
}

fn read_faces(values: &mut Values, el: &Element, mesh: &mut RawMesh) -> Result<(), PlyError> {
    let is_indices = |name: &str| name == "vertex_indices" || name == "vertex_index";
    if !el
        .properties
        .iter()
        .any(|p| matches!(p, Property::List { name, .. } if is_indices(name)))
    {
        return Err(PlyError::NoFaces);
    }
    let vertex_count = mesh.positions.len();
    mesh.indices.reserve(el.count * 3);
    let mut corners = Vec::new();
    for face in 0..el.count {
        for p in &el.properties {
            match p {
                Property::Scalar { ty, .. } => {
                    values.next(*ty, "faces")?;
                }
                Property::List { name, count, item } => {
                    let n = list_len(values, *count, "faces")?;
                    if !is_indices(name) {
                        for _ in 0..n {
                            values.next(*item, "faces")?;
                        }
                        continue;
                    }
                    if !(3..=MAX_POLYGON_CORNERS).contains(&n) {
                        return Err(PlyError::DegenerateFace { face, count: n });
                    }
                    corners.clear();
                    for _ in 0..n {
                        let index = values.next(*item, "faces")? as i64;
                        if index < 0 || index as usize >= vertex_count {
                            return Err(PlyError::IndexOutOfRange {
                                face,
                                index,
                                count: vertex_count,
                            });
                        }
                        corners.push(index as u32);
                    }
                    let before = mesh.indices.len();
                    super::mesh::push_fan(&corners, &mesh.positions, &mut mesh.indices);
                    if mesh.indices.len() == before {
                        mesh.dropped_degenerate += 1;
                    }
                    if mesh.indices.len() / 3 > MAX_TRIANGLES {
                        return Err(PlyError::TooMany {
                            what: "triangles",
                            count: mesh.indices.len() / 3,
                            limit: MAX_TRIANGLES,
                        });
                    }
                }
            }
        }
    }
    Ok(())
}

fn skip_element(values: &mut Values, el: &Element) -> Result<(), PlyError> {
    for _ in 0..el.count {
        for p in &el.properties {
            match p {
                Property::Scalar { ty, .. } => {
                    values.next(*ty, "an extra element")?;
                }
                Property::List { count, item, .. } => {
                    for _ in 0..list_len(values, *count, "an extra element")? {
                        values.next(*item, "an extra element")?;
                    }
                }
            }
        }
    }
    Ok(())
}
