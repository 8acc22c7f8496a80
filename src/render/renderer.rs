//! The renderer: owns the GPU, the pipelines, every loaded scene and each stream's targets, and
//! turns a [`FrameRequest`] into pixels. The frame's passes are recorded by `frame.rs`.

use std::collections::HashMap;

use super::gi::upload_radiosity;
use super::graph::{Pipelines, Resources};
use super::pass::photons::{PhotonInputs, PhotonPass};
use super::pass::shadow::shadow_view;
use super::request::{FrameRequest, RenderedFrame};
use super::scene_gpu::SceneGpu;
use super::sliced::Progress;
use super::targets::FrameTargets;
use super::timer::PassTimer;
use super::{gpu, Gpu, RenderError};
use crate::foveation::rank_map;
use crate::scene::{Plan, Scene};
use crate::settings::Rung;

/// Target sets (one per stream and size) kept alive; the oldest goes first past either limit.
const TARGET_CACHE: usize = 32;
/// GPU memory the target sets may take together (a 3840×2160 set is about 1.5 GB, a
/// 640×480 one 55 MB). One set larger than this is still made, alone.
pub const TARGET_MEMORY: u64 = 4 << 30;

pub(super) type TargetKey = (u64, String, u32, u32);

/// Owns the GPU and everything on it. Not shared: one thread drives it (see `RenderThread`).
pub struct Renderer {
    pub(super) gpu: Gpu,
    pub(super) pipelines: Pipelines,
    pub(super) photon_pass: PhotonPass,
    /// Shared by every stream: the blue-noise rank map.
    pub(super) shared: Resources,
    pub(super) scenes: HashMap<String, SceneGpu>,
    pub(super) targets: Vec<(TargetKey, FrameTargets)>,
    pub(super) timer: PassTimer,
    pub(super) pyramid_builds: u64,
    /// The radiosity solves of loaded scenes, shared with `RenderHandle` for `/readyz`.
    pub(super) solves: Solves,
    /// Where scenes come from by name.
    pub(super) catalog: crate::scene::Catalog,
    /// Targets of sliced frames in flight: never evicted under them.
    pub(super) pinned: Vec<TargetKey>,
    /// GPU bytes the target sets may take together.
    target_memory: u64,
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
            pinned: Vec::new(),
            target_memory: TARGET_MEMORY,
        }
    }

    pub fn adapter(&self) -> String {
        self.gpu.summary()
    }

    /// Whether the adapter is a CPU one (lavapipe, llvmpipe): what shares the CPU with it slows
    /// its renders.
    pub fn is_software(&self) -> bool {
        self.gpu.info.device_type == wgpu::DeviceType::Cpu
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

    /// Blocks until the scene's radiosity solve converges, for at most `timeout` or until
    /// `give_up` says so (loading the scene if needed; returns at once where it has no solve or
    /// has converged). What measures frames waits: while a solve refines, each frame reads a
    /// newer solution (a reference and the configuration it is compared with would differ by
    /// it), and the solver takes a core from the frames being timed (`cornell`'s `balanced`
    /// frame at 1280×720: 225 ms while it solved, 136 after).
    pub fn settle_radiosity(
        &mut self,
        scene: &str,
        timeout: std::time::Duration,
        give_up: &dyn Fn() -> bool,
    ) -> Result<(), RenderError> {
        let Some(solve) = self.radiosity(scene)? else {
            return Ok(());
        };
        let deadline = std::time::Instant::now() + timeout;
        while !solve.converged() && !give_up() {
            let left = deadline.saturating_duration_since(std::time::Instant::now());
            if left.is_zero() {
                break;
            }
            // Short waits, so a stop asked for (Ctrl-C) is seen within a fraction of a second.
            solve.wait(left.min(std::time::Duration::from_millis(200)));
        }
        Ok(())
    }

    /// The radiosity solves of every loaded scene (a shared list that follows later loads).
    pub fn solves(&self) -> Solves {
        self.solves.clone()
    }

    /// Takes over `solves` as the list this renderer keeps its radiosity solves in (a restarted
    /// renderer keeps reporting on the list `/readyz` reads).
    pub fn share_solves(&mut self, solves: Solves) {
        if let Ok(mut list) = solves.lock() {
            list.clear();
        }
        self.solves = solves;
    }

    /// Whether the GPU device has been lost (then nothing renders until a new one is opened).
    pub fn is_lost(&self) -> bool {
        self.gpu.is_lost()
    }

    /// Destroys the device, as a driver reset would: for tests of what follows.
    #[doc(hidden)]
    pub fn lose_device(&self) {
        self.gpu.device.destroy();
    }

    /// How many times a photon pyramid has been built (static scenes: once per scene).
    pub fn pyramid_builds(&self) -> u64 {
        self.pyramid_builds
    }

    /// Sets how many GPU bytes the streams' target sets may take together.
    pub fn set_target_memory(&mut self, bytes: u64) {
        self.target_memory = bytes;
    }

    /// GPU bytes the streams' target sets take now.
    pub fn target_bytes(&self) -> u64 {
        self.targets.iter().map(|(_, t)| t.bytes).sum()
    }

    /// Frees a stream's targets and history (a session ended).
    pub fn release_stream(&mut self, stream: u64) {
        self.targets.retain(|(k, _)| k.0 != stream);
        self.pinned.retain(|k| k.0 != stream);
    }

    /// Renders a whole frame in one submission.
    pub fn render(&mut self, req: &FrameRequest) -> Result<RenderedFrame, RenderError> {
        let mut going = match self.begin(req, 1)? {
            Progress::Done(frame) => return Ok(frame),
            Progress::Going(going) => going,
        };
        loop {
            if let Some(frame) = self.step(&mut going)? {
                return Ok(frame);
            }
        }
    }

    /// Uploads radiosity's newest snapshot and, when the hierarchical rungs will read a photon
    /// pyramid that is stale, records its rebuild. Returns that encoder and what the pyramid
    /// must be built for (light direction, radiosity snapshot).
    pub(super) fn prepare_scene(
        &mut self,
        req: &FrameRequest,
        ti: usize,
    ) -> Result<(Option<wgpu::CommandBuffer>, PhotonInputs), RenderError> {
        let sg = self
            .scenes
            .get_mut(&req.scene)
            .ok_or_else(|| not_loaded(&req.scene))?;
        let to_light = req.light_direction(&sg.scene);
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
            let tiles = super::lights::shadow_tiles(&sg.scene);
            let e = enc.get_or_insert_with(encoder);
            map.build(
                &self.gpu.queue,
                e,
                &mut self.pipelines,
                &sg.mesh,
                &view,
                &tiles,
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

    /// A loaded scene's GPU side.
    pub(super) fn loaded(&self, scene: &str) -> Result<&SceneGpu, RenderError> {
        self.scenes.get(scene).ok_or_else(|| not_loaded(scene))
    }

    pub(super) fn target_index(
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
        // The oldest sets go first, never one a sliced frame is still using.
        let needed = FrameTargets::bytes_for(w, h);
        loop {
            let held: u64 = self.targets.iter().map(|(_, t)| t.bytes).sum();
            let full = self.targets.len() >= TARGET_CACHE || held + needed > self.target_memory;
            let oldest = self
                .targets
                .iter()
                .position(|(k, _)| !self.pinned.contains(k));
            match oldest {
                Some(i) if full => {
                    self.targets.remove(i);
                }
                _ => break,
            }
        }
        let sg = self.loaded(scene)?;
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

pub(super) fn not_loaded(scene: &str) -> RenderError {
    RenderError::Gpu(format!("scene {scene} is not loaded"))
}
