//! The renderer: owns the GPU, the pipelines, every loaded scene and each stream's targets, and
//! turns a [`FrameRequest`] into pixels. The frame's passes are recorded by `frame.rs`.

use std::collections::HashMap;
use std::time::Instant;

use glam::Vec3;

use super::frame::{self, FramePlan};
use super::frame_uniform::frame_uniform;
use super::gi::upload_radiosity;
use super::graph::{Pipelines, Recorder, Resources};
use super::pass::photons::{PhotonInputs, PhotonPass, SIDE as PHOTON_SIDE};
use super::pass::shadow::shadow_view;
use super::request::{FrameRequest, Inspection, RenderedFrame, MAX_SIDE};
use super::scene_gpu::SceneGpu;
use super::targets::{map_read, FrameTargets};
use super::timer::PassTimer;
use super::{gpu, Gpu, RenderError};
use crate::foveation::rank_map;
use crate::scene::{Plan, Scene};
use crate::settings::Rung;

/// Target sets (one per stream and size) kept alive; the oldest goes first.
const TARGET_CACHE: usize = 8;

type TargetKey = (u64, String, u32, u32);

/// Owns the GPU and everything on it. Not shared: one thread drives it (see `RenderThread`).
pub struct Renderer {
    gpu: Gpu,
    pipelines: Pipelines,
    photon_pass: PhotonPass,
    /// Shared by every stream: the blue-noise rank map.
    shared: Resources,
    scenes: HashMap<String, SceneGpu>,
    targets: Vec<(TargetKey, FrameTargets)>,
    timer: PassTimer,
    pyramid_builds: u64,
    /// The radiosity solves of loaded scenes, shared with `RenderHandle` for `/readyz`.
    solves: Solves,
    /// Where scenes come from by name.
    catalog: crate::scene::Catalog,
}

/// Radiosity solves the renderer's scenes use, readable from any thread.
pub type Solves = std::sync::Arc<std::sync::Mutex<Vec<crate::radiosity::RadiosityHandle>>>;

impl Renderer {
    pub fn new() -> Result<Renderer, RenderError> {
        Ok(Renderer::with_gpu(Gpu::new()?))
    }

    pub fn with_gpu(gpu: Gpu) -> Renderer {
        let d = &gpu.device;
        let mut pipelines = Pipelines::new(d);
        let photon_pass = PhotonPass::new(d, &mut pipelines);
        let side = rank_map::TILE;
        let rank = gpu::texture_2d(
            d,
            "sampling.rank_map",
            (side, side),
            wgpu::TextureFormat::R32Float,
            wgpu::TextureUsages::TEXTURE_BINDING | wgpu::TextureUsages::COPY_DST,
        );
        gpu.queue.write_texture(
            rank.as_image_copy(),
            bytemuck::cast_slice(&rank_map::thresholds()),
            wgpu::TexelCopyBufferLayout {
                offset: 0,
                bytes_per_row: Some(side * 4),
                rows_per_image: Some(side),
            },
            wgpu::Extent3d {
                width: side,
                height: side,
                depth_or_array_layers: 1,
            },
        );
        let mut shared = Resources::default();
        shared.texture("sampling.rank_map", rank);
        let timer = PassTimer::new(d, &gpu.queue);
        Renderer {
            pipelines,
            photon_pass,
            shared,
            gpu,
            scenes: HashMap::new(),
            targets: Vec::new(),
            timer,
            pyramid_builds: 0,
            solves: Solves::default(),
            catalog: crate::scene::Catalog::builtin(),
        }
    }

    pub fn adapter(&self) -> String {
        self.gpu.summary()
    }

    /// Whether per-pass GPU times are measured (timestamp queries).
    pub fn timestamps(&self) -> bool {
        self.timer.enabled()
    }

    /// Sets where scenes come from by name (built in, and `serve --scenes` folders).
    pub fn set_catalog(&mut self, catalog: crate::scene::Catalog) {
        self.catalog = catalog;
    }

    /// Loads a scene onto the GPU ahead of its first frame (otherwise the first frame does it).
    pub fn load_scene(&mut self, name: &str) -> Result<&Scene, RenderError> {
        if !self.scenes.contains_key(name) {
            self.insert_scene(self.catalog.load(name)?)?;
        }
        self.scenes
            .get(name)
            .map(|s| &s.scene)
            .ok_or_else(|| RenderError::Gpu(format!("scene {name} did not load")))
    }

    /// Registers a scene that is not built in (a scene file from elsewhere, a test's own);
    /// it replaces any scene of the same name.
    pub fn add_scene(&mut self, scene: Scene) -> Result<(), RenderError> {
        let name = scene.name().to_string();
        self.scenes.remove(&name);
        self.targets.retain(|(k, _)| k.1 != name);
        self.insert_scene(scene)
    }

    fn insert_scene(&mut self, scene: Scene) -> Result<(), RenderError> {
        let name = scene.name().to_string();
        let d = &self.gpu.device;
        let sg = SceneGpu::upload(
            d,
            &self.gpu.queue,
            &mut self.pipelines,
            &self.photon_pass,
            scene,
        )?;
        if let (Some(h), Ok(mut solves)) = (&sg.radiosity, self.solves.lock()) {
            solves.retain(|s| s.scene() != name);
            solves.push(h.clone());
        }
        self.scenes.insert(name, sg);
        Ok(())
    }

    /// The scene's radiosity solve (loading the scene if needed); `None` when its plan has none.
    pub fn radiosity(
        &mut self,
        scene: &str,
    ) -> Result<Option<crate::radiosity::RadiosityHandle>, RenderError> {
        self.load_scene(scene)?;
        Ok(self.scenes.get(scene).and_then(|s| s.radiosity.clone()))
    }

    /// The radiosity solves of every loaded scene (a shared list that follows later loads).
    pub fn solves(&self) -> Solves {
        self.solves.clone()
    }

    /// How many times a photon pyramid has been built (static scenes: once per scene).
    pub fn pyramid_builds(&self) -> u64 {
        self.pyramid_builds
    }

    /// Frees a stream's targets and history (a session ended).
    pub fn release_stream(&mut self, stream: u64) {
        self.targets.retain(|(k, _)| k.0 != stream);
    }

    pub fn render(&mut self, req: &FrameRequest) -> Result<RenderedFrame, RenderError> {
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
        let ti = self.target_index(req.stream, &req.scene, w, h)?;
        self.timer.begin_frame();
        let (photon_encoder, inputs) = self.prepare_scene(req, ti)?;
        let submission = self.encode_frame(req, ti, inputs, photon_encoder)?;
        let render_ms = started.elapsed().as_secs_f64() * 1e3;
        let device = &self.gpu.device;
        let passes_ms = self.timer.read(device, submission)?;

        let started = Instant::now();
        let t = &self.targets[ti].1;
        let (rgba, count) = t.read_back(device, &self.gpu.queue)?;
        let readback_ms = started.elapsed().as_secs_f64() * 1e3;
        let sampled = if req.settings.foveation.enabled {
            f64::from(count) / (f64::from(w) * f64::from(h))
        } else {
            1.0
        };
        Ok(RenderedFrame {
            width: w,
            height: h,
            rgba,
            sampled,
            render_ms,
            readback_ms,
            passes_ms,
            radiosity: self.scenes.get(&req.scene).and_then(|s| s.gi),
        })
    }

    /// Uploads radiosity's newest snapshot and, when the hierarchical rungs will read a photon
    /// pyramid that is stale, records its rebuild. Returns that encoder and what the pyramid
    /// must be built for (light direction, radiosity snapshot).
    fn prepare_scene(
        &mut self,
        req: &FrameRequest,
        ti: usize,
    ) -> Result<(Option<wgpu::CommandBuffer>, PhotonInputs), RenderError> {
        let sg = self
            .scenes
            .get_mut(&req.scene)
            .ok_or_else(|| RenderError::Gpu(format!("scene {} is not loaded", req.scene)))?;
        let to_light = req
            .to_light
            .and_then(|l| l.try_normalize())
            .unwrap_or_else(|| sg.scene.file.light.to_light_at(req.time_s));
        upload_radiosity(&self.gpu.queue, sg);
        let inputs = PhotonInputs {
            to_light,
            gi_version: sg.gi_version,
            indirect: req.settings.indirect,
            // The key map is built (below, first) whenever shadows are on and the scene has it.
            shadowed: req.settings.shadows && sg.shadow.is_some(),
        };
        let device = &self.gpu.device;
        let encoder = || {
            device.create_command_encoder(&wgpu::CommandEncoderDescriptor {
                label: Some("light views"),
            })
        };
        let mut enc: Option<wgpu::CommandEncoder> = None;
        if let Some(map) = sg
            .shadow
            .as_mut()
            .filter(|m| req.settings.shadows && m.built_for != Some(to_light))
        {
            let view = shadow_view(&sg.scene, to_light);
            let spots = super::lights::shadowed_spots(&sg.scene);
            let e = enc.get_or_insert_with(encoder);
            map.build(
                &self.gpu.queue,
                e,
                &mut self.pipelines,
                &sg.mesh,
                &view,
                &spots,
                to_light,
                &mut self.timer,
            )?;
        }
        let needs =
            self.targets[ti].1.needs_dipole && req.settings.translucency.rung >= Rung::Hierarchical;
        if let Some(map) = sg
            .photons
            .as_mut()
            .filter(|m| needs && m.built_for != Some(inputs))
        {
            let e = enc.get_or_insert_with(encoder);
            self.photon_pass.build(
                &self.gpu.queue,
                e,
                map,
                &sg.scene,
                &sg.mesh,
                inputs,
                &mut self.timer,
            )?;
            self.pyramid_builds += 1;
        }
        Ok((enc.map(wgpu::CommandEncoder::finish), inputs))
    }

    /// Writes the frame's uniforms, records its passes, submits and waits for them.
    fn encode_frame(
        &mut self,
        req: &FrameRequest,
        ti: usize,
        inputs: PhotonInputs,
        photon_encoder: Option<wgpu::CommandBuffer>,
    ) -> Result<wgpu::SubmissionIndex, RenderError> {
        let sg = self
            .scenes
            .get(&req.scene)
            .ok_or_else(|| RenderError::Gpu(format!("scene {} is not loaded", req.scene)))?;
        let pyramid_ready = sg
            .photons
            .as_ref()
            .is_some_and(|m| m.built_for == Some(inputs));
        let shadow_ready = sg
            .shadow
            .as_ref()
            .is_some_and(|m| m.built_for == Some(inputs.to_light));
        let (device, queue) = (&self.gpu.device, &self.gpu.queue);
        let t = &mut self.targets[ti].1;
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
        queue.write_buffer(t.buffer("frame.uniform")?, 0, bytemuck::bytes_of(&uniform));
        let plan = FramePlan::of(&req.settings, req.width, req.height, t.needs_dipole);

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
            routes: Default::default(),
            timer: &mut self.timer,
            size: (req.width, req.height),
        };
        frame::record(&mut recorder, &plan, &sg.mesh)?;
        t.routes = recorder.routes;
        self.timer.resolve(&mut encoder);
        let submission = queue.submit(photon_encoder.into_iter().chain([encoder.finish()]));
        device
            .poll(wgpu::PollType::Wait {
                submission_index: Some(submission.clone()),
                timeout: None,
            })
            .map_err(|e| RenderError::Gpu(format!("waiting for the frame: {e}")))?;
        if let Some(e) = pollster::block_on(scope.pop()) {
            return Err(RenderError::Gpu(e.to_string()));
        }
        t.prev_view_proj = camera.view_proj(req.width, req.height);
        t.prev_eye = Vec3::from(camera.eye);
        t.has_history = true;
        t.frame_index = t.frame_index.wrapping_add(1);
        Ok(submission)
    }

    /// Reads back the intermediate images of a stream's last frame.
    pub fn inspect(
        &self,
        stream: u64,
        scene: &str,
        width: u32,
        height: u32,
    ) -> Result<Inspection, RenderError> {
        let key = (stream, scene.to_string(), width, height);
        let (_, t) = self
            .targets
            .iter()
            .find(|(k, _)| *k == key)
            .ok_or_else(|| {
                RenderError::Readback(format!(
                    "no frame rendered for stream {stream} at {width}x{height}"
                ))
            })?;
        let buf = |name| read_buffer(&self.gpu, t.buffer(name)?);
        let f32s = |b: Vec<u8>| -> Vec<f32> { bytemuck::pod_collect_to_vec(&b) };
        let u32s = |b: Vec<u8>| -> Vec<u32> { bytemuck::pod_collect_to_vec(&b) };
        let quads = |b: Vec<u8>| -> Vec<[f32; 4]> { bytemuck::pod_collect_to_vec(&b) };
        let nodes = self
            .scenes
            .get(scene)
            .and_then(|s| s.photons.as_ref())
            .and_then(|m| m.nodes());
        Ok(Inspection {
            probability: f32s(buf("sampling.probability")?),
            flags: u32s(buf("sampling.flags")?),
            seeds: u32s(buf("sampling.seeds")?),
            nearest: u32s(
                buf(t.routes.resolve("jfa.nearest")).or_else(|_| buf("jfa.seeds[ping]"))?,
            ),
            color: quads(buf("shade.color")?),
            resolved: quads(buf("resolve.color")?),
            normal_distance: quads(read_texture(
                &self.gpu,
                t.texture("gbuffer.normal_distance")?,
                16,
            )?),
            photons: match nodes {
                Some(nodes) => {
                    let n = (PHOTON_SIDE * PHOTON_SIDE) as usize;
                    let all: Vec<[f32; 8]> =
                        bytemuck::pod_collect_to_vec(&read_buffer(&self.gpu, nodes)?);
                    all[..n.min(all.len())].to_vec()
                }
                None => Vec::new(),
            },
        })
    }

    fn target_index(
        &mut self,
        stream: u64,
        scene: &str,
        w: u32,
        h: u32,
    ) -> Result<usize, RenderError> {
        let key = (stream, scene.to_string(), w, h);
        if let Some(i) = self.targets.iter().position(|(k, _)| *k == key) {
            return Ok(i);
        }
        if self.targets.len() >= TARGET_CACHE {
            self.targets.remove(0);
        }
        let sg = self
            .scenes
            .get(scene)
            .ok_or_else(|| RenderError::Gpu(format!("scene {scene} is not loaded")))?;
        let plan = Plan::of(&sg.scene, w, h);
        let materials = super::materials::upload(
            &self.gpu.device,
            "materials.planned",
            &super::materials::gpu_materials(&sg.scene, Some(&plan)),
        );
        let mut shared = self.shared.clone();
        shared.extend(&sg.resources);
        let t = FrameTargets::new(&self.gpu.device, &shared, materials, w, h, plan.photon_pass);
        self.targets.push((key, t));
        Ok(self.targets.len() - 1)
    }
}

fn read_buffer(gpu: &Gpu, source: &wgpu::Buffer) -> Result<Vec<u8>, RenderError> {
    let buffer = gpu.device.create_buffer(&wgpu::BufferDescriptor {
        label: Some("inspect"),
        size: source.size(),
        usage: wgpu::BufferUsages::COPY_DST | wgpu::BufferUsages::MAP_READ,
        mapped_at_creation: false,
    });
    let mut encoder = gpu.device.create_command_encoder(&Default::default());
    encoder.copy_buffer_to_buffer(source, 0, &buffer, 0, source.size());
    let submission = gpu.queue.submit([encoder.finish()]);
    map_read(&gpu.device, submission, &buffer, |bytes| bytes.to_vec())
}

fn read_texture(
    gpu: &Gpu,
    texture: &wgpu::Texture,
    bytes_per_pixel: u32,
) -> Result<Vec<u8>, RenderError> {
    let (w, h) = (texture.width(), texture.height());
    let align = wgpu::COPY_BYTES_PER_ROW_ALIGNMENT;
    let row = w * bytes_per_pixel;
    let padded = row.div_ceil(align) * align;
    let buffer = gpu.device.create_buffer(&wgpu::BufferDescriptor {
        label: Some("inspect"),
        size: u64::from(padded) * u64::from(h),
        usage: wgpu::BufferUsages::COPY_DST | wgpu::BufferUsages::MAP_READ,
        mapped_at_creation: false,
    });
    let mut encoder = gpu.device.create_command_encoder(&Default::default());
    encoder.copy_texture_to_buffer(
        texture.as_image_copy(),
        wgpu::TexelCopyBufferInfo {
            buffer: &buffer,
            layout: wgpu::TexelCopyBufferLayout {
                offset: 0,
                bytes_per_row: Some(padded),
                rows_per_image: Some(h),
            },
        },
        wgpu::Extent3d {
            width: w,
            height: h,
            depth_or_array_layers: 1,
        },
    );
    let submission = gpu.queue.submit([encoder.finish()]);
    map_read(&gpu.device, submission, &buffer, |bytes| {
        bytes
            .chunks_exact(padded as usize)
            .flat_map(|c| c[..row as usize].to_vec())
            .collect()
    })
}
