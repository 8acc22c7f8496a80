//! Frames in parts. A long frame (the reference rung at 4K runs for many seconds on a software
//! adapter, a foveated 4K frame for seconds) is split into submissions: the passes before
//! shading; when foveated, the sampling map; the shading in bands of rows (foveated: each
//! band's samples listed, then shaded); when foveated, the reconstruction in parts; and the
//! passes after it. The render thread runs other sessions' frames between the parts, so one
//! heavy frame delays them by at most one part.
//!
//! What a frame in flight owns lives in its stream's targets (pinned until it ends); what it
//! shares with other frames of its scene (shadow map, photon pyramid) must not be rebuilt for
//! another light meanwhile: [`Renderer::conflicts`] says when a frame would.

use std::collections::{BTreeMap, VecDeque};
use std::time::Instant;

use glam::Vec3;

use super::frame::{self, FramePlan};
use super::frame_uniform::frame_uniform;
use super::graph::Recorder;
use super::pass::photons::PhotonInputs;
use super::pass::pull_push;
use super::renderer::{not_loaded, Renderer, TargetKey};
use super::request::{FrameRequest, GpuLowPass, Readback, RenderedFrame, MAX_SIDE};
use super::uniforms::FrameUniform;
use super::RenderError;

/// Where a frame stands after [`Renderer::begin`] or [`Renderer::step`].
pub enum Progress {
    Done(RenderedFrame),
    Going(Box<FrameInFlight>),
}

/// A sliced frame between its parts.
pub struct FrameInFlight {
    req: FrameRequest,
    key: TargetKey,
    /// The parts still to run, next first (the suffix last).
    parts: VecDeque<Part>,
    to_light: Vec3,
    render_ms: f64,
    passes_ms: BTreeMap<String, f64>,
}

impl FrameInFlight {
    pub fn stream(&self) -> u64 {
        self.req.stream
    }
}

/// One submission of a frame.
#[derive(Clone, Copy)]
enum Part {
    Whole,
    Prefix,
    /// Foveated: the sampling map (and an empty list).
    Sampling,
    Rows(u32, u32),
    /// Foveated: part `k` of the reconstruction's `pull_push::PARTS`.
    Reconstruction(u32),
    Suffix,
}

/// The parts after the prefix of a frame shaded in `bands`: each of the longest fixed passes
/// of a foveated frame (at 3840×2160 on a software adapter the G-buffer, sampling and
/// reconstruction run 0.2–0.6 s each) is a part of its own.
fn later_parts(plan: &FramePlan, bands: Vec<(u32, u32)>) -> VecDeque<Part> {
    let mut parts = VecDeque::new();
    if plan.foveated {
        parts.push_back(Part::Sampling);
    }
    parts.extend(bands.into_iter().map(|(a, b)| Part::Rows(a, b)));
    if plan.foveated {
        let n = if plan.pull_push { pull_push::PARTS } else { 1 };
        parts.extend((0..n).map(Part::Reconstruction));
    }
    parts.push_back(Part::Suffix);
    parts
}

/// Splits `height` rows into `slices` bands of whole 8-row workgroups.
pub fn bands(height: u32, slices: u32) -> Vec<(u32, u32)> {
    let groups = height.div_ceil(8);
    let n = slices.clamp(1, groups.max(1));
    (0..n)
        .map(|i| {
            let first = (groups * i / n) * 8;
            let end = ((groups * (i + 1) / n) * 8).min(height);
            (first, end)
        })
        .filter(|(a, b)| b > a)
        .collect()
}

impl Renderer {
    /// Starts a frame: whole when `slices` is 1, else the passes before shading, leaving
    /// `slices` bands of shading and the rest to [`Renderer::step`].
    pub fn begin(&mut self, req: &FrameRequest, slices: u32) -> Result<Progress, RenderError> {
        let (w, h) = (req.width, req.height);
        if w == 0 || h == 0 || w > MAX_SIDE || h > MAX_SIDE {
            return Err(RenderError::Size {
                width: w,
                height: h,
                max: MAX_SIDE,
            });
        }
        self.load_scene(&req.scene)?;
        let started = Instant::now();
        let key: TargetKey = (req.stream, req.scene.clone(), w, h);
        let ti = self.target_index(req.stream, &req.scene, w, h)?;
        self.timer.begin_frame();
        let (photon_encoder, inputs) = self.prepare_scene(req, ti)?;
        self.write_uniform(req, ti, inputs)?;
        let sliced = slices > 1;
        let part = if sliced { Part::Prefix } else { Part::Whole };
        let submission = self.submit(req, ti, part, photon_encoder)?;
        let render_ms = started.elapsed().as_secs_f64() * 1e3;
        let passes_ms = self.timer.read(&self.gpu.device, submission)?;
        let mut going = FrameInFlight {
            req: req.clone(),
            key: key.clone(),
            parts: if sliced {
                let plan = FramePlan::of(&req.settings, w, h, self.targets[ti].1.needs_dipole);
                later_parts(&plan, bands(h, slices))
            } else {
                VecDeque::new()
            },
            to_light: inputs.to_light,
            render_ms,
            passes_ms,
        };
        if sliced {
            self.pinned.push(key);
            return Ok(Progress::Going(Box::new(going)));
        }
        self.finish(&mut going, ti).map(Progress::Done)
    }

    /// Runs a sliced frame's next part; the last one returns the frame.
    pub fn step(&mut self, f: &mut FrameInFlight) -> Result<Option<RenderedFrame>, RenderError> {
        let Some(ti) = self.targets.iter().position(|(k, _)| *k == f.key) else {
            return Err(RenderError::Gpu(format!(
                "stream {}'s targets were released mid-frame",
                f.req.stream
            )));
        };
        let started = Instant::now();
        self.timer.begin_frame();
        let part = f.parts.pop_front().unwrap_or(Part::Suffix);
        let submission = self.submit(&f.req, ti, part, None)?;
        for (pass, ms) in self.timer.read(&self.gpu.device, submission)? {
            *f.passes_ms.entry(pass).or_default() += ms;
        }
        f.render_ms += started.elapsed().as_secs_f64() * 1e3;
        if !matches!(part, Part::Suffix) {
            return Ok(None);
        }
        self.pinned.retain(|k| *k != f.key);
        self.finish(f, ti).map(Some)
    }

    /// Lets go of a sliced frame nobody wants any more (its session left).
    pub fn abandon(&mut self, f: FrameInFlight) {
        self.pinned.retain(|k| *k != f.key);
    }

    /// Whether running `req` now would change what the sliced frame `f` reads from its scene:
    /// the shadow map and photon pyramid are built for one light direction at a time.
    pub fn conflicts(&self, req: &FrameRequest, f: &FrameInFlight) -> bool {
        if req.scene != f.req.scene {
            return false;
        }
        self.loaded(&req.scene)
            .is_ok_and(|sg| req.light_direction(&sg.scene) != f.to_light)
    }

    fn write_uniform(
        &mut self,
        req: &FrameRequest,
        ti: usize,
        inputs: PhotonInputs,
    ) -> Result<(), RenderError> {
        let sg = self.loaded(&req.scene)?;
        let pyramid_ready = sg
            .photons
            .as_ref()
            .is_some_and(|m| m.built_for == Some(inputs));
        let shadow_ready = sg
            .shadow
            .as_ref()
            .is_some_and(|m| m.built_for == Some(inputs.to_light));
        let t = &self.targets[ti].1;
        let camera = req.camera.unwrap_or(sg.scene.file.camera);
        let uniform = frame_uniform(
            &sg.scene,
            &camera,
            req,
            t,
            inputs.to_light,
            pyramid_ready,
            shadow_ready,
        );
        let buffer = t.buffer("frame.uniform")?;
        self.gpu
            .queue
            .write_buffer(buffer, 0, bytemuck::bytes_of(&uniform));
        self.targets[ti].1.mode = uniform.mode;
        self.targets[ti].1.rung = uniform.rung;
        Ok(())
    }

    /// Records one part, submits it and waits for it.
    fn submit(
        &mut self,
        req: &FrameRequest,
        ti: usize,
        part: Part,
        photon_encoder: Option<wgpu::CommandBuffer>,
    ) -> Result<wgpu::SubmissionIndex, RenderError> {
        let (i420, low_pass) = (self.wants_i420(req), self.gpu_low_pass(req));
        // Field by field: the targets, pipelines and timer are borrowed mutably below.
        let sg = self
            .scenes
            .get(&req.scene)
            .ok_or_else(|| not_loaded(&req.scene))?;
        let (device, queue) = (&self.gpu.device, &self.gpu.queue);
        let t = &mut self.targets[ti].1;
        if matches!(part, Part::Whole | Part::Prefix) {
            // This part overwrites the saliency the last frame kept: until the frame finishes,
            // no later frame may take what is there for the last frame's.
            t.prev_settings = None;
        }
        if let Part::Rows(a, b) = part {
            let offset = std::mem::offset_of!(FrameUniform, shade_rows) as u64;
            let buffer = t.buffer("frame.uniform")?;
            queue.write_buffer(buffer, offset, bytemuck::cast_slice(&[a, b]));
        }
        let mut plan = FramePlan::of(&req.settings, req.width, req.height, t.needs_dipole);
        plan.i420 = i420;
        plan.low_pass = low_pass;
        let scope = device.push_error_scope(wgpu::ErrorFilter::Validation);
        let mut encoder = device.create_command_encoder(&wgpu::CommandEncoderDescriptor {
            label: Some("frame"),
        });
        let mut recorder = Recorder {
            device,
            queue,
            encoder: &mut encoder,
            pipelines: &mut self.pipelines,
            resources: &t.resources,
            binds: &mut t.binds,
            // Later parts read the ports the first part set (`frame.color`).
            routes: match part {
                Part::Whole | Part::Prefix => Default::default(),
                _ => t.routes.clone(),
            },
            timer: &mut self.timer,
            size: (req.width, req.height),
            mode: t.mode,
            scene_kinds: sg.kinds,
            rung: t.rung,
        };
        match part {
            Part::Whole => frame::record(&mut recorder, &plan, &sg.mesh)?,
            Part::Prefix => frame::record_prefix(&mut recorder, &plan, &sg.mesh)?,
            Part::Sampling => frame::record_sampling(&mut recorder)?,
            Part::Rows(a, b) => frame::record_rows(&mut recorder, &plan, a, b)?,
            Part::Reconstruction(k) => frame::record_reconstruction(&mut recorder, &plan, Some(k))?,
            Part::Suffix => frame::record_suffix(&mut recorder, &plan)?,
        }
        t.routes = recorder.routes;
        self.timer.resolve(&mut encoder);
        let submission = queue.submit(photon_encoder.into_iter().chain([encoder.finish()]));
        let waited = device.poll(wgpu::PollType::Wait {
            submission_index: Some(submission.clone()),
            timeout: None,
        });
        // A validation error fails the submission too: it, not the wait, says what went wrong.
        if let Some(e) = pollster::block_on(scope.pop()) {
            return Err(RenderError::Gpu(e.to_string()));
        }
        waited.map_err(|e| RenderError::Gpu(format!("waiting for the frame: {e}")))?;
        if matches!(part, Part::Whole | Part::Suffix) {
            let camera = req.camera.unwrap_or(sg.scene.file.camera);
            t.prev_view_proj = camera.view_proj(req.width, req.height);
            t.prev_eye = Vec3::from(camera.eye);
            t.has_history = true;
            t.prev_settings = Some(req.settings.clone());
            t.frame_index = t.frame_index.wrapping_add(1);
        }
        Ok(submission)
    }

    /// Reads the finished frame back.
    /// Whether a frame is converted to I420 on the GPU and read back so (see `Readback`).
    fn wants_i420(&self, req: &FrameRequest) -> bool {
        let even = req.width.is_multiple_of(2) && req.height.is_multiple_of(2);
        let gpu = !self.is_software();
        even && match req.readback {
            Readback::Rgba => false,
            Readback::I420Preferred => gpu,
            Readback::I420 => true,
        }
    }

    /// The low-pass the renderer does for this frame (see `GpuLowPass`).
    fn gpu_low_pass(&self, req: &FrameRequest) -> Option<super::pass::low_pass::Filter> {
        let low_pass = match req.low_pass {
            GpuLowPass::Off => return None,
            GpuLowPass::Preferred(p) if !self.is_software() || self.wants_i420(req) => p,
            GpuLowPass::Preferred(_) => return None,
            GpuLowPass::Always(p) => p,
        };
        Some(super::pass::low_pass::Filter {
            low_pass,
            viewing: crate::viewing::Viewing::new(req.display, req.width, req.height),
            gaze: req.gaze.map(f64::from),
        })
    }

    fn finish(&mut self, f: &mut FrameInFlight, ti: usize) -> Result<RenderedFrame, RenderError> {
        let (w, h) = (f.req.width, f.req.height);
        let started = Instant::now();
        let i420 = self.wants_i420(&f.req);
        let t = &self.targets[ti].1;
        let (image, count) = t.read_back(&self.gpu.device, &self.gpu.queue, i420)?;
        let (rgba, i420) = if i420 {
            (Vec::new(), Some(super::pass::i420::unpad(&image, w, h)))
        } else {
            (image, None)
        };
        let readback_ms = started.elapsed().as_secs_f64() * 1e3;
        let sampled = if f.req.settings.foveation.enabled {
            f64::from(count) / (f64::from(w) * f64::from(h))
        } else {
            1.0
        };
        Ok(RenderedFrame {
            width: w,
            height: h,
            rgba,
            i420,
            low_passed: self.gpu_low_pass(&f.req).is_some(),
            sampled,
            render_ms: f.render_ms,
            readback_ms,
            passes_ms: std::mem::take(&mut f.passes_ms),
            radiosity: self.scenes.get(&f.req.scene).and_then(|s| s.gi),
            unfoveated: None,
        })
    }
}

#[cfg(test)]
mod tests {
    use super::bands;

    #[test]
    fn bands_cover_every_row_once_in_whole_workgroups() {
        for (h, n) in [(2160, 40), (480, 3), (7, 5), (8, 1), (1, 100), (2161, 7)] {
            let b = bands(h, n);
            assert_eq!(b.first().map(|x| x.0), Some(0), "{h} {n}");
            assert_eq!(b.last().map(|x| x.1), Some(h), "{h} {n}");
            for w in b.windows(2) {
                assert_eq!(w[0].1, w[1].0, "bands touch: {h} {n}");
            }
            for (a, e) in &b {
                assert!(e > a && a % 8 == 0, "{h} {n}: {a}..{e}");
            }
            assert!(b.len() as u32 <= n.max(1));
        }
    }
}
