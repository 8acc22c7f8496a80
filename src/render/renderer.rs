use std::collections::HashMap;
use std::time::Instant;

use glam::Vec3;

use super::pass::forward::{ForwardPass, Lighting, SceneBuffers};
use super::pass::marker::MarkerPass;
use super::targets::FrameTargets;
use super::{Gpu, RenderError};
use crate::optics::color::srgb8_to_linear;
use crate::scene::Scene;

/// Largest side a frame may have; matches wgpu's default 2-D texture limit.
pub const MAX_SIDE: u32 = 8192;
/// Target sets kept alive for reuse; sessions rarely use more than a couple of sizes.
const TARGET_CACHE: usize = 4;

/// Everything that decides one frame's pixels.
#[derive(Debug, Clone, PartialEq)]
pub struct FrameRequest {
    pub scene: String,
    pub width: u32,
    pub height: u32,
    /// Normalised gaze (top-left origin) at which the marker is drawn; `None` draws no marker.
    pub gaze: Option<[f32; 2]>,
    /// Overrides the scene light's direction (unit vector towards the light).
    pub to_light: Option<Vec3>,
}

impl FrameRequest {
    pub fn new(scene: &str, width: u32, height: u32) -> FrameRequest {
        FrameRequest { scene: scene.to_string(), width, height, gaze: None, to_light: None }
    }
}

/// A rendered frame in host memory.
#[derive(Debug, Clone)]
pub struct RenderedFrame {
    pub width: u32,
    pub height: u32,
    /// Tightly packed RGBA8, sRGB-encoded, top row first.
    pub rgba: Vec<u8>,
    pub render_ms: f64,
    pub readback_ms: f64,
}

/// Owns the GPU and everything on it. Not shared: one thread drives it (see `RenderThread`).
pub struct Renderer {
    gpu: Gpu,
    forward: ForwardPass,
    marker: MarkerPass,
    scenes: HashMap<String, (Scene, SceneBuffers)>,
    targets: Vec<FrameTargets>,
}

impl Renderer {
    pub fn new() -> Result<Renderer, RenderError> {
        Ok(Renderer::with_gpu(Gpu::new()?))
    }

    pub fn with_gpu(gpu: Gpu) -> Renderer {
        let forward = ForwardPass::new(&gpu.device);
        let marker = MarkerPass::new(&gpu.device);
        Renderer { gpu, forward, marker, scenes: HashMap::new(), targets: Vec::new() }
    }

    pub fn adapter(&self) -> String {
        self.gpu.summary()
    }

    /// Loads a scene onto the GPU ahead of its first frame (otherwise the first frame does it).
    pub fn load_scene(&mut self, name: &str) -> Result<&Scene, RenderError> {
        if !self.scenes.contains_key(name) {
            let scene = Scene::builtin(name)?;
            let buffers = self.forward.upload(&self.gpu.device, &scene);
            tracing::info!(scene = name, triangles = scene.mesh.triangle_count(), "scene loaded");
            self.scenes.insert(name.to_string(), (scene, buffers));
        }
        let (scene, _) = &self.scenes[name];
        Ok(scene)
    }

    pub fn render(&mut self, req: &FrameRequest) -> Result<RenderedFrame, RenderError> {
        let (w, h) = (req.width, req.height);
        if w == 0 || h == 0 || w > MAX_SIDE || h > MAX_SIDE {
            return Err(RenderError::Size { width: w, height: h, max: MAX_SIDE });
        }
        self.load_scene(&req.scene)?;
        let started = Instant::now();
        let ti = self.target_index(w, h);
        let (scene, buffers) = &self.scenes[&req.scene];
        let targets = &self.targets[ti];
        let device = &self.gpu.device;
        let queue = &self.gpu.queue;

        let scope = device.push_error_scope(wgpu::ErrorFilter::Validation);
        let mut encoder =
            device.create_command_encoder(&wgpu::CommandEncoderDescriptor { label: Some("frame") });
        let mut lighting = Lighting::of(scene);
        if let Some(l) = req.to_light.and_then(|l| l.try_normalize()) {
            lighting.to_light = l;
        }
        let background = Vec3::from(scene.file.background_srgb.map(srgb8_to_linear));
        let view_proj = scene.file.camera.view_proj(w, h);
        self.forward.encode(
            queue,
            &mut encoder,
            &targets.color_view,
            &targets.depth_view,
            buffers,
            view_proj,
            &lighting,
            background,
        );
        if let Some(g) = req.gaze {
            self.marker.encode(queue, &mut encoder, &targets.color_view, (w, h), g);
        }
        let submission = queue.submit([encoder.finish()]);
        device
            .poll(wgpu::PollType::Wait { submission_index: Some(submission), timeout: None })
            .map_err(|e| RenderError::Gpu(format!("waiting for the frame: {e}")))?;
        if let Some(e) = pollster::block_on(scope.pop()) {
            return Err(RenderError::Gpu(e.to_string()));
        }
        let render_ms = started.elapsed().as_secs_f64() * 1e3;

        let started = Instant::now();
        let rgba = targets.read_back(device, queue)?;
        let readback_ms = started.elapsed().as_secs_f64() * 1e3;
        Ok(RenderedFrame { width: w, height: h, rgba, render_ms, readback_ms })
    }

    /// Index of the targets for this size, creating them (and evicting the oldest) if needed.
    fn target_index(&mut self, w: u32, h: u32) -> usize {
        if let Some(i) = self.targets.iter().position(|t| t.width == w && t.height == h) {
            return i;
        }
        if self.targets.len() >= TARGET_CACHE {
            self.targets.remove(0);
        }
        self.targets.push(FrameTargets::new(&self.gpu.device, w, h));
        self.targets.len() - 1
    }
}
