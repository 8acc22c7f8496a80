//! A model file as a scene of its own (`fovea render --model`, a `.glb` in a served folder):
//! its lights and camera where it has them, otherwise a default key light and a camera that
//! frames its bounds.

use std::path::Path;

use glam::Vec3;

use super::build::{self, Loaded};
use super::folder::Folder;
use super::{Camera, Light, LightSpec, SceneError, SceneFile};

/// Where the default key light comes from (towards it): above, right and in front.
const DEFAULT_TO_LIGHT: [f32; 3] = [0.4, 0.8, 0.5];
/// Plain meshes have no units: their bounding box diagonal is taken as this many mm.
const PLAIN_MESH_DIAGONAL_MM: f64 = 200.0;

pub fn scene_of_model(path: &Path, folder: &Folder) -> Result<Scene, SceneError> {
    let name = path
        .file_stem()
        .map(|s| s.to_string_lossy().into_owned())
        .unwrap_or_else(|| "model".into());
    let file_name = path
        .file_name()
        .map(|s| s.to_string_lossy().into_owned())
        .unwrap_or_default();
    let fail = |message: String| SceneError::MeshFile {
        scene: name.clone(),
        mesh: file_name.clone(),
        message,
    };
    let loaded = build::load_model(path, folder).map_err(fail)?;
    let base = path.parent().unwrap_or(folder.root());
    scene_of_loaded(&name, &file_name, loaded, Some((folder, base)))
}

/// A built-in glTF model (embedded, no files beside it) as a scene.
pub fn builtin_model(name: &str, file_name: &str, bytes: &[u8]) -> Result<Scene, SceneError> {
    let imported = super::gltf::import_bytes(bytes, Path::new(""), None).map_err(|e| {
        SceneError::MeshFile {
            scene: name.to_string(),
            mesh: file_name.to_string(),
            message: e.to_string(),
        }
    })?;
    scene_of_loaded(name, file_name, Loaded::Gltf(imported), None)
}

fn scene_of_loaded(
    name: &str,
    file_name: &str,
    mut loaded: Loaded,
    at: build::Location,
) -> Result<Scene, SceneError> {
    let fail = |message: String| SceneError::MeshFile {
        scene: name.to_string(),
        mesh: file_name.to_string(),
        message,
    };
    let (lo, hi) = bounds(&loaded);
    let unlit = match &loaded {
        Loaded::Gltf(g) => g.lights.is_empty(),
        Loaded::Plain(_) => false,
    };
    let (mut file, lights) = match &loaded {
        Loaded::Gltf(g) => {
            // glTF is in metres; its lights in lux and candela, scaled so the key light (or
            // the strongest light at the model's centre) gives irradiance 1.
            let centre = (lo + hi) * 0.5;
            let key = g.lights.iter().find_map(|l| match l {
                LightSpec::Directional {
                    to_light,
                    color,
                    intensity,
                } => Some((*to_light, *color, *intensity)),
                _ => None,
            });
            let strongest = g
                .lights
                .iter()
                .map(|l| irradiance_at(l, centre))
                .fold(0.0f32, f32::max);
            let (light, scale) = match key {
                Some((to_light, color, lux)) if lux > 0.0 => {
                    (light(to_light, color, 1.0), 1.0 / lux)
                }
                _ if strongest > 0.0 => (light(DEFAULT_TO_LIGHT, [1.0; 3], 0.3), 1.0 / strongest),
                _ => (light(DEFAULT_TO_LIGHT, [1.0; 3], 1.0), 1.0),
            };
            let mut skipped_key = key.is_some();
            let lights: Vec<LightSpec> = g
                .lights
                .iter()
                .filter(|l| {
                    // The first directional light became the key light.
                    let is_key = skipped_key && matches!(l, LightSpec::Directional { .. });
                    if is_key {
                        skipped_key = false;
                    }
                    !is_key
                })
                .map(|l| l.scaled(scale))
                .collect();
            let camera = g.camera.map(|c| aim(c, centre, (hi - lo).length()));
            (
                scene_file(name, 1000.0, light, camera.unwrap_or_else(|| frame(lo, hi))),
                lights,
            )
        }
        Loaded::Plain(_) => {
            let diagonal = f64::from((hi - lo).length()).max(1e-9);
            let mut f = scene_file(
                name,
                PLAIN_MESH_DIAGONAL_MM / diagonal,
                light(DEFAULT_TO_LIGHT, [1.0; 3], 1.0),
                frame(lo, hi),
            );
            f.materials.insert(
                "surface".into(),
                serde_json::from_value(serde_json::json!({
                    "kind": "opaque", "albedo": [0.8, 0.8, 0.8], "roughness": 0.5, "double_sided": true
                }))
                .map_err(|e| fail(e.to_string()))?,
            );
            (f, Vec::new())
        }
    };
    file.objects[0].mesh = file_name.to_string();
    if matches!(loaded, Loaded::Plain(_)) {
        file.objects[0].material = "surface".into();
    }
    file.lights = lights;
    // The file's lights are in the scene already (scaled, the key one taken out).
    if let Loaded::Gltf(g) = &mut loaded {
        g.lights.clear();
    }
    let json = serde_json::to_string(&file).map_err(|e| fail(e.to_string()))?;
    let mut scene = build::build_with(&json, at, Some((file_name.to_string(), loaded)))?;
    // A room lit only by its own emissive surfaces (a Cornell box as glTF): radiosity lights
    // it, so no default sun shines through its walls and no sky fills it.
    if unlit && scene.has_emitter() && super::plan::enclosure(&scene) >= super::plan::ENCLOSED {
        scene.file.light.intensity = 0.0;
        scene.file.ambient = 0.0;
        scene.file.description =
            format!("{name}, as loaded from its file: lit by its emissive surfaces");
    }
    Ok(scene)
}

use super::Scene;

fn light(to_light: [f32; 3], color: [f32; 3], intensity: f32) -> Light {
    Light {
        to_light,
        color,
        intensity,
        orbit_deg_per_s: 0.0,
    }
}

fn scene_file(name: &str, mm_per_unit: f64, light: Light, camera: Camera) -> SceneFile {
    SceneFile {
        name: name.to_string(),
        description: format!("{name}, as loaded from its file"),
        mm_per_unit,
        ambient: 0.1,
        background_srgb: [38, 42, 50],
        light,
        camera,
        materials: Default::default(),
        objects: vec![super::ObjectSpec {
            mesh: String::new(),
            corners: None,
            material: String::new(),
            translate: [0.0; 3],
            scale: 1.0,
            rotate_y_deg: 0.0,
        }],
        lights: Vec::new(),
        radiosity: None,
    }
}

/// A glTF camera made ready to orbit: its target (glTF has none) is the point on its view
/// axis nearest the model's centre, its up the world's +Y unless the file rolls the camera,
/// and a missing far plane well beyond the model.
fn aim(mut c: Camera, centre: Vec3, size: f32) -> Camera {
    let eye = Vec3::from(c.eye);
    let forward = (Vec3::from(c.target) - eye).normalize_or(-Vec3::Z);
    let along = (centre - eye).dot(forward).max(2.0 * c.near.max(1e-4));
    c.target = (eye + forward * along).into();
    let right = forward.cross(Vec3::from(c.up));
    if right.y.abs() < 1e-3 && forward.cross(Vec3::Y).length() > 1e-3 {
        c.up = [0.0, 1.0, 0.0];
    }
    if !(c.far > c.near) {
        c.far = c.near.max(1e-3) + 100.0 * size.max(1e-3);
    }
    c
}

/// Irradiance a light gives a surface facing it at `p`, in the file's units.
fn irradiance_at(l: &LightSpec, p: Vec3) -> f32 {
    match l {
        LightSpec::Directional { intensity, .. } => *intensity,
        LightSpec::Point {
            position,
            intensity,
            ..
        }
        | LightSpec::Spot {
            position,
            intensity,
            ..
        } => intensity / Vec3::from(*position).distance_squared(p).max(1e-6),
    }
}

fn bounds(loaded: &Loaded) -> (Vec3, Vec3) {
    let points: Box<dyn Iterator<Item = &Vec3>> = match loaded {
        Loaded::Plain(m) => Box::new(m.positions.iter()),
        Loaded::Gltf(g) => Box::new(g.parts.iter().flat_map(|p| p.mesh.positions.iter())),
    };
    points.fold(
        (Vec3::splat(f32::MAX), Vec3::splat(f32::MIN)),
        |(lo, hi), &p| (lo.min(p), hi.max(p)),
    )
}

/// A camera looking at the box `lo..hi` from the front, a little above and to the right, far
/// enough back that its bounding sphere fills about 80% of a 40° view.
pub fn frame(lo: Vec3, hi: Vec3) -> Camera {
    let centre = (lo + hi) * 0.5;
    let radius = ((hi - lo).length() * 0.5).max(1e-4);
    let fov_y_deg = 40.0f32;
    let distance = radius / (fov_y_deg.to_radians() * 0.5).sin() / 0.8;
    let dir = Vec3::new(0.35, 0.3, 1.0).normalize();
    Camera {
        eye: (centre + dir * distance).into(),
        target: centre.into(),
        up: [0.0, 1.0, 0.0],
        fov_y_deg,
        near: (distance - radius * 2.0).max(distance * 0.01),
        far: distance + radius * 4.0,
    }
}
