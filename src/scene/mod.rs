//! Scenes: a JSON description (camera, light, material, background) plus a mesh. The built-in
//! scenes are embedded in the binary so `fovea` runs from any directory.

mod camera;
mod mesh;
mod ply;

pub use camera::Camera;
pub use mesh::Mesh;
pub use ply::{parse_ply, PlyError, PlyMesh};

use glam::Vec3;
use serde::{Deserialize, Serialize};

/// The scene a session gets when `hello` names none.
pub const DEFAULT_SCENE: &str = "bunny";

/// Built-in scenes: (name, scene JSON).
const BUILTIN_SCENES: &[(&str, &str)] = &[("bunny", include_str!("../../assets/scenes/bunny.json"))];

/// Meshes the scene files may refer to by file name.
const BUILTIN_MESHES: &[(&str, &[u8])] = &[("bunny.ply", include_bytes!("../../assets/meshes/bunny.ply"))];

#[derive(Debug, thiserror::Error)]
pub enum SceneError {
    #[error("unknown scene {0:?} (available: {available})", available = builtin_names().join(", "))]
    Unknown(String),
    #[error("scene {scene:?} refers to mesh {mesh:?}, which is not built in")]
    UnknownMesh { scene: String, mesh: String },
    #[error("scene file {scene:?} is invalid: {source}")]
    Json { scene: String, source: serde_json::Error },
    #[error("scene {scene:?}: mesh {mesh:?}: {source}")]
    Mesh { scene: String, mesh: String, source: PlyError },
    #[error("scene {scene:?}: {message}")]
    Invalid { scene: String, message: String },
}

/// One directional light.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Light {
    /// Direction from the scene towards the light (normalised at load).
    pub to_light: [f32; 3],
    /// Linear RGB colour of the light.
    pub color: [f32; 3],
    /// Irradiance scale on a surface facing the light.
    pub intensity: f32,
}

/// A scene file as written on disk (see `docs/scenes.md`).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct SceneFile {
    pub name: String,
    #[serde(default)]
    pub description: String,
    pub mesh: String,
    /// Linear diffuse reflectance, each channel in [0, 1].
    pub albedo: [f32; 3],
    /// Constant ambient irradiance as a fraction of the light, so unlit sides are not black.
    pub ambient: f32,
    /// Background colour as it appears in the output image (sRGB bytes).
    pub background_srgb: [u8; 3],
    pub light: Light,
    pub camera: Camera,
    /// Size of one scene unit in metres (depth of field works in metres). Default: centimetres.
    #[serde(default = "centimetres")]
    pub metres_per_unit: f32,
}

fn centimetres() -> f32 {
    0.01
}

/// A loaded, validated scene.
#[derive(Debug, Clone)]
pub struct Scene {
    pub file: SceneFile,
    pub mesh: Mesh,
}

pub fn builtin_names() -> Vec<String> {
    BUILTIN_SCENES.iter().map(|(n, _)| (*n).to_string()).collect()
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
        let mut file: SceneFile = serde_json::from_str(json)
            .map_err(|source| SceneError::Json { scene: "<json>".into(), source })?;
        let scene = file.name.clone();
        let invalid = |message: String| SceneError::Invalid { scene: scene.clone(), message };
        let (_, bytes) = BUILTIN_MESHES
            .iter()
            .find(|(n, _)| *n == file.mesh)
            .ok_or_else(|| SceneError::UnknownMesh { scene: scene.clone(), mesh: file.mesh.clone() })?;
        let ply = parse_ply(bytes)
            .map_err(|source| SceneError::Mesh { scene: scene.clone(), mesh: file.mesh.clone(), source })?;
        file.camera.validate().map_err(invalid)?;
        if file.albedo.iter().any(|a| !(0.0..=1.0).contains(a)) {
            return Err(invalid(format!("albedo {:?} must lie in [0, 1]", file.albedo)));
        }
        if !(0.0..=1.0).contains(&file.ambient) {
            return Err(invalid(format!("ambient {} must lie in [0, 1]", file.ambient)));
        }
        let to_light = Vec3::from(file.light.to_light)
            .try_normalize()
            .ok_or_else(|| invalid("light.to_light must be a non-zero finite vector".into()))?;
        file.light.to_light = to_light.into();
        let light_ok = file.light.color.iter().all(|c| c.is_finite() && *c >= 0.0)
            && file.light.intensity.is_finite()
            && file.light.intensity >= 0.0;
        if !light_ok {
            return Err(invalid("light colour and intensity must be finite and ≥ 0".into()));
        }
        if !(file.metres_per_unit.is_finite() && file.metres_per_unit > 0.0) {
            return Err(invalid(format!("metres_per_unit {} must be finite and > 0", file.metres_per_unit)));
        }
        let mesh = Mesh::with_smooth_normals(ply.positions, ply.indices);
        Ok(Scene { file, mesh })
    }

    pub fn name(&self) -> &str {
        &self.file.name
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn every_builtin_scene_loads() {
        for name in builtin_names() {
            let s = Scene::builtin(&name).unwrap();
            assert!(s.mesh.triangle_count() > 0);
            assert!((Vec3::from(s.file.light.to_light).length() - 1.0).abs() < 1e-6);
        }
    }

    #[test]
    fn unknown_scene_lists_the_available_ones() {
        let e = Scene::builtin("teapot").unwrap_err().to_string();
        assert!(e.contains("teapot") && e.contains("bunny"), "{e}");
    }

    #[test]
    fn bad_values_in_a_scene_file_are_rejected_with_the_reason() {
        let good = include_str!("../../assets/scenes/bunny.json");
        let bad = good.replace("\"ambient\": 0.06", "\"ambient\": 3.0");
        assert_ne!(good, bad, "test must actually change the file");
        let e = Scene::from_json(&bad).unwrap_err().to_string();
        assert!(e.contains("ambient"), "{e}");
    }
}
