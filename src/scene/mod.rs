//! Scenes: a JSON description (camera, one directional light, materials, objects placing
//! meshes), loaded and validated into one combined mesh with a material per vertex. The
//! built-in scenes are embedded in the binary so `fovea` runs from any directory.
//! Format: `docs/scenes.md`.

mod camera;
mod file;
pub mod material;
mod mesh;
pub mod plan;
mod ply;

pub use camera::Camera;
pub use file::{Light, ObjectSpec, RadiosityMode, RadiositySpec, SceneFile};
pub use material::{Material, MaterialSpec};
pub use mesh::Mesh;
pub use plan::Plan;
pub use ply::{parse_ply, PlyError, PlyMesh};

use glam::{Mat4, Quat, Vec3};

/// The scene a session gets when `hello` names none.
pub const DEFAULT_SCENE: &str = "bunny-marble";

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
    #[error("scene {scene:?}: mesh {mesh:?}: {source}")]
    Mesh {
        scene: String,
        mesh: String,
        source: PlyError,
    },
    #[error("scene {scene:?}: {message}")]
    Invalid { scene: String, message: String },
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
    /// One per object, in file order.
    pub placed: Vec<Placed>,
}

/// The built-in scenes' names, default first.
pub fn builtin_names() -> Vec<&'static str> {
    BUILTIN_SCENES.iter().map(|(n, _)| *n).collect()
}

/// A unit square in XZ centred on the origin, facing +Y (two counter-clockwise triangles).
fn plane() -> PlyMesh {
    let positions = vec![
        Vec3::new(-0.5, 0.0, -0.5),
        Vec3::new(-0.5, 0.0, 0.5),
        Vec3::new(0.5, 0.0, 0.5),
        Vec3::new(0.5, 0.0, -0.5),
    ];
    PlyMesh {
        positions,
        indices: vec![0, 1, 2, 0, 2, 3],
    }
}

impl Scene {
    pub fn builtin(name: &str) -> Result<Scene, SceneError> {
        let (_, json) = BUILTIN_SCENES
            .iter()
            .find(|(n, _)| *n == name)
            .ok_or_else(|| SceneError::Unknown(name.to_string()))?;
        Scene::from_json(json)
    }

    pub fn from_json(json: &str) -> Result<Scene, SceneError> {
        let mut file: SceneFile =
            serde_json::from_str(json).map_err(|source| SceneError::Json {
                scene: "<json>".into(),
                source,
            })?;
        let scene = file.name.clone();
        let invalid = |message: String| SceneError::Invalid {
            scene: scene.clone(),
            message,
        };
        file.camera.validate().map_err(invalid)?;
        if !(0.0..=1.0).contains(&file.ambient) {
            return Err(invalid(format!(
                "ambient {} must lie in [0, 1]",
                file.ambient
            )));
        }
        if !(file.mm_per_unit.is_finite() && file.mm_per_unit > 0.0) {
            return Err(invalid(format!(
                "mm_per_unit {} must be finite and > 0",
                file.mm_per_unit
            )));
        }
        let to_light = Vec3::from(file.light.to_light)
            .try_normalize()
            .ok_or_else(|| invalid("light.to_light must be a non-zero finite vector".into()))?;
        file.light.to_light = to_light.into();
        let light_ok = file.light.color.iter().all(|c| c.is_finite() && *c >= 0.0)
            && file.light.intensity.is_finite()
            && file.light.intensity >= 0.0
            && file.light.orbit_deg_per_s.is_finite();
        if !light_ok {
            return Err(invalid(
                "light colour and intensity must be finite and ≥ 0".into(),
            ));
        }
        let mut materials = Vec::new();
        for (name, spec) in &file.materials {
            let m = Material::from_spec(spec)
                .map_err(|e| invalid(format!("material {name:?}: {e}")))?;
            materials.push((name.clone(), m));
        }
        if file.objects.is_empty() {
            return Err(invalid("a scene needs at least one object".into()));
        }
        if let Some(r) = &file.radiosity {
            if !(r.patch_size.is_finite() && r.patch_size > 0.0)
                || r.max_depth > 6
                || !(r.stop_fraction > 0.0 && r.stop_fraction < 1.0)
            {
                return Err(invalid(
                    "radiosity: patch_size must be > 0, max_depth ≤ 6 and stop_fraction in (0, 1)"
                        .into(),
                ));
            }
        }
        let mut mesh = Mesh::default();
        let mut placed = Vec::new();
        for (i, object) in file.objects.iter().enumerate() {
            let material = materials
                .iter()
                .position(|(n, _)| *n == object.material)
                .ok_or_else(|| {
                    invalid(format!(
                        "object {i} uses material {:?}, which the scene does not define",
                        object.material
                    ))
                })?;
            let mut quad = None;
            let ply = match object.mesh.as_str() {
                "plane" => plane(),
                "quad" => {
                    let corners = object.corners.map(|c| c.map(Vec3::from)).ok_or_else(|| {
                        invalid(format!("object {i}: a quad needs its four corners"))
                    })?;
                    let (cells, depth) = quad_lattice(&corners, file.radiosity.as_ref())
                        .ok_or_else(|| {
                            invalid(format!(
                                "object {i}: quad corners must be finite and form a parallelogram"
                            ))
                        })?;
                    quad = Some((corners, cells, depth));
                    lattice_mesh(&corners, crate::radiosity::lattice(cells, depth))
                }
                name => {
                    let (_, bytes) =
                        BUILTIN_MESHES
                            .iter()
                            .find(|(n, _)| *n == name)
                            .ok_or_else(|| SceneError::UnknownMesh {
                                scene: scene.clone(),
                                mesh: name.to_string(),
                            })?;
                    parse_ply(bytes).map_err(|source| SceneError::Mesh {
                        scene: scene.clone(),
                        mesh: name.to_string(),
                        source,
                    })?
                }
            };
            if !(object.scale.is_finite() && object.scale > 0.0)
                || !Vec3::from(object.translate).is_finite()
                || !object.rotate_y_deg.is_finite()
            {
                return Err(invalid(format!(
                    "object {i}: scale must be > 0 and the transform finite"
                )));
            }
            let transform = Mat4::from_scale_rotation_translation(
                Vec3::splat(object.scale),
                Quat::from_rotation_y(object.rotate_y_deg.to_radians()),
                Vec3::from(object.translate),
            );
            let positions: Vec<Vec3> = ply
                .positions
                .iter()
                .map(|p| transform.transform_point3(*p))
                .collect();
            let part = Mesh::with_smooth_normals(positions, ply.indices);
            // The cheap translucency rung shades with normals blurred over the light's reach.
            let reach_units = (materials[material].1.reach_mm() / file.mm_per_unit) as f32;
            placed.push(Placed {
                material: material as u32,
                first_vertex: mesh.positions.len() as u32,
                vertex_count: part.positions.len() as u32,
                first_index: mesh.indices.len() as u32,
                index_count: part.indices.len() as u32,
                quad: quad
                    .map(|(c, cells, d)| (c.map(|p| transform.transform_point3(p)), cells, d)),
            });
            mesh.append(part.with_blurred_normals(reach_units), material as u32);
        }
        Ok(Scene {
            file,
            mesh,
            materials,
            placed,
        })
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
                            triangles_per_patch: 16,
                        }
                    }
                }
            })
            .collect()
    }
}

/// Patches per side and subdivision depth for a quad: patches no larger than the scene's
/// `radiosity.patch_size` (one patch without radiosity settings). `None` if not a parallelogram.
fn quad_lattice(c: &[Vec3; 4], spec: Option<&RadiositySpec>) -> Option<([u32; 2], u32)> {
    let (u, v) = (c[1] - c[0], c[3] - c[0]);
    let closes = (c[0] + u + v - c[2]).length() <= 1e-4 * (u.length() + v.length());
    if !(c.iter().all(|p| p.is_finite()) && closes && u.cross(v).length() > 0.0) {
        return None;
    }
    Some(match spec {
        Some(r) if r.mode != RadiosityMode::Off => {
            let n = |len: f32| ((len / r.patch_size).ceil() as u32).clamp(1, 64);
            ([n(u.length()), n(v.length())], r.max_depth)
        }
        _ => ([1, 1], 0),
    })
}

/// A parallelogram as a grid of `lattice[0] × lattice[1]` cells, row by row from corner 0
/// (the order the radiosity solver writes its per-vertex output in).
fn lattice_mesh(c: &[Vec3; 4], lattice: [u32; 2]) -> PlyMesh {
    let [lu, lv] = lattice;
    let mut positions = Vec::with_capacity(((lu + 1) * (lv + 1)) as usize);
    for j in 0..=lv {
        for i in 0..=lu {
            positions.push(
                c[0] + (c[1] - c[0]) * (i as f32 / lu as f32)
                    + (c[3] - c[0]) * (j as f32 / lv as f32),
            );
        }
    }
    let mut indices = Vec::with_capacity((lu * lv * 6) as usize);
    let at = |i: u32, j: u32| j * (lu + 1) + i;
    for j in 0..lv {
        for i in 0..lu {
            indices.extend([at(i, j), at(i + 1, j), at(i + 1, j + 1)]);
            indices.extend([at(i, j), at(i + 1, j + 1), at(i, j + 1)]);
        }
    }
    PlyMesh { positions, indices }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn every_builtin_scene_loads() {
        for name in builtin_names() {
            let s = Scene::builtin(&name).unwrap_or_else(|e| panic!("{name}: {e}"));
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
