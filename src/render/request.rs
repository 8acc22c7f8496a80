//! What the renderer is asked for and what it gives back: plain data, shared by the renderer,
//! its thread and every caller.

use glam::Vec3;

use crate::encode::foveated::LowPass;
use crate::foveation::rank_map;
use crate::radiosity::Progress;
use crate::scene::Camera;
use crate::settings::RenderSettings;
use crate::viewing::Display;

/// Largest side a frame may have; matches wgpu's default 2-D texture limit.
pub const MAX_SIDE: u32 = 8192;
/// Smallest effective ξ: the rank-0 pixel of every 64×64 blue-noise tile is always shaded.
pub const MIN_XI: f32 = 1.0 / (rank_map::TILE * rank_map::TILE) as f32;
/// Pupil diameter assumed when a sample carries none: a typical indoor value.
pub const DEFAULT_PUPIL_MM: f32 = 4.0;

/// Everything that decides one frame's pixels.
#[derive(Debug, Clone, PartialEq)]
pub struct FrameRequest {
    pub scene: String,
    pub width: u32,
    pub height: u32,
    /// Normalised gaze (top-left origin) the frame is foveated around.
    pub gaze: [f32; 2],
    /// Draw the gaze marker at `gaze`.
    pub marker: bool,
    pub pupil_mm: f32,
    pub display: Display,
    pub settings: RenderSettings,
    /// Overrides the scene light's direction (unit vector towards the light).
    pub to_light: Option<Vec3>,
    /// Overrides the scene camera.
    pub camera: Option<Camera>,
    /// Whose frame sequence this is: history (reprojection) is kept per stream.
    pub stream: u64,
    /// Seconds into the stream, for animated lights.
    pub time_s: f64,
    /// How the frame comes back to host memory.
    pub readback: Readback,
    /// Foveated encoding's low-pass, done before the readback where the renderer may.
    pub low_pass: GpuLowPass,
}

/// The image a frame is read back as.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub enum Readback {
    /// Packed RGBA8.
    #[default]
    Rgba,
    /// I420 planes (what H.264 encodes) where the GPU converts faster than the encoder thread
    /// would: not on a CPU adapter, where the `i420` pass took 56 ms a 720p frame against a few
    /// ms on the CPU (measured with lavapipe), and only at even sizes; RGBA otherwise.
    I420Preferred,
    /// I420 planes at even sizes whatever the adapter (tests of the pass).
    I420,
}

/// Whether the renderer low-passes the periphery for foveated encoding
/// (`encode::foveated`) before the frame is read back.
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub enum GpuLowPass {
    /// No: the encoder does it if the session asked.
    #[default]
    Off,
    /// Where the adapter is a GPU, or where the frame is read back as I420 (which the CPU
    /// filter cannot take). On a CPU adapter the pass shares the render thread's cores, where
    /// the encoder thread runs beside it.
    Preferred(LowPass),
    /// Whatever the adapter (tests of the pass).
    Always(LowPass),
}

impl FrameRequest {
    /// Unit vector towards the key light for this frame: the request's override, or the
    /// scene's light at the request's time (animated lights orbit).
    pub fn light_direction(&self, scene: &crate::scene::Scene) -> Vec3 {
        self.to_light
            .and_then(|l| l.try_normalize())
            .unwrap_or_else(|| scene.file.light.to_light_at(self.time_s))
    }

    pub fn new(scene: &str, width: u32, height: u32) -> FrameRequest {
        FrameRequest {
            scene: scene.to_string(),
            width,
            height,
            gaze: [0.5, 0.5],
            marker: false,
            pupil_mm: DEFAULT_PUPIL_MM,
            display: Display::default(),
            settings: RenderSettings::default(),
            to_light: None,
            camera: None,
            stream: 0,
            time_s: 0.0,
            readback: Readback::Rgba,
            low_pass: GpuLowPass::Off,
        }
    }
}

/// A rendered frame in host memory.
#[derive(Debug, Clone)]
pub struct RenderedFrame {
    pub width: u32,
    pub height: u32,
    /// Tightly packed RGBA8, sRGB-encoded, top row first (empty when `i420` holds the frame).
    pub rgba: Vec<u8>,
    /// The frame as I420 planes (Y, U, V, tight), when the request asked for them.
    pub i420: Option<Vec<u8>>,
    /// The renderer low-passed the periphery (the request's `low_pass`), so the encoder must not.
    pub low_passed: bool,
    /// Fraction of the frame's pixels the shading pass ran for.
    pub sampled: f64,
    pub render_ms: f64,
    pub readback_ms: f64,
    /// GPU milliseconds per pass label (empty without timestamp queries).
    pub passes_ms: std::collections::BTreeMap<String, f64>,
    /// Where the scene's radiosity solve stood when this frame used it; `None` without one.
    pub radiosity: Option<Progress>,
    /// Why a foveated request was shaded whole (see `foveation_policy`); `None` otherwise.
    pub unfoveated: Option<String>,
}

/// Intermediate images of the last frame of a stream, for tests and diagnostics.
#[derive(Debug, Clone)]
pub struct Inspection {
    pub probability: Vec<f32>,
    pub flags: Vec<u32>,
    pub seeds: Vec<u32>,
    pub nearest: Vec<u32>,
    pub color: Vec<[f32; 4]>,
    pub resolved: Vec<[f32; 4]>,
    pub normal_distance: Vec<[f32; 4]>,
    /// G-buffer albedo (RGBA8: rgb, material id in alpha).
    pub albedo: Vec<[u8; 4]>,
    /// Photons (pyramid level 0) as [x, y, z, extent, Φr, Φg, Φb, weight]; empty without any.
    pub photons: Vec<[f32; 8]>,
    /// Workgroups the last pull-push ran, from its indirect dispatches' counts: the fill's and
    /// the pull from the pixels' (32×32 pixels each), level 1's push (32×32 cells).
    pub fill_tiles: u32,
    pub pull_tiles: u32,
    pub level1_tiles: u32,
}
