//! glTF 2.0 (`.gltf` with its buffers and images, or `.glb`) into Fovea's scene parts: the
//! default scene's node hierarchy flattened into world-space triangles, its materials
//! (`material.rs`), punctual lights and first perspective camera. Buffers and images are read
//! through the scene folder only (no URIs, nothing outside it), with the sizes in `limits`.

mod material;
mod texture;

use std::path::Path;

use glam::{Mat3, Mat4, Vec2, Vec3};

use super::folder::Folder;
use super::limits::{read_limited, MAX_FILE_BYTES, MAX_TRIANGLES, MAX_VERTICES};
use super::mesh::push_fan;
use super::{Camera, LightSpec, MaterialSpec, RawMesh};

/// Required extensions Fovea reads (the crate's own list lacks diffuse transmission).
const SUPPORTED: &[&str] = &[
    "KHR_lights_punctual",
    "KHR_materials_emissive_strength",
    "KHR_materials_ior",
    "KHR_materials_transmission",
    "KHR_materials_volume",
    "KHR_materials_diffuse_transmission",
];

#[derive(Debug, thiserror::Error)]
pub enum GltfError {
    #[error("not a valid glTF 2.0 file: {0}")]
    Invalid(String),
    #[error("the file requires {name}, which Fovea does not read; {hint}")]
    Unsupported { name: String, hint: &'static str },
    #[error("buffer {index}: {message}")]
    Buffer { index: usize, message: String },
    #[error("mesh {mesh:?} primitive {primitive}: {message}")]
    Primitive {
        mesh: String,
        primitive: usize,
        message: String,
    },
    #[error("the scene holds more than {limit} {what}")]
    TooMany { what: &'static str, limit: usize },
    #[error("the file has no triangles in its default scene")]
    NoGeometry,
}

/// Triangles from one glTF primitive, in world space.
#[derive(Debug, Clone)]
pub struct Part {
    pub mesh: RawMesh,
    /// The file's normals (world space), if it has them; otherwise they are computed.
    pub normals: Option<Vec<Vec3>>,
    /// Per-vertex linear RGBA multiplying the material's base colour (COLOR_0 × base colour
    /// texture), if either is present.
    pub tint: Option<Vec<[f32; 4]>>,
    /// Index into `Imported::materials`.
    pub material: usize,
}

#[derive(Debug, Clone, Default)]
pub struct Imported {
    pub parts: Vec<Part>,
    pub materials: Vec<(String, MaterialSpec)>,
    /// Lights in the file's photometric units (lux, candela); `scene::model` scales them.
    pub lights: Vec<LightSpec>,
    pub camera: Option<Camera>,
    /// What was read but left out (optional extensions, skipped primitives, dropped triangles).
    pub notes: Vec<String>,
}

fn hint(name: &str) -> &'static str {
    match name {
        "KHR_draco_mesh_compression" => "write it back uncompressed, e.g. `gltf-pipeline -i in.glb -o out.glb` (gltf-pipeline decodes Draco)",
        "EXT_meshopt_compression" => "write it back without meshopt compression, e.g. with gltf-transform (it decodes meshopt when reading)",
        "KHR_texture_basisu" | "EXT_texture_webp" | "EXT_texture_avif" => "convert its textures to PNG or JPEG, e.g. `gltf-transform png in.glb out.glb`",
        "KHR_mesh_quantization" => "dequantize it, e.g. `gltf-transform dequantize in.glb out.glb`",
        _ => "re-export the file without it",
    }
}

/// Imports `path`, which lies in `folder` (its buffers and images must too).
pub fn import(path: &Path, folder: &Folder) -> Result<Imported, GltfError> {
    let bytes = read_limited(path).map_err(|e| GltfError::Invalid(e.to_string()))?;
    let base = path.parent().unwrap_or(folder.root()).to_path_buf();
    // The gltf crate slices buffers with checked `get`s, but a malformed accessor can still
    // reach an arithmetic overflow inside it; a panic there must not take the server down.
    std::panic::catch_unwind(|| import_bytes(&bytes, &base, folder)).unwrap_or_else(|_| {
        Err(GltfError::Invalid(
            "the file's accessors are inconsistent (the reader gave up)".into(),
        ))
    })
}

pub fn import_bytes(bytes: &[u8], base: &Path, folder: &Folder) -> Result<Imported, GltfError> {
    let invalid = |e: gltf::Error| GltfError::Invalid(e.to_string());
    let raw = gltf::Gltf::from_slice_without_validation(bytes).map_err(invalid)?;
    let mut imported = Imported::default();
    for name in raw.extensions_required() {
        if !SUPPORTED.contains(&name) {
            return Err(GltfError::Unsupported {
                name: name.to_string(),
                hint: hint(name),
            });
        }
    }
    for name in raw.extensions_used() {
        if !SUPPORTED.contains(&name) {
            imported
                .notes
                .push(format!("optional extension {name} ignored"));
        }
    }
    let blob = raw.blob.clone();
    let mut root = raw.document.into_json();
    // Validate with the crate (indices in range, required fields) once our own extensions
    // are off its list of unknown required ones.
    root.extensions_required
        .retain(|e| e != "KHR_materials_diffuse_transmission");
    let doc = gltf::Document::from_json(root).map_err(|e| GltfError::Invalid(e.to_string()))?;
    let buffers = load_buffers(&doc, blob, base, folder)?;
    let textures = Textures::new(&doc, &buffers, base, folder, &mut imported.notes);
    for (i, m) in doc.materials().enumerate() {
        let mr = m.pbr_metallic_roughness();
        let g = material::GltfMaterial {
            metallic_roughness_mean: material::mean(
                mr.metallic_roughness_texture()
                    .and_then(|t| textures.get(t.texture().index(), false)),
            ),
            emissive_mean: material::mean(
                m.emissive_texture()
                    .and_then(|t| textures.get(t.texture().index(), true)),
            ),
            material: m.clone(),
        };
        if m.normal_texture().is_some() || m.occlusion_texture().is_some() {
            imported.notes.push(format!(
                "material {i}: normal and occlusion maps are not used"
            ));
        }
        let name = m
            .name()
            .map_or_else(|| format!("material-{i}"), str::to_string);
        imported.materials.push((name, material::spec_of(&g)));
    }
    // Primitives without a material get glTF's default (white, rough, dielectric).
    let default_material = imported.materials.len();
    imported.materials.push((
        "default".into(),
        MaterialSpec::Opaque {
            albedo: [1.0; 3],
            surface: super::material::SurfaceSpec {
                roughness: Some(1.0),
                ..Default::default()
            },
        },
    ));
    let scene = doc
        .default_scene()
        .or_else(|| doc.scenes().next())
        .ok_or(GltfError::NoGeometry)?;
    let mut stack: Vec<(gltf::Node, Mat4, usize)> =
        scene.nodes().map(|n| (n, Mat4::IDENTITY, 0)).collect();
    let (mut vertices, mut triangles) = (0usize, 0usize);
    while let Some((node, parent, depth)) = stack.pop() {
        if depth > 64 {
            return Err(GltfError::Invalid(
                "node hierarchy deeper than 64 (a cycle?)".into(),
            ));
        }
        let world = parent * Mat4::from_cols_array_2d(&node.transform().matrix());
        if !world.is_finite() {
            imported.notes.push(format!(
                "node {}: non-finite transform, skipped",
                node.index()
            ));
            continue;
        }
        if let Some(mesh) = node.mesh() {
            for (pi, prim) in mesh.primitives().enumerate() {
                let material = prim.material().index().unwrap_or(default_material);
                let tex = prim
                    .material()
                    .pbr_metallic_roughness()
                    .base_color_texture()
                    .and_then(|t| {
                        textures
                            .get(t.texture().index(), true)
                            .map(|x| (x, t.tex_coord()))
                    });
                match read_primitive(&prim, &buffers, world, tex, material) {
                    Ok(Some(part)) => {
                        vertices += part.mesh.positions.len();
                        triangles += part.mesh.indices.len() / 3;
                        if part.mesh.dropped_degenerate > 0 {
                            imported.notes.push(format!(
                                "mesh {:?}: {} degenerate triangles dropped",
                                mesh.name().unwrap_or(""),
                                part.mesh.dropped_degenerate
                            ));
                        }
                        imported.parts.push(part);
                    }
                    Ok(None) => imported.notes.push(format!(
                        "mesh {:?} primitive {pi}: {:?} primitives are not drawn",
                        mesh.name().unwrap_or(""),
                        prim.mode()
                    )),
                    Err(message) => {
                        return Err(GltfError::Primitive {
                            mesh: mesh.name().unwrap_or("").to_string(),
                            primitive: pi,
                            message,
                        })
                    }
                }
                if vertices > MAX_VERTICES {
                    return Err(GltfError::TooMany {
                        what: "vertices",
                        limit: MAX_VERTICES,
                    });
                }
                if triangles > MAX_TRIANGLES {
                    return Err(GltfError::TooMany {
                        what: "triangles",
                        limit: MAX_TRIANGLES,
                    });
                }
            }
        }
        if let Some(light) = node.light() {
            imported.lights.push(light_spec(&light, world));
        }
        if let (Some(cam), None) = (node.camera(), &imported.camera) {
            match cam.projection() {
                gltf::camera::Projection::Perspective(p) => {
                    let eye = world.transform_point3(Vec3::ZERO);
                    let forward = world.transform_vector3(-Vec3::Z).normalize_or_zero();
                    let up = world.transform_vector3(Vec3::Y).normalize_or_zero();
                    imported.camera = Some(Camera {
                        eye: eye.into(),
                        target: (eye + forward).into(),
                        up: up.into(),
                        fov_y_deg: p.yfov().to_degrees(),
                        near: p.znear(),
                        far: p.zfar().unwrap_or(0.0),
                    });
                }
                gltf::camera::Projection::Orthographic(_) => imported.notes.push(
                    "orthographic cameras are not supported; the view is framed instead".into(),
                ),
            }
        }
        stack.extend(node.children().map(|c| (c, world, depth + 1)));
    }
    if imported.parts.is_empty() {
        return Err(GltfError::NoGeometry);
    }
    Ok(imported)
}

fn light_spec(light: &gltf::khr_lights_punctual::Light, world: Mat4) -> LightSpec {
    use gltf::khr_lights_punctual::Kind;
    let position = world.transform_point3(Vec3::ZERO).into();
    let direction = world.transform_vector3(-Vec3::Z).normalize_or_zero();
    let (color, intensity, range) = (light.color(), light.intensity(), light.range());
    match light.kind() {
        Kind::Directional => LightSpec::Directional {
            to_light: (-direction).into(),
            color,
            intensity,
        },
        Kind::Point => LightSpec::Point {
            position,
            color,
            intensity,
            range,
        },
        Kind::Spot {
            inner_cone_angle,
            outer_cone_angle,
        } => LightSpec::Spot {
            position,
            direction: direction.into(),
            color,
            intensity,
            range,
            inner_deg: inner_cone_angle.to_degrees(),
            outer_deg: outer_cone_angle.to_degrees(),
        },
    }
}

fn load_buffers(
    doc: &gltf::Document,
    blob: Option<Vec<u8>>,
    base: &Path,
    folder: &Folder,
) -> Result<Vec<Vec<u8>>, GltfError> {
    let mut blob = blob;
    let mut out = Vec::new();
    for b in doc.buffers() {
        let index = b.index();
        let err = |message: String| GltfError::Buffer { index, message };
        if b.length() as u64 > MAX_FILE_BYTES {
            return Err(err(format!(
                "{} bytes is over the {MAX_FILE_BYTES}-byte limit",
                b.length()
            )));
        }
        let data = match b.source() {
            gltf::buffer::Source::Bin => blob
                .take()
                .ok_or_else(|| err("the GLB has no BIN chunk".into()))?,
            gltf::buffer::Source::Uri(uri) => read_uri(uri, base, folder).map_err(err)?,
        };
        if data.len() < b.length() {
            return Err(err(format!(
                "holds {} bytes, the file says {}",
                data.len(),
                b.length()
            )));
        }
        out.push(data);
    }
    Ok(out)
}

/// A buffer or image URI: an embedded base64 `data:` URI, or a file beside the glTF.
fn read_uri(uri: &str, base: &Path, folder: &Folder) -> Result<Vec<u8>, String> {
    use base64::Engine;
    if let Some(rest) = uri.strip_prefix("data:") {
        let (_, payload) = rest
            .split_once(";base64,")
            .ok_or("data URI is not base64")?;
        if payload.len() as u64 > MAX_FILE_BYTES * 4 / 3 {
            return Err("data URI over the size limit".into());
        }
        return base64::engine::general_purpose::STANDARD
            .decode(payload)
            .map_err(|e| format!("data URI: {e}"));
    }
    let decoded = percent_decode(uri);
    let path = folder.resolve(base, &decoded).map_err(|e| e.to_string())?;
    read_limited(&path).map_err(|e| e.to_string())
}

/// URIs in glTF are percent-encoded (`my%20mesh.bin`).
fn percent_decode(s: &str) -> String {
    let b = s.as_bytes();
    let mut out = Vec::with_capacity(b.len());
    let mut i = 0;
    while i < b.len() {
        let hex = |c: u8| (c as char).to_digit(16);
        if b[i] == b'%' && i + 2 < b.len() {
            if let (Some(h), Some(l)) = (hex(b[i + 1]), hex(b[i + 2])) {
                out.push((h * 16 + l) as u8);
                i += 3;
                continue;
            }
        }
        out.push(b[i]);
        i += 1;
    }
    String::from_utf8_lossy(&out).into_owned()
}

/// The file's textures, decoded lazily per (texture, colour space); failures become notes.
struct Textures {
    decoded: Vec<[Option<texture::Texture>; 2]>,
}

impl Textures {
    fn new(
        doc: &gltf::Document,
        buffers: &[Vec<u8>],
        base: &Path,
        folder: &Folder,
        notes: &mut Vec<String>,
    ) -> Textures {
        let used = |t: &gltf::Texture, srgb: bool| {
            doc.materials().any(|m| {
                let pbr = m.pbr_metallic_roughness();
                let is = |i: Option<gltf::texture::Info>| {
                    i.is_some_and(|i| i.texture().index() == t.index())
                };
                if srgb {
                    is(pbr.base_color_texture()) || is(m.emissive_texture())
                } else {
                    is(pbr.metallic_roughness_texture())
                }
            })
        };
        let decoded = doc
            .textures()
            .map(|t| {
                [true, false].map(|srgb| {
                    if !used(&t, srgb) {
                        return None;
                    }
                    let bytes = match t.source().source() {
                        gltf::image::Source::View { view, .. } => buffers
                            .get(view.buffer().index())
                            .and_then(|b| {
                                b.get(view.offset()..view.offset().checked_add(view.length())?)
                            })
                            .map(<[u8]>::to_vec)
                            .ok_or_else(|| "image view out of range".to_string()),
                        gltf::image::Source::Uri { uri, .. } => read_uri(uri, base, folder),
                    };
                    match bytes.and_then(|b| texture::decode(&b, srgb)) {
                        Ok(t) => Some(t),
                        Err(e) => {
                            notes.push(format!(
                                "texture {}: {e}; its factor is used alone",
                                t.index()
                            ));
                            None
                        }
                    }
                })
            })
            .collect();
        Textures { decoded }
    }

    fn get(&self, index: usize, srgb: bool) -> Option<&texture::Texture> {
        self.decoded.get(index)?[usize::from(!srgb)].as_ref()
    }
}

fn read_primitive(
    prim: &gltf::Primitive,
    buffers: &[Vec<u8>],
    world: Mat4,
    base_colour: Option<(&texture::Texture, u32)>,
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
            if a.dimensions() != dims || (!float && !matches!(sem, gltf::Semantic::Colors(_))) {
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
    let uvs: Option<Vec<Vec2>> = base_colour.and_then(|(_, set)| {
        let sem = gltf::Semantic::TexCoords(set);
        check(sem, gltf::accessor::Dimensions::Vec2)
            .ok()
            .flatten()?;
        let uv: Vec<Vec2> = reader
            .read_tex_coords(set)?
            .into_f32()
            .map(Vec2::from)
            .collect();
        (uv.len() == count).then_some(uv)
    });
    let tint = match (colours, uvs, base_colour) {
        (None, None, _) => None,
        (c, uv, tex) => Some(
            (0..count)
                .map(|i| {
                    let a = c.as_ref().map_or([1.0; 4], |c| c[i]);
                    let b = match (&uv, tex) {
                        (Some(uv), Some((t, _))) => t.sample(uv[i]),
                        _ => [1.0; 4],
                    };
                    std::array::from_fn(|k| (a[k] * b[k]).clamp(0.0, 1.0))
                })
                .collect(),
        ),
    };
    Ok(Some(Part {
        mesh,
        normals,
        tint,
        material,
    }))
}
