//! The scene plan: from the scene file (and the frame size) alone, which passes a frame needs.
//! Nothing translucent → no photon pass and no pyramid. Static light and geometry → the pyramid
//! is built once. A translucent material whose light spreads less than a pixel at the distance
//! it is seen from → its translucency is invisible, and the cheap opaque rung shades it.

use std::fmt;

use glam::Vec3;

use super::{Material, Scene};

/// Photon map side (the renderer's photon pass uses this): 64² photons over the translucent
/// objects' bounding sphere.
pub const PHOTON_MAP_SIDE: u32 = 64;

/// When the light-space photon pyramid is (re)built.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Pyramid {
    /// No translucent material needs the dipole.
    NotNeeded,
    /// Geometry and light are static: built once, reused by every frame and session.
    Once,
    /// The light moves: rebuilt every frame.
    EveryFrame { orbit_deg_per_s: f32 },
}

#[derive(Debug, Clone, PartialEq)]
pub struct MaterialPlan {
    pub name: String,
    pub translucent: bool,
    pub emitter: bool,
    /// Radius (mm) through which 90% of the re-emitted light leaves (`Material::reach_mm`).
    pub reach_mm: f64,
    /// What one pixel covers (mm) on the nearest object using this material.
    pub footprint_mm: f64,
    /// Spacing of the photons (mm): light that spreads less than this shows them as dots.
    pub photon_spacing_mm: f64,
    /// Shade with the subsurface rungs (false: opaque BRDF, at the dipole's total reflectance).
    pub subsurface: bool,
    /// The interface: (roughness, metallic, double-sided); `None` for emitters.
    pub surface: Option<(f64, f64, bool)>,
}

#[derive(Debug, Clone, PartialEq)]
pub struct Plan {
    pub scene: String,
    pub width: u32,
    pub height: u32,
    pub materials: Vec<MaterialPlan>,
    pub photon_pass: bool,
    pub pyramid: Pyramid,
    /// Progressive refinement radiosity: for enclosed scenes with an area light.
    pub radiosity: bool,
    /// Why radiosity is on or off, for the printout.
    pub radiosity_reason: String,
    /// The key light's shadow pass, and why.
    pub shadows: bool,
    pub shadow_reason: String,
    /// Extra punctual lights by kind: directional, point, spot.
    pub extra_lights: [usize; 3],
}

/// Whether the key light needs a shadow map: it shines, and something can stand between it and
/// a surface (a single flat object cannot shadow itself).
fn shadows(scene: &Scene) -> (bool, String) {
    let first = scene.mesh.normals.first().copied().unwrap_or(Vec3::Y);
    let flat = scene.placed.len() == 1 && scene.mesh.normals.iter().all(|n| n.dot(first) > 0.9999);
    if flat {
        return (
            false,
            "off (a single flat surface cannot shadow itself)".into(),
        );
    }
    let (mut spots, mut points) = (0, 0);
    for l in &scene.file.lights {
        match l {
            super::LightSpec::Spot { .. } => spots += 1,
            super::LightSpec::Point { .. } => points += 1,
            super::LightSpec::Directional { .. } => {}
        }
    }
    if scene.file.light.intensity <= 0.0 && spots + points == 0 {
        return (
            false,
            "off (the key light is off and no spot or point light shines)".into(),
        );
    }
    let tiles = spots + 6 * points;
    let punctual = match (spots, points) {
        (0, 0) => String::new(),
        _ if tiles <= SHADOW_TILES => format!(
            ", each spot light's (a 512² perspective tile: {spots}) and point light's (a cube of six: {points})"
        ),
        _ => format!(
            ", and the spot lights' (one 512² tile each) and point lights' (six each) in scene order while {SHADOW_TILES} tiles last: {spots} spot and {points} point lights need {tiles}, the rest are unshadowed"
        ),
    };
    (
        true,
        format!(
            "on: the key light's shadow map{punctual}; 3×3 tent PCF, normal-offset and depth bias"
        ),
    )
}

/// Tiles in the punctual lights' shadow atlas: a spot light takes one, a point light six.
pub const SHADOW_TILES: usize = 16;

/// Auto mode turns radiosity on when at least this share of directions from the scene's centre
/// meets a surface: a box open on one side (a Cornell box) is ~5/6, a bunny on a floor ~1/2.
pub const ENCLOSED: f64 = 2.0 / 3.0;

/// The key light as radiosity's source of a first bounce, when it shines and holds still (an
/// orbiting light would need a new solve every frame).
pub fn radiosity_sun(scene: &Scene) -> Option<crate::radiosity::Sun> {
    let l = &scene.file.light;
    let shines = l.intensity > 0.0 && l.color.iter().any(|&c| c > 0.0);
    (shines && l.orbit_deg_per_s == 0.0).then(|| crate::radiosity::Sun {
        to_light: Vec3::from(l.to_light),
        irradiance: Vec3::from(l.color) * l.intensity,
    })
}

/// The share of directions from the centre of the scene's bounds that meet a surface.
pub fn enclosure(scene: &Scene) -> f64 {
    let tris: Vec<[Vec3; 3]> = scene
        .mesh
        .indices
        .chunks_exact(3)
        .map(|t| [0, 1, 2].map(|k| scene.mesh.positions[t[k] as usize]))
        .collect();
    let (lo, hi) = scene.mesh.bounds();
    crate::radiosity::enclosure(&tris, (lo + hi) / 2.0, 4.0 * (hi - lo).length())
}

/// Whether the scene needs radiosity, and why.
fn radiosity(scene: &Scene) -> (bool, String) {
    use super::RadiosityMode;
    let mode = scene.file.radiosity.map(|r| r.mode).unwrap_or_default();
    let sun = radiosity_sun(scene).is_some();
    match mode {
        RadiosityMode::Off => return (false, "off (the scene file turns it off)".into()),
        RadiosityMode::On if sun => return (
            true,
            "on (the scene file asks for it): the key light's first bounce and its interreflection"
                .into(),
        ),
        RadiosityMode::On if !scene.has_emitter() => {
            return (
                false,
                "off (nothing emits, and the key light is dark or orbits: no bounce to solve)"
                    .into(),
            )
        }
        RadiosityMode::Auto if !scene.has_emitter() => {
            return (
                false,
                "off (nothing emits; \"radiosity\": {\"mode\": \"on\"} in a scene file carries the key light's bounce)".into(),
            )
        }
        RadiosityMode::On => return (true, "on (the scene file asks for it)".into()),
        RadiosityMode::Auto => {}
    }
    let enclosed = enclosure(scene);
    if enclosed >= ENCLOSED {
        (
            true,
            format!(
                "on (enclosed: {:.0}% of directions from the centre meet a surface, and an area light shines)",
                100.0 * enclosed
            ),
        )
    } else {
        (
            false,
            format!(
                "off (open scene: only {:.0}% of directions from the centre meet a surface)",
                100.0 * enclosed
            ),
        )
    }
}

impl Plan {
    pub fn of(scene: &Scene, width: u32, height: u32) -> Plan {
        let cam = &scene.file.camera;
        let eye = Vec3::from(cam.eye);
        // Millimetres one pixel spans per unit of distance from the eye.
        let mm_per_pixel_per_unit = 2.0 * (f64::from(cam.fov_y_deg).to_radians() / 2.0).tan()
            / f64::from(height.max(1))
            * scene.file.mm_per_unit;
        let (_, radius) = scene.translucent_bounds();
        let photon_spacing_mm =
            2.0 * f64::from(radius) * scene.file.mm_per_unit / f64::from(PHOTON_MAP_SIDE);
        let materials: Vec<MaterialPlan> = scene
            .materials
            .iter()
            .enumerate()
            .map(|(id, (name, m))| {
                // Nearest vertex of this material: the most detailed view of it.
                let nearest = scene
                    .mesh
                    .positions
                    .iter()
                    .zip(&scene.mesh.material)
                    .filter(|(_, mat)| **mat as usize == id)
                    .map(|(p, _)| f64::from(p.distance(eye)))
                    .fold(f64::INFINITY, f64::min)
                    .max(f64::from(cam.near));
                let footprint_mm = nearest * mm_per_pixel_per_unit;
                let reach_mm = m.reach_mm();
                MaterialPlan {
                    name: name.clone(),
                    translucent: m.is_translucent(),
                    emitter: matches!(m, Material::Emitter { .. }),
                    reach_mm,
                    footprint_mm,
                    photon_spacing_mm,
                    subsurface: matches!(m, Material::Translucent { .. })
                        && reach_mm >= footprint_mm
                        && reach_mm >= photon_spacing_mm,
                    surface: m
                        .surface()
                        .map(|s| (s.roughness, s.metallic, s.double_sided)),
                }
            })
            .collect();
        let needs_dipole = materials.iter().any(|m| m.subsurface);
        let (radiosity, radiosity_reason) = radiosity(scene);
        let orbit = scene.file.light.orbit_deg_per_s;
        let pyramid = match (needs_dipole, orbit != 0.0) {
            (false, _) => Pyramid::NotNeeded,
            (true, false) => Pyramid::Once,
            (true, true) => Pyramid::EveryFrame {
                orbit_deg_per_s: orbit,
            },
        };
        let (shadows, shadow_reason) = shadows(scene);
        let mut extra_lights = [0; 3];
        for l in &scene.file.lights {
            extra_lights[match l {
                super::LightSpec::Directional { .. } => 0,
                super::LightSpec::Point { .. } => 1,
                super::LightSpec::Spot { .. } => 2,
            }] += 1;
        }
        Plan {
            scene: scene.name().to_string(),
            width,
            height,
            materials,
            photon_pass: needs_dipole,
            pyramid,
            radiosity,
            radiosity_reason,
            shadows,
            shadow_reason,
            extra_lights,
        }
    }

    /// Whether material `id` is shaded with the subsurface rungs.
    pub fn subsurface(&self, id: usize) -> bool {
        self.materials.get(id).is_some_and(|m| m.subsurface)
    }
}

impl fmt::Display for Plan {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        writeln!(
            f,
            "scene plan for {:?} at {}x{}:",
            self.scene, self.width, self.height
        )?;
        for m in &self.materials {
            let interface = match m.surface {
                Some((r, metal, two)) => format!(
                    "GGX specular (roughness {r:.2}{}){}",
                    if metal > 0.0 {
                        format!(", metallic {metal:.2}")
                    } else {
                        String::new()
                    },
                    if two { ", double-sided" } else { "" }
                ),
                None => String::new(),
            };
            if m.emitter {
                writeln!(f, "  material {:?}: area light", m.name)?;
            } else if !m.translucent {
                writeln!(f, "  material {:?}: opaque: Lambert + {interface}", m.name)?;
            } else if m.subsurface {
                writeln!(
                    f,
                    "  material {:?}: subsurface scattering, every rung (light spreads {:.2} mm, a pixel covers {:.2} mm), under a rough interface: {interface}",
                    m.name, m.reach_mm, m.footprint_mm
                )?;
            } else if m.reach_mm < m.photon_spacing_mm && m.reach_mm >= m.footprint_mm {
                writeln!(
                    f,
                    "  material {:?}: translucent, but light spreads {:.2} mm < the photons' spacing ({:.2} mm), which would show as dots: rung opaque only + {interface}",
                    m.name, m.reach_mm, m.photon_spacing_mm
                )?;
            } else {
                writeln!(
                    f,
                    "  material {:?}: translucent, but light spreads {:.2} mm < one pixel ({:.2} mm): rung opaque only (its total diffuse reflectance) + {interface}",
                    m.name, m.reach_mm, m.footprint_mm
                )?;
            }
        }
        match self.pyramid {
            Pyramid::NotNeeded => writeln!(f, "  light-space photon pass: off (nothing needs subsurface scattering)")?,
            Pyramid::Once => writeln!(f, "  light-space photon pass + quad-tree pyramid: built once (static light and geometry)")?,
            Pyramid::EveryFrame { orbit_deg_per_s } => {
                writeln!(f, "  light-space photon pass + quad-tree pyramid: rebuilt every frame (light orbits {orbit_deg_per_s}°/s)")?
            }
        }
        writeln!(f, "  shadows: {}", self.shadow_reason)?;
        let [d, p, s] = self.extra_lights;
        if d + p + s == 0 {
            writeln!(f, "  extra lights: none")?;
        } else {
            writeln!(f, "  extra lights: {d} directional, {p} point, {s} spot: diffuse + specular; spot and point lights shadowed while the atlas has room (see shadows), directional ones not; translucent bodies take their light through the photons (which lie where the key light sees them) and locally elsewhere")?;
        }
        writeln!(f, "  radiosity: {}", self.radiosity_reason)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn opaque_only_scenes_run_nothing_translucent() {
        let p = Plan::of(&Scene::builtin("opaque").unwrap(), 640, 480);
        assert!(!p.photon_pass && p.pyramid == Pyramid::NotNeeded && !p.radiosity);
        assert!(p.materials.iter().all(|m| !m.subsurface));
        assert!(p.to_string().contains("photon pass: off"));
    }

    #[test]
    fn radiosity_runs_in_the_enclosed_box_and_never_for_one_open_object() {
        let box_plan = Plan::of(&Scene::builtin("cornell").unwrap(), 640, 480);
        assert!(box_plan.radiosity, "{box_plan}");
        assert!(
            box_plan.to_string().contains("radiosity: on (enclosed"),
            "{box_plan}"
        );
        for open in ["bunny-marble", "bunny", "materials", "opaque", "bunny-skin"] {
            let p = Plan::of(&Scene::builtin(open).unwrap(), 640, 480);
            assert!(
                !p.radiosity && p.to_string().contains("radiosity: off"),
                "{p}"
            );
        }
        // An area light alone does not make an open scene enclosed: the bunny on its floor
        // with the lamp of the box above it stays off, and the printout says why.
        let cornell = include_str!("../../assets/scenes/cornell.json");
        let mut file: crate::scene::SceneFile = serde_json::from_str(cornell).unwrap();
        let floor =
            |o: &crate::scene::ObjectSpec| o.corners.is_some_and(|c| c.iter().all(|p| p[1] == 0.0));
        file.objects
            .retain(|o| o.material == "marble" || o.material == "lamp" || floor(o));
        assert_eq!(file.objects.len(), 3);
        let open = Scene::from_json(&serde_json::to_string(&file).unwrap()).unwrap();
        let p = Plan::of(&open, 640, 480);
        assert!(!p.radiosity && p.to_string().contains("open scene"), "{p}");
    }

    #[test]
    fn radiosity_on_carries_a_still_key_light_s_bounce_with_no_emitter() {
        let marble = include_str!("../../assets/scenes/bunny-marble.json");
        let mut file: crate::scene::SceneFile = serde_json::from_str(marble).unwrap();
        file.radiosity = Some(crate::scene::RadiositySpec {
            mode: crate::scene::RadiosityMode::On,
            patch_size: Some(2.0),
            max_depth: 2,
            stop_fraction: 0.001,
        });
        let plan_of = |file: &crate::scene::SceneFile| {
            let scene = Scene::from_json(&serde_json::to_string(file).unwrap()).unwrap();
            (Plan::of(&scene, 640, 480), radiosity_sun(&scene))
        };
        let (p, sun) = plan_of(&file);
        assert!(p.radiosity && p.to_string().contains("first bounce"), "{p}");
        let sun = sun.unwrap();
        assert!(
            (sun.irradiance.x - 2.5).abs() < 1e-6 && (sun.to_light.length() - 1.0).abs() < 1e-6
        );
        // An orbiting or dark key light gives no bounce, and with no emitter nothing runs.
        file.light.orbit_deg_per_s = 10.0;
        let (p, sun) = plan_of(&file);
        assert!(!p.radiosity && sun.is_none(), "{p}");
        file.light.orbit_deg_per_s = 0.0;
        file.light.intensity = 0.0;
        assert!(!plan_of(&file).0.radiosity);
    }

    #[test]
    fn one_translucent_object_builds_the_pyramid_once() {
        let p = Plan::of(&Scene::builtin("bunny-marble").unwrap(), 640, 480);
        assert!(p.photon_pass && p.pyramid == Pyramid::Once);
        assert!(p.subsurface(0), "{p}");
    }

    #[test]
    fn mixed_scenes_plan_each_material() {
        let p = Plan::of(&Scene::builtin("materials").unwrap(), 640, 480);
        let get = |n: &str| p.materials.iter().find(|m| m.name == n).unwrap();
        assert!(
            get("marble").subsurface && !get("plaster").subsurface && !get("plaster").translucent
        );
        assert!(p.photon_pass);
    }

    #[test]
    fn an_animated_light_rebuilds_every_frame() {
        let json = include_str!("../../assets/scenes/bunny-marble.json").replace(
            "\"intensity\": 2.5",
            "\"intensity\": 2.5, \"orbit_deg_per_s\": 30",
        );
        let p = Plan::of(&Scene::from_json(&json).unwrap(), 640, 480);
        assert_eq!(
            p.pyramid,
            Pyramid::EveryFrame {
                orbit_deg_per_s: 30.0
            }
        );
        assert!(p.to_string().contains("rebuilt every frame"));
    }

    #[test]
    fn a_tiny_mean_free_path_at_a_coarse_resolution_needs_only_the_cheap_rung() {
        // 90% of skin's re-emitted light leaves within ~6.6 mm; seen on a 24-pixel-high frame a
        // pixel covers ~11 mm, so its translucency is invisible there.
        let p = Plan::of(&Scene::builtin("materials").unwrap(), 32, 24);
        let skin = p.materials.iter().find(|m| m.name == "skin").unwrap();
        assert!(skin.translucent && !skin.subsurface, "{p}");
        assert!(p
            .to_string()
            .contains("rung opaque only (its total diffuse reflectance)"));
        // At full HD the same material needs its subsurface light.
        let hd = Plan::of(&Scene::builtin("materials").unwrap(), 1920, 1080);
        assert!(
            hd.materials
                .iter()
                .find(|m| m.name == "skin")
                .unwrap()
                .subsurface,
            "{hd}"
        );
    }
}
