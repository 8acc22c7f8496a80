//! Frames rendered straight on a `Renderer` (no server), and their intermediate images.

use fovea::render::{FrameRequest, Inspection, Renderer};
use fovea::settings::{Preset, RenderSettings};

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
