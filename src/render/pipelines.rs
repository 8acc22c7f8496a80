//! Layouts, shader modules and pipelines, built once per device from the passes'
//! declarations and cached; a pipeline may be specialised by override constants (the frame's
//! mode bits, the kinds of material a scene has, its maps), one per set met.

use std::collections::HashMap;

use super::gpu;
use super::graph::PassDecl;

/// Pipelines one entry point may have specialised for different frame modes.
pub const MAX_SPECIALISED: usize = 8;

type ComputeKey = (&'static str, &'static str, Specialised);

/// What a compute pipeline is specialised for, each when given: the frame's mode bits
/// (`SPECIALISED_MODE` in common.wgsl), and for the shading pass the kinds of material the
/// scene has (`SCENE_KINDS`) and the frame's translucency rung (`FRAME_RUNG`).
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq, Hash)]
pub struct Specialised {
    pub mode: Option<u32>,
    pub scene_kinds: Option<u32>,
    pub rung: Option<u32>,
}

/// Layouts and pipelines, built once per device from the declarations.
pub struct Pipelines {
    device: wgpu::Device,
    layouts: HashMap<&'static str, wgpu::BindGroupLayout>,
    modules: HashMap<&'static str, wgpu::ShaderModule>,
    /// By pass, entry point, the frame mode and the scene's material kinds it was
    /// specialised for (if it was).
    compute: HashMap<ComputeKey, wgpu::ComputePipeline>,
    /// By pass and variant (the pass's own key for the constants it was built with).
    render: HashMap<(&'static str, u32), wgpu::RenderPipeline>,
}

impl Pipelines {
    pub fn new(device: &wgpu::Device) -> Pipelines {
        Pipelines {
            device: device.clone(),
            layouts: HashMap::new(),
            modules: HashMap::new(),
            compute: HashMap::new(),
            render: HashMap::new(),
        }
    }

    pub fn layout(&mut self, decl: &PassDecl) -> wgpu::BindGroupLayout {
        let device = &self.device;
        self.layouts
            .entry(decl.label)
            .or_insert_with(|| gpu::layout(device, decl.label, &decl.layout_entries()))
            .clone()
    }

    pub fn module(&mut self, decl: &PassDecl) -> wgpu::ShaderModule {
        let device = &self.device;
        self.modules
            .entry(decl.label)
            .or_insert_with(|| gpu::shader(device, decl.label, decl.shader))
            .clone()
    }

    /// The compute pipeline of one entry point; `label` names it (timers use the pass label).
    pub fn compute(
        &mut self,
        decl: &PassDecl,
        entry: &'static str,
        label: &'static str,
    ) -> wgpu::ComputePipeline {
        self.compute_for(decl, entry, label, Specialised::default())
    }

    /// The pipeline of `entry`, specialised as `by` says, one pipeline per set met, built on
    /// first use. Modes come from client settings: past a handful per entry point, the
    /// pipeline not specialised for modes serves the rest rather than the cache growing with
    /// every combination.
    pub fn compute_for(
        &mut self,
        decl: &PassDecl,
        entry: &'static str,
        label: &'static str,
        by: Specialised,
    ) -> wgpu::ComputePipeline {
        let key = (decl.label, entry, by);
        if let Some(p) = self.compute.get(&key) {
            return p.clone();
        }
        let specialised = |k: &&ComputeKey| k.0 == decl.label && k.1 == entry && k.2.mode.is_some();
        if by.mode.is_some() && self.compute.keys().filter(specialised).count() >= MAX_SPECIALISED {
            let general = Specialised { mode: None, ..by };
            return self.compute_for(decl, entry, label, general);
        }
        let layout = self.layout(decl);
        let module = self.module(decl);
        let constants: Vec<(&str, f64)> = [
            by.mode.map(|m| ("SPECIALISED_MODE", f64::from(m))),
            by.scene_kinds.map(|k| ("SCENE_KINDS", f64::from(k))),
            by.rung.map(|r| ("FRAME_RUNG", f64::from(r))),
        ]
        .into_iter()
        .flatten()
        .collect();
        let p = gpu::compute_pipeline(&self.device, label, &module, entry, &layout, &constants);
        self.compute.insert(key, p.clone());
        p
    }
}

impl Pipelines {
    /// A raster pass's pipeline, built by `build` from the pass's layout and shader module on
    /// first use of this `variant` (a pass that specialises its shader per scene numbers the
    /// constant sets it builds; others pass 0).
    pub fn render(
        &mut self,
        decl: &PassDecl,
        variant: u32,
        build: impl FnOnce(
            &wgpu::Device,
            &wgpu::BindGroupLayout,
            &wgpu::ShaderModule,
        ) -> wgpu::RenderPipeline,
    ) -> wgpu::RenderPipeline {
        let key = (decl.label, variant);
        if let Some(p) = self.render.get(&key) {
            return p.clone();
        }
        let layout = self.layout(decl);
        let module = self.module(decl);
        let p = build(&self.device, &layout, &module);
        self.render.insert(key, p.clone());
        p
    }
}
