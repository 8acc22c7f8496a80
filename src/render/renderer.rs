use std::collections::HashMap;
use std::time::Instant;

use glam::Vec3;

use super::frame_uniform::frame_uniform;
use super::gi::{start_radiosity, upload_radiosity};
use super::gpu::{self, FramePass};
use super::pass::compact::CompactPass;
use super::pass::gbuffer::{GBufferPass, GBufferTargets, MeshBuffers};
use super::pass::jfa::JfaPass;
use super::pass::photons::{PhotonInputs, PhotonMap, PhotonPass};
use super::pass::screen_diffusion::ScreenDiffusionPass;
use super::pass::shade::ShadePass;
use super::pass::{dof, output, resolve, sampling};
use super::targets::{map_read, FrameTargets};
use super::timer::PassTimer;
use super::{Gpu, RenderError};
use crate::foveation::rank_map;
use crate::foveation::{Rung, Settings};
use crate::protocol::Display;
use crate::radiosity::Progress;
use crate::scene::{Camera, Plan, Scene};

/// Largest side a frame may have; matches wgpu's default 2-D texture limit.
pub const MAX_SIDE: u32 = 8192;
/// Target sets (one per stream and size) kept alive; the oldest goes first.
const TARGET_CACHE: usize = 8;
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
    pub settings: Settings,
    /// Overrides the scene light's direction (unit vector towards the light).
    pub to_light: Option<Vec3>,
    /// Overrides the scene camera.
    pub camera: Option<Camera>,
    /// Whose frame sequence this is: history (reprojection) is kept per stream.
    pub stream: u64,
    /// Seconds into the stream, for animated lights.
    pub time_s: f64,
}

impl FrameRequest {
    pub fn new(scene: &str, width: u32, height: u32) -> FrameRequest {
        FrameRequest {
            scene: scene.to_string(),
            width,
            height,
            gaze: [0.5, 0.5],
            marker: false,
            pupil_mm: DEFAULT_PUPIL_MM,
            display: Display::default(),
            settings: Settings::default(),
            to_light: None,
            camera: None,
            stream: 0,
            time_s: 0.0,
        }
    }
}

/// A rendered frame in host memory.
#[derive(Debug, Clone)]
pub struct RenderedFrame {
    pub width: u32,
    pub height: u32,
    /// Tightly packed RGBA8, sRGB-encoded, top row first.
    pub rgba: Vec<u8>,
    /// Fraction of the frame's pixels the shading pass ran for.
    pub sampled: f64,
    pub render_ms: f64,
    pub readback_ms: f64,
    /// GPU milliseconds per pass label (empty without timestamp queries).
    pub passes_ms: std::collections::BTreeMap<String, f64>,
    /// Where the scene's radiosity solve stood when this frame used it; `None` without one.
    pub radiosity: Option<Progress>,
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
    /// Photons (pyramid level 0) as [x, y, z, extent, Φr, Φg, Φb, weight]; empty without any.
    pub photons: Vec<[f32; 8]>,
}

pub(crate) struct Passes {
    pub gbuffer: GBufferPass,
    pub sampling: FramePass,
    pub compact: CompactPass,
    pub shade: ShadePass,
    pub jfa: JfaPass,
    pub resolve: FramePass,
    pub dof: FramePass,
    pub output: FramePass,
    pub photons: PhotonPass,
    pub screen_diffusion: ScreenDiffusionPass,
}

/// A scene on the GPU: its mesh, materials, and photon pyramid if anything is translucent.
pub(crate) struct SceneGpu {
    pub scene: Scene,
    pub mesh: MeshBuffers,
    /// Every translucent material marked subsurface (for the G-buffer and the photon map).
    pub materials: wgpu::Buffer,
    pub reach: wgpu::Buffer,
    pub photons: Option<PhotonMap>,
    /// Bound in place of the pyramid when the scene has none.
    pub no_photons: wgpu::Buffer,
    /// The scene's radiosity solve, when its plan asks for one, and the snapshot uploaded.
    pub radiosity: Option<crate::radiosity::RadiosityHandle>,
    pub gi: Option<Progress>,
    pub gi_version: u64,
}

type TargetKey = (u64, String, u32, u32);

/// Owns the GPU and everything on it. Not shared: one thread drives it (see `RenderThread`).
pub struct Renderer {
    gpu: Gpu,
    passes: Passes,
    rank_map: wgpu::TextureView,
    scenes: HashMap<String, SceneGpu>,
    targets: Vec<(TargetKey, FrameTargets)>,
    timer: PassTimer,
    pyramid_builds: u64,
}

impl Renderer {
    pub fn new() -> Result<Renderer, RenderError> {
        Ok(Renderer::with_gpu(Gpu::new()?))
    }

    pub fn with_gpu(gpu: Gpu) -> Renderer {
        let d = &gpu.device;
        let passes = Passes {
            gbuffer: GBufferPass::new(d),
            sampling: sampling::new(d),
            compact: CompactPass::new(d),
            shade: ShadePass::new(d),
            jfa: JfaPass::new(d),
            resolve: resolve::new(d),
            dof: dof::new(d),
            output: output::new(d),
            photons: PhotonPass::new(d),
            screen_diffusion: ScreenDiffusionPass::new(d),
        };
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
        let timer = PassTimer::new(d, &gpu.queue);
        Renderer {
            passes,
            rank_map: gpu::view(&rank),
            gpu,
            scenes: HashMap::new(),
            targets: Vec::new(),
            timer,
            pyramid_builds: 0,
        }
    }

    pub fn adapter(&self) -> String {
        self.gpu.summary()
    }

    /// Whether per-pass GPU times are measured (timestamp queries).
    pub fn timestamps(&self) -> bool {
        self.timer.enabled()
    }

    /// Loads a scene onto the GPU ahead of its first frame (otherwise the first frame does it).
    pub fn load_scene(&mut self, name: &str) -> Result<&Scene, RenderError> {
        if !self.scenes.contains_key(name) {
            self.insert_scene(Scene::builtin(name)?);
        }
        Ok(&self.scenes[name].scene)
    }

    /// Registers a scene that is not built in (a scene file from elsewhere, a test's own);
    /// it replaces any scene of the same name.
    pub fn add_scene(&mut self, scene: Scene) {
        let name = scene.name().to_string();
        self.scenes.remove(&name);
        self.targets.retain(|(k, _)| k.1 != name);
        self.insert_scene(scene);
    }

    fn insert_scene(&mut self, scene: Scene) {
        let name = scene.name().to_string();
        let d = &self.gpu.device;
        let mesh = self.passes.gbuffer.upload(d, &scene);
        let materials = super::materials::upload(
            d,
            "materials.scene",
            &super::materials::gpu_materials(&scene, None),
        );
        let reach = super::materials::upload_reach(d, &scene);
        let photons = scene
            .has_translucency()
            .then(|| self.passes.photons.create_map(d, &materials));
        let no_photons = d.create_buffer(&wgpu::BufferDescriptor {
            label: Some("pyramid.none"),
            size: 32,
            usage: wgpu::BufferUsages::STORAGE,
            mapped_at_creation: false,
        });
        tracing::info!(scene = %name, triangles = scene.mesh.triangle_count(), translucent = scene.has_translucency(), "scene loaded");
        let radiosity = start_radiosity(&scene);
        self.scenes.insert(
            name,
            SceneGpu {
                scene,
                mesh,
                materials,
                reach,
                photons,
                no_photons,
                radiosity,
                gi: None,
                gi_version: 0,
            },
        );
    }

    /// The scene's radiosity solve (loading the scene if needed); `None` when its plan has none.
    pub fn radiosity(
        &mut self,
        scene: &str,
    ) -> Result<Option<crate::radiosity::RadiosityHandle>, RenderError> {
        self.load_scene(scene)?;
        Ok(self.scenes[scene].radiosity.clone())
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
        let ti = self.target_index(req.stream, &req.scene, w, h);
        let rung = req.settings.translucency.rung;
        let to_light = {
            let scene = &self.scenes[&req.scene].scene;
            req.to_light
                .and_then(|l| l.try_normalize())
                .unwrap_or_else(|| scene.file.light.to_light_at(req.time_s))
        };
        let sg = self.scenes.get_mut(&req.scene).expect("loaded above");
        upload_radiosity(&self.gpu.queue, sg);
        let photon_inputs = PhotonInputs {
            to_light,
            gi_version: sg.gi_version,
            indirect: req.settings.indirect,
        };
        let radiosity = sg.gi;
        let mut photon_encoder = None;
        self.timer.begin_frame();
        if let Some(map) = sg.photons.as_mut() {
            let plan_needs = self.targets[ti].1.needs_dipole;
            if rung >= Rung::Hierarchical && plan_needs && map.built_for != Some(photon_inputs) {
                let mut enc =
                    self.gpu
                        .device
                        .create_command_encoder(&wgpu::CommandEncoderDescriptor {
                            label: Some("photons"),
                        });
                self.passes.photons.build(
                    &self.gpu.queue,
                    &mut enc,
                    map,
                    &sg.scene,
                    &sg.mesh,
                    photon_inputs,
                    &mut self.timer,
                );
                self.pyramid_builds += 1;
                photon_encoder = Some(enc.finish());
            }
        }
        let sg = &self.scenes[&req.scene];
        let (scene, mesh) = (&sg.scene, &sg.mesh);
        let pyramid_ready = sg
            .photons
            .as_ref()
            .is_some_and(|m| m.built_for == Some(photon_inputs));
        let t = &self.targets[ti].1;
        let device = &self.gpu.device;
        let queue = &self.gpu.queue;
        let settings = &req.settings;
        let fov = &settings.foveation;
        let camera = req.camera.unwrap_or(scene.file.camera);
        let uniform = frame_uniform(scene, &camera, req, t, to_light, pyramid_ready);
        queue.write_buffer(&t.uniform, 0, bytemuck::bytes_of(&uniform));

        let scope = device.push_error_scope(wgpu::ErrorFilter::Validation);
        let mut encoder = device.create_command_encoder(&wgpu::CommandEncoderDescriptor {
            label: Some("frame"),
        });
        let [nd, albedo, blurred, irradiance] = t.gbuffer_views();
        let targets = GBufferTargets {
            normal_distance: &nd,
            albedo: &albedo,
            blurred_normal: &blurred,
            irradiance: &irradiance,
            depth: &t.depth,
        };
        let p = &self.passes;
        let size = (w, h);
        let timer = &mut self.timer;
        p.gbuffer
            .encode(&mut encoder, &targets, &t.bind.gbuffer, mesh, timer);
        if rung == Rung::Screen && t.needs_dipole {
            let [a, b, c] = &t.bind.screen_diffusion;
            p.screen_diffusion
                .encode(&mut encoder, [a, b, c], size, timer);
        }
        if fov.enabled {
            encoder.clear_buffer(&t.counter, 0, None);
            p.sampling
                .encode(&mut encoder, &t.bind.sampling, size, timer);
            // The list also counts the samples (the header's `sampled`), so it is built either way;
            // without compaction the shading pass masks a full-frame dispatch instead of using it.
            p.compact.encode(&mut encoder, &t.bind.compact, size, timer);
            if fov.compaction {
                p.shade
                    .encode_list(&mut encoder, &t.bind.shade, &t.counter, timer);
            } else {
                p.shade
                    .encode_grid(&mut encoder, &t.bind.shade, size, timer);
            }
            let steps = fov.jfa_steps(w, h, MIN_XI);
            t.write_jfa_steps(queue, &steps);
            let jfa: Vec<&wgpu::BindGroup> = t.bind.jfa.iter().take(steps.len()).collect();
            p.jfa.encode(&mut encoder, &jfa, size, timer);
            p.resolve.encode(&mut encoder, &t.bind.resolve, size, timer);
        } else {
            p.shade
                .encode_grid(&mut encoder, &t.bind.shade, size, timer);
        }
        let output = match (settings.dof, fov.enabled) {
            (true, foveated) => {
                let from = if foveated {
                    &t.bind.dof_from_resolved
                } else {
                    &t.bind.dof_from_color
                };
                p.dof.encode(&mut encoder, from, size, timer);
                &t.bind.output_dof
            }
            (false, true) => &t.bind.output_resolved,
            (false, false) => &t.bind.output_color,
        };
        p.output.encode(&mut encoder, output, size, timer);
        t.keep_history(&mut encoder);
        timer.resolve(&mut encoder);
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
        let render_ms = started.elapsed().as_secs_f64() * 1e3;
        let passes_ms = self.timer.read(device, submission)?;

        let started = Instant::now();
        let (rgba, count) = t.read_back(device, queue)?;
        let readback_ms = started.elapsed().as_secs_f64() * 1e3;
        let sampled = if fov.enabled {
            f64::from(count) / (f64::from(w) * f64::from(h))
        } else {
            1.0
        };

        let view_proj = camera.view_proj(w, h);
        let t = &mut self.targets[ti].1;
        t.prev_view_proj = view_proj;
        t.prev_eye = Vec3::from(camera.eye);
        t.has_history = true;
        t.frame_index = t.frame_index.wrapping_add(1);
        Ok(RenderedFrame {
            width: w,
            height: h,
            rgba,
            sampled,
            render_ms,
            readback_ms,
            passes_ms,
            radiosity,
        })
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
        let buf = |b: &wgpu::Buffer| read_buffer(&self.gpu, b);
        let f32s = |b: Vec<u8>| -> Vec<f32> { bytemuck::pod_collect_to_vec(&b) };
        let u32s = |b: Vec<u8>| -> Vec<u32> { bytemuck::pod_collect_to_vec(&b) };
        let quads = |b: Vec<u8>| -> Vec<[f32; 4]> { bytemuck::pod_collect_to_vec(&b) };
        Ok(Inspection {
            probability: f32s(buf(&t.probability)?),
            flags: u32s(buf(&t.flags)?),
            seeds: u32s(buf(&t.seeds)?),
            nearest: u32s(buf(t.jfa_result())?),
            color: quads(buf(&t.color)?),
            resolved: quads(buf(&t.resolved)?),
            normal_distance: quads(read_texture(&self.gpu, &t.normal_distance, 16)?),
            photons: match self.scenes.get(scene).and_then(|s| s.photons.as_ref()) {
                Some(map) => {
                    let n = (super::pass::photons::SIDE * super::pass::photons::SIDE) as usize;
                    let all: Vec<[f32; 8]> = bytemuck::pod_collect_to_vec(&buf(&map.nodes)?);
                    all[..n].to_vec()
                }
                None => Vec::new(),
            },
        })
    }

    fn target_index(&mut self, stream: u64, scene: &str, w: u32, h: u32) -> usize {
        let key = (stream, scene.to_string(), w, h);
        if let Some(i) = self.targets.iter().position(|(k, _)| *k == key) {
            return i;
        }
        if self.targets.len() >= TARGET_CACHE {
            self.targets.remove(0);
        }
        let sg = &self.scenes[scene];
        let plan = Plan::of(&sg.scene, w, h);
        let materials = super::materials::upload(
            &self.gpu.device,
            "materials.planned",
            &super::materials::gpu_materials(&sg.scene, Some(&plan)),
        );
        let mut t = FrameTargets::new(
            &self.gpu.device,
            &self.passes,
            &self.rank_map,
            sg,
            materials,
            w,
            h,
        );
        t.needs_dipole = plan.photon_pass;
        self.targets.push((key, t));
        self.targets.len() - 1
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
