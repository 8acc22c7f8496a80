//! Scenes: a JSON description (camera, key light and more lights, materials, objects placing
//! meshes and glTF files), loaded and validated into one combined mesh with a material per
//! vertex. The built-in scenes are embedded in the binary so `fovea` runs from any directory;
//! scenes of one's own are read from folders (`Catalog`). Format: `docs/scenes.md`.

mod build;
mod camera;
mod catalog;
mod file;
mod folder;
mod gltf;
pub mod limits;
pub mod material;
mod mesh;
mod model;
mod obj;
pub mod plan;
mod ply;
pub mod sampling;

pub use build::MAX_MATERIALS;
pub use camera::Camera;
pub use catalog::{Catalog, CatalogEntry};
pub use file::{Light, LightSpec, ObjectSpec, RadiosityMode, RadiositySpec, SceneFile, MAX_LIGHTS};
pub use folder::{Folder, FolderError};
pub use material::{Material, MaterialSpec};
pub use mesh::Mesh;
pub use obj::{parse_obj, ObjError};
pub use plan::Plan;
pub use ply::{parse_ply, PlyError, RawMesh};

use glam::Vec3;

/// The scene a session gets when `hello` names none.
pub const DEFAULT_SCENE: &str = "gallery";

/// Built-in scenes that are glTF models: (name, file name, the file).
const BUILTIN_MODELS: &[(&str, &str, &[u8])] = &[(
    "gallery",
    "gallery.glb",
    include_bytes!("../../assets/scenes/gallery.glb"),
)];

/// Built-in scenes: (name, scene JSON).
const BUILTIN_SCENES: &[(&str, &str)] = &[
    (
        "bunny-marble",
        include_str!("../../assets/scenes/bunny-marble.json"),
    ),
    (
        "bunny-skin",
        include_str!("../../assets/scenes/bunny-skin.json"),
    ),
    (
        "materials",
        include_str!("../../assets/scenes/materials.json"),
    ),
    ("opaque", include_str!("../../assets/scenes/opaque.json")),
    ("bunny", include_str!("../../assets/scenes/bunny.json")),
    ("cornell", include_str!("../../assets/scenes/cornell.json")),
];

/// Meshes scene files may refer to by file name.
const BUILTIN_MESHES: &[(&str, &[u8])] =
    &[("bunny.ply", include_bytes!("../../assets/meshes/bunny.ply"))];

#[derive(Debug, thiserror::Error)]
pub enum SceneError {
    #[error("unknown scene {0:?} (available: {available})", available = builtin_names().join(", "))]
    Unknown(String),
    #[error("scene {scene:?} refers to mesh {mesh:?}, which is not built in (available: bunny.ply, plane, quad)")]
    UnknownMesh { scene: String, mesh: String },
    #[error("scene file {scene:?} is invalid: {source}")]
    Json {
        scene: String,
        source: serde_json::Error,
    },
    #[error("scene {scene:?}: mesh {mesh:?}: {message}")]
    MeshFile {
        scene: String,
        mesh: String,
        message: String,
    },
    #[error("{path}: {message}")]
    File { path: String, message: String },
    #[error("scene {scene:?}: {message}")]
    Invalid { scene: String, message: String },
}

/// A texture: RGBA8 row by row (sRGB-encoded for base colour maps), and how it is sampled.
#[derive(Debug, Clone, PartialEq)]
pub struct TextureImage {
    pub width: u32,
    pub height: u32,
    pub rgba: Vec<u8>,
    pub sampling: sampling::Sampling,
}

/// Where an object's vertices sit in the combined mesh, and for a quad its lattice.
#[derive(Debug, Clone, PartialEq)]
pub struct Placed {
    pub material: u32,
    pub first_vertex: u32,
    pub vertex_count: u32,
    pub first_index: u32,
    pub index_count: u32,
    /// For `quad` objects: corners, patches per side and subdivision depth (the mesh is the
    /// finest lattice, so per-vertex radiosity shows every element).
    pub quad: Option<([Vec3; 4], [u32; 2], u32)>,
}

/// A loaded, validated scene.
#[derive(Debug, Clone)]
pub struct Scene {
    pub file: SceneFile,
    /// Every object's triangles in world space.
    pub mesh: Mesh,
    /// Materials by id (the order of `file.materials`), with their names.
    pub materials: Vec<(String, Material)>,
    /// One per object (a glTF object: one per primitive), in file order.
    pub placed: Vec<Placed>,
    /// What loading left out or repaired (ignored extensions, dropped triangles, …).
    pub notes: Vec<String>,
    /// Base colour textures, and for each material the one it uses (the mesh's `uv` reads it).
    pub textures: Vec<TextureImage>,
    pub material_textures: Vec<Option<u32>>,
    /// Linear maps (tangent-space normals, occlusion), and for each material the normal map it
    /// uses with its scale.
    pub linear_maps: Vec<TextureImage>,
    pub material_normal_maps: Vec<Option<(u32, f32)>>,
    /// For each material its occlusion map (a `linear_maps` layer, R) and strength.
    pub material_occlusion_maps: Vec<Option<(u32, f32)>>,
}

/// The built-in scenes' names, default first.
pub fn builtin_names() -> Vec<&'static str> {
    BUILTIN_MODELS
        .iter()
        .map(|(n, _, _)| *n)
        .chain(BUILTIN_SCENES.iter().map(|(n, _)| *n))
        .collect()
}

impl Scene {
    pub fn builtin(name: &str) -> Result<Scene, SceneError> {
        if let Some((_, file, bytes)) = BUILTIN_MODELS.iter().find(|(n, _, _)| *n == name) {
            return model::builtin_model(name, file, bytes);
        }
        let (_, json) = BUILTIN_SCENES
            .iter()
            .find(|(n, _)| *n == name)
            .ok_or_else(|| SceneError::Unknown(name.to_string()))?;
        Scene::from_json(json)
    }

    /// A glTF (`.gltf` text or `.glb`) held in memory, embedded data only, as the loader reads
    /// it; for fuzzing the parser without files.
    pub fn check_gltf_bytes(bytes: &[u8]) -> Result<usize, String> {
        gltf::import_guarded(bytes, std::path::Path::new("."), None)
            .map(|i| i.parts.len())
            .map_err(|e| e.to_string())
    }

    /// A scene file given as text: its meshes must be built in.
    pub fn from_json(json: &str) -> Result<Scene, SceneError> {
        build::build(json, None)
    }

    /// A scene file (`.json`) or a model (`.gltf`, `.glb`, `.ply`, `.obj`, lit and framed by
    /// default where it says nothing) on disk; everything it refers to must lie in `folder`.
    pub fn load(path: &std::path::Path, folder: &Folder) -> Result<Scene, SceneError> {
        let file_err = |message: String| SceneError::File {
            path: path.display().to_string(),
            message,
        };
        let real = folder
            .resolve(folder.root(), &path.to_string_lossy())
            .or_else(|_| {
                // An absolute path (from the command line) is fine when it is in the folder.
                let real = path.canonicalize().map_err(|e| file_err(e.to_string()))?;
                if real.starts_with(folder.root()) {
                    Ok(real)
                } else {
                    Err(file_err(format!("not inside {}", folder.root().display())))
                }
            })?;
        let base = real.parent().unwrap_or(folder.root()).to_path_buf();
        let is_json = real
            .extension()
            .is_some_and(|e| e.eq_ignore_ascii_case("json"));
        if is_json {
            let bytes = limits::read_limited(&real).map_err(|e| file_err(e.to_string()))?;
            let json = String::from_utf8(bytes).map_err(|_| file_err("not UTF-8 text".into()))?;
            build::build(&json, Some((folder, &base)))
        } else {
            model::scene_of_model(&real, folder)
        }
    }

    /// Centre and radius of a sphere around every translucent vertex (scene units).
    pub fn translucent_bounds(&self) -> (Vec3, f32) {
        let scene = self;
        let pts: Vec<Vec3> = scene
            .mesh
            .positions
            .iter()
            .zip(&scene.mesh.material)
            .filter(|(_, m)| {
                scene
                    .materials
                    .get(**m as usize)
                    .is_some_and(|(_, mat)| mat.is_translucent())
            })
            .map(|(p, _)| *p)
            .collect();
        if pts.is_empty() {
            return (Vec3::ZERO, 1.0);
        }
        let (lo, hi) = pts.iter().fold(
            (Vec3::splat(f32::MAX), Vec3::splat(f32::MIN)),
            |(a, b), p| (a.min(*p), b.max(*p)),
        );
        let centre = 0.5 * (lo + hi);
        let radius = pts
            .iter()
            .map(|p| p.distance(centre))
            .fold(0.0, f32::max)
            .max(1e-3);
        (centre, radius * 1.01)
    }

    pub fn name(&self) -> &str {
        &self.file.name
    }

    pub fn has_translucency(&self) -> bool {
        self.materials.iter().any(|(_, m)| m.is_translucent())
    }

    pub fn metres_per_unit(&self) -> f64 {
        self.file.mm_per_unit / 1000.0
    }

    pub fn has_emitter(&self) -> bool {
        self.materials
            .iter()
            .any(|(_, m)| m.emission().iter().any(|e| *e > 0.0))
    }

    /// The scene as the radiosity solver sees it: one surface per object, in the mesh's
    /// vertex order, so the solver's per-vertex output lines up with the mesh.
    pub fn radiosity_surfaces(&self) -> Vec<crate::radiosity::Surface> {
        use crate::radiosity::Surface;
        let v3 = |c: [f64; 3]| Vec3::new(c[0] as f32, c[1] as f32, c[2] as f32);
        self.placed
            .iter()
            .map(|p| {
                let m = &self.materials[p.material as usize].1;
                match p.quad {
                    Some((corners, cells, max_depth)) => Surface::Quad {
                        corners,
                        cells,
                        max_depth,
                        reflectance: v3(m.albedo()),
                        emission: v3(m.emission()),
                    },
                    None => {
                        let (v0, v1) = (
                            p.first_vertex as usize,
                            (p.first_vertex + p.vertex_count) as usize,
                        );
                        let (i0, i1) = (
                            p.first_index as usize,
                            (p.first_index + p.index_count) as usize,
                        );
                        Surface::Mesh {
                            positions: self.mesh.positions[v0..v1].to_vec(),
                            normals: self.mesh.normals[v0..v1].to_vec(),
                            indices: self.mesh.indices[i0..i1]
                                .iter()
                                .map(|i| i - p.first_vertex)
                                .collect(),
                            reflectance: v3(m.albedo()),
                            emission: v3(m.emission()),
                            triangles_per_patch: 16,
                        }
                    }
                }
            })
            .collect()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn every_builtin_scene_loads() {
        for name in builtin_names() {
            let s = Scene::builtin(name).unwrap_or_else(|e| panic!("{name}: {e}"));
            assert!(s.mesh.triangle_count() > 0);
            assert!((Vec3::from(s.file.light.to_light).length() - 1.0).abs() < 1e-6);
            assert_eq!(s.mesh.material.len(), s.mesh.positions.len());
        }
        assert!(Scene::builtin(DEFAULT_SCENE).unwrap().has_translucency());
        assert!(!Scene::builtin("opaque").unwrap().has_translucency());
    }

    #[test]
    fn unknown_scene_lists_the_available_ones() {
        let e = Scene::builtin("teapot").unwrap_err().to_string();
        assert!(e.contains("teapot") && e.contains("bunny-marble"), "{e}");
    }

    #[test]
    fn bad_values_in_a_scene_file_are_rejected_with_the_reason() {
        let good = include_str!("../../assets/scenes/bunny-marble.json");
        for (from, to, expect) in [
            ("\"ambient\": 0.02", "\"ambient\": 3.0", "ambient"),
            ("\"preset\": \"marble\"", "\"preset\": \"jade\"", "jade"),
            ("\"material\": \"marble\"", "\"material\": \"gold\"", "gold"),
            (
                "\"mesh\": \"bunny.ply\"",
                "\"mesh\": \"teapot.obj\"",
                "teapot.obj",
            ),
        ] {
            let bad = good.replace(from, to);
            assert_ne!(good, bad, "test must actually change the file ({from})");
            let e = Scene::from_json(&bad).unwrap_err().to_string();
            assert!(e.contains(expect), "{e}");
        }
    }

    #[test]
    fn an_orbiting_light_turns_and_a_static_one_does_not() {
        let mut l = Light {
            to_light: [1.0, 0.0, 0.0],
            color: [1.0; 3],
            intensity: 1.0,
            orbit_deg_per_s: 0.0,
        };
        assert_eq!(l.to_light_at(10.0), Vec3::X);
        l.orbit_deg_per_s = 90.0;
        assert!((l.to_light_at(1.0) - Vec3::new(0.0, 0.0, -1.0)).length() < 1e-6);
    }
}
