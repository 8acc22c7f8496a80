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

/// Lights beyond the key light (`SceneFile::lights`): they light surfaces directly (diffuse and
/// specular), spot and point lights with shadows from the atlas; the subsurface photons, which
/// lie where the key light sees a translucent body, carry their light into it.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(tag = "kind", rename_all = "snake_case", deny_unknown_fields)]
pub enum LightSpec {
    /// Like the key light: `intensity` is the irradiance on a surface facing it.
    Directional {
        to_light: [f32; 3],
        color: [f32; 3],
        intensity: f32,
    },
    /// `intensity` is the irradiance it gives a surface facing it 1 scene unit away (it falls
    /// with the square of the distance); `range` (scene units), if set, fades it to 0 there.
    Point {
        position: [f32; 3],
        color: [f32; 3],
        intensity: f32,
        #[serde(default, skip_serializing_if = "Option::is_none")]
        range: Option<f32>,
    },
    /// A point light limited to a cone around `direction`, full inside `inner_deg` of it and
    /// fading to 0 at `outer_deg`.
    Spot {
        position: [f32; 3],
        direction: [f32; 3],
        color: [f32; 3],
        intensity: f32,
        #[serde(default, skip_serializing_if = "Option::is_none")]
        range: Option<f32>,
        inner_deg: f32,
        outer_deg: f32,
    },
}

/// Most extra lights a scene may have (the shading pass loops over all of them per pixel).
pub const MAX_LIGHTS: usize = 8;

impl LightSpec {
    /// The light with its intensity multiplied by `k` (an exposure).
    pub fn scaled(mut self, k: f32) -> LightSpec {
        match &mut self {
            LightSpec::Directional { intensity, .. }
            | LightSpec::Point { intensity, .. }
            | LightSpec::Spot { intensity, .. } => *intensity *= k,
        }
        self
    }

    /// The light moved with the object that brought it (a glTF file placed in a scene).
    pub fn transformed(self, m: glam::Mat4) -> LightSpec {
        let dir = |v: [f32; 3]| {
            m.transform_vector3(Vec3::from(v))
                .normalize_or_zero()
                .into()
        };
        let pos = |p: [f32; 3]| m.transform_point3(Vec3::from(p)).into();
        match self {
            LightSpec::Directional {
                to_light,
                color,
                intensity,
            } => LightSpec::Directional {
                to_light: dir(to_light),
                color,
                intensity,
            },
            LightSpec::Point {
                position,
                color,
                intensity,
                range,
            } => LightSpec::Point {
                position: pos(position),
                color,
                intensity,
                range,
            },
            LightSpec::Spot {
                position,
                direction,
                color,
                intensity,
                range,
                inner_deg,
                outer_deg,
            } => LightSpec::Spot {
                position: pos(position),
                direction: dir(direction),
                color,
                intensity,
                range,
                inner_deg,
                outer_deg,
            },
        }
    }

    pub fn validate(&self) -> Result<(), String> {
        let finite3 = |v: &[f32; 3]| v.iter().all(|x| x.is_finite());
        let colour_ok = |c: &[f32; 3], i: f32| {
            c.iter().all(|x| x.is_finite() && *x >= 0.0) && i.is_finite() && i >= 0.0
        };
        let range_ok = |r: &Option<f32>| r.is_none_or(|r| r.is_finite() && r > 0.0);
        let ok = match self {
            LightSpec::Directional {
                to_light,
                color,
                intensity,
            } => {
                finite3(to_light)
                    && Vec3::from(*to_light).length() > 1e-6
                    && colour_ok(color, *intensity)
            }
            LightSpec::Point {
                position,
                color,
                intensity,
                range,
            } => finite3(position) && colour_ok(color, *intensity) && range_ok(range),
            LightSpec::Spot {
                position,
                direction,
                color,
                intensity,
                range,
                inner_deg,
                outer_deg,
            } => {
                finite3(position)
                    && finite3(direction)
                    && Vec3::from(*direction).length() > 1e-6
                    && colour_ok(color, *intensity)
                    && range_ok(range)
                    && (0.0..90.0).contains(inner_deg)
                    && *outer_deg > *inner_deg
                    && *outer_deg <= 90.0
            }
        };
        if ok {
            Ok(())
        } else {
            Err(format!("light {self:?}: positions and directions must be finite (directions non-zero), colour and intensity ≥ 0, range > 0, and 0 ≤ inner_deg < outer_deg ≤ 90"))
        }
    }
}

/// A mesh placed in the scene: scaled, turned about the vertical axis, then moved.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ObjectSpec {
    /// A built-in mesh: `bunny.ply`, `plane` (a unit square in XZ facing +Y), or `quad` (the
    /// parallelogram `corners`, in scene units, counter-clockwise seen from its front); or a
    /// file beside the scene file: `.ply`, `.obj` (with `material`), `.gltf`/`.glb` (its own
    /// materials unless `material` is given; its lights join the scene's).
    pub mesh: String,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub corners: Option<[[f32; 3]; 4]>,
    /// A key of the scene's `materials` (optional for glTF files, which bring their own).
    #[serde(default, skip_serializing_if = "String::is_empty")]
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
    /// Whenever something emits or the key light shines (and holds still): the key light's
    /// first bounce seeds the solve, so an open scene gets its floor's light on its objects.
    On,
    Off,
}

#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct RadiositySpec {
    #[serde(default)]
    pub mode: RadiosityMode,
    /// Largest patch edge, scene units (walls are split into patches no larger). Omitted:
    /// each quad is split into [`DEFAULT_PATCHES`] along its longer side.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub patch_size: Option<f32>,
    /// How many times an element may halve where a shot leaves a steep gradient.
    #[serde(default = "two")]
    pub max_depth: u32,
    /// Converged when the unshot power is below this fraction of the emitted power.
    #[serde(default = "thousandth")]
    pub stop_fraction: f64,
}

/// Patches along a quad's longer side when the scene gives no `patch_size`: fine enough for
/// a floor's bounce to fall off across it, coarse enough for a fast solve.
pub const DEFAULT_PATCHES: u32 = 16;

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
    #[serde(default)]
    pub materials: BTreeMap<String, MaterialSpec>,
    pub objects: Vec<ObjectSpec>,
    /// Lights beyond the key light `light` (at most `MAX_LIGHTS`).
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub lights: Vec<LightSpec>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub radiosity: Option<RadiositySpec>,
}
