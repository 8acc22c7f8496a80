//! glTF 2.0 (`.gltf` with its buffers and images, or `.glb`) into Fovea's scene parts: the
//! default scene's node hierarchy flattened into world-space triangles, its materials
//! (`material.rs`), punctual lights and first perspective camera. Buffers and images are read
//! through the scene folder only (no URIs, nothing outside it), with the sizes in `limits`.

mod buffers;
mod material;
mod primitive;
mod texture;

use std::path::Path;

use glam::{Mat4, Vec3};

use super::folder::Folder;
use super::limits::{read_limited, MAX_TRIANGLES, MAX_VERTICES};
use super::{Camera, LightSpec, MaterialSpec, RawMesh};
use buffers::{load_buffers, read_uri};
use primitive::read_primitive;
use texture::UvMap;

/// Required extensions Fovea reads (the crate's own list lacks diffuse transmission).
const SUPPORTED: &[&str] = &[
    "KHR_lights_punctual",
    "KHR_materials_emissive_strength",
    "KHR_materials_ior",
    "KHR_materials_transmission",
    "KHR_materials_volume",
    "KHR_materials_diffuse_transmission",
    "KHR_texture_transform",
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
    /// Per-vertex linear RGBA multiplying the material's base colour (COLOR_0), if present.
    pub tint: Option<Vec<[f32; 4]>>,
    /// Texture coordinates, transformed, if the material has maps: xy for the base colour
    /// map, zw for the normal and occlusion maps.
    pub uv: Option<Vec<[f32; 4]>>,
    /// Tangents (xyz, w: bitangent sign), world space, where the material has a normal map.
    pub tangents: Option<Vec<[f32; 4]>>,
    /// Index into `Imported::materials`.
    pub material: usize,
}

#[derive(Debug, Clone, Default)]
pub struct Imported {
    pub parts: Vec<Part>,
    pub materials: Vec<(String, MaterialSpec)>,
    /// Base colour texture of each material (index into `textures`).
    pub material_textures: Vec<Option<usize>>,
    /// Decoded base colour textures (sRGB RGBA8).
    pub textures: Vec<crate::scene::TextureImage>,
    /// Normal map of each material (index into `linear_maps`) with its scale.
    pub material_normal_maps: Vec<Option<(usize, f32)>>,
    /// Occlusion map of each material (index into `linear_maps`) with its strength.
    pub material_occlusion_maps: Vec<Option<(usize, f32)>>,
    /// Decoded linear maps: tangent-space normals, occlusion (R).
    pub linear_maps: Vec<crate::scene::TextureImage>,
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
    import_guarded(&bytes, &base, Some(folder))
}

/// [`import_bytes`] with the reader's panics turned into errors: the gltf crate slices buffers
/// with checked `get`s, but a malformed accessor can still reach an arithmetic overflow inside
/// it, and a panic there must not take the server down.
pub fn import_guarded(
    bytes: &[u8],
    base: &Path,
    folder: Option<&Folder>,
) -> Result<Imported, GltfError> {
    std::panic::catch_unwind(|| import_bytes(bytes, base, folder)).unwrap_or_else(|_| {
        Err(GltfError::Invalid(
            "the file's accessors are inconsistent (the reader gave up)".into(),
        ))
    })
}

/// Imports a glTF held in memory; its URIs resolve in `folder` (`None`: built-in, embedded
/// data only).
pub fn import_bytes(
    bytes: &[u8],
    base: &Path,
    folder: Option<&Folder>,
) -> Result<Imported, GltfError> {
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
    // Texture indices already added to `imported.textures` / `linear_maps`, in order.
    let mut used: Vec<usize> = Vec::new();
    let mut used_normals: Vec<usize> = Vec::new();
    for (i, m) in doc.materials().enumerate() {
        let mr = m.pbr_metallic_roughness();
        let g = material::GltfMaterial {
            metallic_roughness_mean: material::mean(
                mr.metallic_roughness_texture()
                    .and_then(|t| textures.get(t.texture().index())),
                false,
            ),
            emissive_mean: material::mean(
                m.emissive_texture()
                    .and_then(|t| textures.get(t.texture().index())),
                true,
            ),
            material: m.clone(),
        };
        let occlusion = m.occlusion_texture().and_then(|t| {
            let index = t.texture().index();
            let image = textures.get(index)?;
            let layer = add_once(&mut used_normals, &mut imported.linear_maps, index, image);
            Some((layer, t.strength()))
        });
        imported.material_occlusion_maps.push(occlusion);
        let normal = m.normal_texture().and_then(|t| {
            let index = t.texture().index();
            let image = textures.get(index)?;
            let layer = add_once(&mut used_normals, &mut imported.linear_maps, index, image);
            Some((layer, t.scale()))
        });
        imported.material_normal_maps.push(normal);
        let name = m
            .name()
            .map_or_else(|| format!("material-{i}"), str::to_string);
        imported.materials.push((name, material::spec_of(&g)));
        let base = mr.base_color_texture().map(|t| t.texture().index());
        let layer = base.and_then(|index| {
            let image = textures.get(index)?;
            Some(add_once(&mut used, &mut imported.textures, index, image))
        });
        imported.material_textures.push(layer);
    }
    // Primitives without a material get a white rough dielectric (glTF's default material is a
    // rough metal, which shows black without an environment to reflect).
    let default_material = imported.materials.len();
    imported.material_textures.push(None);
    imported.material_normal_maps.push(None);
    imported.material_occlusion_maps.push(None);
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
                // Two sets of texture coordinates per primitive: the base colour map's, and
                // the normal map's (the occlusion map's when there is no normal map), each
                // with its own set and KHR_texture_transform.
                let pm = prim.material();
                const TRANSFORM: &str = "KHR_texture_transform";
                let mut notes = Vec::new();
                let base = pm
                    .pbr_metallic_roughness()
                    .base_color_texture()
                    .filter(|t| textures.get(t.texture().index()).is_some())
                    .map(|t| UvMap::of(t.tex_coord(), t.extension_value(TRANSFORM), &mut notes));
                let normal = pm
                    .normal_texture()
                    .filter(|t| textures.get(t.texture().index()).is_some())
                    .map(|t| UvMap::of(t.tex_coord(), t.extension_value(TRANSFORM), &mut notes));
                let occlusion = pm
                    .occlusion_texture()
                    .filter(|t| textures.get(t.texture().index()).is_some())
                    .map(|t| UvMap::of(t.tex_coord(), t.extension_value(TRANSFORM), &mut notes));
                if let (Some(n), Some(o)) = (normal, occlusion) {
                    if n != o {
                        notes.push(format!(
                            "mesh {:?}: the occlusion map is read with the normal map's texture coordinates (TEXCOORD_{} and its transform)",
                            mesh.name().unwrap_or(""),
                            n.set
                        ));
                    }
                }
                imported.notes.extend(notes);
                let detail = normal.or(occlusion);
                match read_primitive(
                    &prim,
                    &buffers,
                    world,
                    [base, detail],
                    normal.is_some(),
                    material,
                ) {
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

/// `image`'s position in `out`, added the first time texture `index` is seen.
fn add_once(
    seen: &mut Vec<usize>,
    out: &mut Vec<crate::scene::TextureImage>,
    index: usize,
    image: &crate::scene::TextureImage,
) -> usize {
    match seen.iter().position(|&u| u == index) {
        Some(k) => k,
        None => {
            seen.push(index);
            out.push(image.clone());
            out.len() - 1
        }
    }
}

/// The file's textures that some material uses, decoded once; failures become notes.
struct Textures {
    decoded: Vec<Option<crate::scene::TextureImage>>,
}

impl Textures {
    fn new(
        doc: &gltf::Document,
        buffers: &[Vec<u8>],
        base: &Path,
        folder: Option<&Folder>,
        notes: &mut Vec<String>,
    ) -> Textures {
        let used = |t: &gltf::Texture| {
            doc.materials().any(|m| {
                let pbr = m.pbr_metallic_roughness();
                let is = |i: Option<gltf::texture::Info>| {
                    i.is_some_and(|i| i.texture().index() == t.index())
                };
                is(pbr.base_color_texture())
                    || is(m.emissive_texture())
                    || is(pbr.metallic_roughness_texture())
                    || m.normal_texture()
                        .is_some_and(|n| n.texture().index() == t.index())
                    || m.occlusion_texture()
                        .is_some_and(|o| o.texture().index() == t.index())
            })
        };
        let decoded = doc
            .textures()
            .map(|t| {
                if !used(&t) {
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
                match bytes.and_then(|b| texture::decode(&b)) {
                    Ok(mut img) => {
                        img.sampling = crate::scene::sampling::Sampling::of_gltf(&t.sampler());
                        Some(img)
                    }
                    Err(e) => {
                        notes.push(format!(
                            "texture {}: {e}; its factor is used alone",
                            t.index()
                        ));
                        None
                    }
                }
            })
            .collect();
        Textures { decoded }
    }

    fn get(&self, index: usize) -> Option<&crate::scene::TextureImage> {
        self.decoded.get(index)?.as_ref()
    }
}
