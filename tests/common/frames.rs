//! Frames rendered straight on a `Renderer` (no server), and their intermediate images.

use fovea::render::{FrameRequest, Inspection, Renderer};
use fovea::scene::Scene;
use fovea::settings::{Preset, RenderSettings};
use serde_json::json;

/// The renderer on the software adapter; GPU tests fail, never skip, without one.
pub fn renderer() -> Renderer {
    Renderer::new().unwrap_or_else(|e| panic!("GPU tests need an adapter: {e}"))
}

/// A frame of the bunny scene at `preset`, gaze at `gaze`.
pub fn foveated(preset: &str, w: u32, h: u32, gaze: [f32; 2]) -> FrameRequest {
    let mut r = FrameRequest::new("bunny", w, h);
    r.settings = RenderSettings::of(Preset::from_name(preset).unwrap());
    r.gaze = gaze;
    r
}

/// The intermediate images of `req`'s stream after its last frame.
pub fn inspect(r: &Renderer, req: &FrameRequest) -> Inspection {
    r.inspect(req.stream, &req.scene, req.width, req.height)
        .unwrap()
}

/// A `full`-preset frame of `scene` without the marker, on `stream`.
pub fn full(scene: &str, w: u32, h: u32, stream: u64) -> FrameRequest {
    let mut r = FrameRequest::new(scene, w, h);
    r.settings = RenderSettings::of(Preset::Full);
    r.marker = false;
    r.stream = stream;
    r
}

/// Renders `req` and returns its stream's intermediate images.
pub fn render(r: &mut Renderer, req: &FrameRequest) -> Inspection {
    r.render(req).unwrap();
    r.inspect(req.stream, &req.scene, req.width, req.height)
        .unwrap()
}

/// A scene file with a key light of intensity 1 towards `to_light`, black background.
pub fn scene_json(
    name: &str,
    objects: serde_json::Value,
    materials: serde_json::Value,
    camera: serde_json::Value,
    to_light: [f32; 3],
    ambient: f32,
) -> Scene {
    Scene::from_json(
        &json!({
            "name": name, "ambient": ambient, "background_srgb": [0, 0, 0],
            "light": {"to_light": to_light, "color": [1, 1, 1], "intensity": 1},
            "camera": camera, "materials": materials, "objects": objects
        })
        .to_string(),
    )
    .unwrap()
}
