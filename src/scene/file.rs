//! The scene file as written on disk (`docs/scenes.md`): its light, objects and radiosity
//! settings, with their defaults.

use std::collections::BTreeMap;

use glam::{Quat, Vec3};
use serde::{Deserialize, Serialize};

use super::{Camera, MaterialSpec};

/// One directional light.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Light {
    /// Direction from the scene towards the light (normalised at load).
    pub to_light: [f32; 3],
    /// Linear RGB colour of the light.
    pub color: [f32; 3],
    /// Irradiance on a surface facing the light (1 makes a white Lambertian surface white).
    pub intensity: f32,
    /// Degrees per second the light circles the vertical axis; 0 for a static light.
    #[serde(default)]
    pub orbit_deg_per_s: f32,
}

impl Light {
    /// Direction towards the light `t` seconds into a sequence.
    pub fn to_light_at(&self, t: f64) -> Vec3 {
        let base = Vec3::from(self.to_light);
        if self.orbit_deg_per_s == 0.0 {
            return base;
        }
        Quat::from_rotation_y((f64::from(self.orbit_deg_per_s) * t).to_radians() as f32) * base
    }
}

/// A mesh placed in the scene: scaled, turned about the vertical axis, then moved.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ObjectSpec {
    /// A built-in mesh: `bunny.ply`, `plane` (a unit square in XZ facing +Y), or `quad` (the
    /// parallelogram `corners`, in scene units, counter-clockwise seen from its front).
    pub mesh: String,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub corners: Option<[[f32; 3]; 4]>,
    /// A key of the scene's `materials`.
    pub material: String,
    #[serde(default)]
    pub translate: [f32; 3],
    #[serde(default = "one")]
    pub scale: f32,
    #[serde(default)]
    pub rotate_y_deg: f32,
}

fn one() -> f32 {
    1.0
}

fn ten() -> f64 {
    10.0
}

/// Whether the scene gets diffuse interreflection (progressive refinement radiosity).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum RadiosityMode {
    /// The plan decides: on for an enclosed scene with an area light (see `Plan`).
    #[default]
    Auto,
    On,
    Off,
}

#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct RadiositySpec {
    #[serde(default)]
    pub mode: RadiosityMode,
    /// Largest patch edge, scene units (walls are split into patches no larger).
    pub patch_size: f32,
    /// How many times an element may halve where a shot leaves a steep gradient.
    #[serde(default = "two")]
    pub max_depth: u32,
    /// Converged when the unshot power is below this fraction of the emitted power.
    #[serde(default = "thousandth")]
    pub stop_fraction: f64,
}

fn two() -> u32 {
    2
}

fn thousandth() -> f64 {
    0.001
}

/// A scene file as written on disk.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct SceneFile {
    pub name: String,
    #[serde(default)]
    pub description: String,
    /// Millimetres per scene unit (subsurface scattering and depth of field are physical).
    #[serde(default = "ten")]
    pub mm_per_unit: f64,
    /// Constant ambient irradiance as a fraction of the light, so unlit sides are not black.
    pub ambient: f32,
    /// Background colour as it appears in the output image (sRGB bytes).
    pub background_srgb: [u8; 3],
    pub light: Light,
    pub camera: Camera,
    pub materials: BTreeMap<String, MaterialSpec>,
    pub objects: Vec<ObjectSpec>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub radiosity: Option<RadiositySpec>,
}
