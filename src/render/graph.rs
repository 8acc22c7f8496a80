//! A small frame graph. Each pass declares once, in a [`PassDecl`], the named resources it binds
//! (with how it uses them) and the render targets it writes. From that one declaration come the
//! bind group layout, the bind groups (built on first use and cached by a [`BindKey`]) and the
//! naga test that holds every declaration to its shader (`tests/shaders.rs`).
//!
//! Names are dotted, `owner.what` (`gbuffer.normal_distance`, `history.color`,
//! `jfa.seeds[ping]`). A pass may also bind a *port*, a name that the frame routes to a real
//! resource while it records (`frame.color` is whichever buffer holds the newest colour;
//! `jfa.in`/`jfa.out` alternate between the ping-pong buffers), so an optional pass is skipped
//! by the plan rather than by extra bind-group variants.

use std::collections::HashMap;

use super::gpu;
use super::timer::PassTimer;

pub use super::pipelines::{Pipelines, Specialised, MAX_SPECIALISED};

pub use super::binding::{
    dynamic_uniform, layers, read, sampler, texture, texture_array, uint_texture, uniform, write,
    write_uint, Access, Binding,
};

/// Everything the graph needs to know about a pass, stated once beside its shader.
#[derive(Debug)]
pub struct PassDecl {
    /// Pipeline and timing label.
    pub label: &'static str,
    /// The pass's WGSL, without the shared prelude.
    pub shader: &'static str,
    /// Binding number of `bindings[0]`; the rest follow in order.
    pub first_binding: u32,
    pub bindings: &'static [Binding],
    /// Render targets the pass writes (not bindings): colour attachments, then depth.
    pub attachments: &'static [&'static str],
    /// The shader entry points the pass runs.
    pub entry_points: &'static [&'static str],
}

impl PassDecl {
    /// Binding numbers with their declarations.
    pub fn numbered(&self) -> impl Iterator<Item = (u32, &Binding)> {
        (self.first_binding..).zip(self.bindings.iter())
    }

    /// Names the pass reads (bindings only; a read-write binding counts as both).
    pub fn reads(&self) -> Vec<&'static str> {
        self.bindings
            .iter()
            .filter(|b| !b.access.writes())
            .map(|b| b.name)
            .collect()
    }

    /// Names the pass writes: read-write bindings and render targets.
    pub fn writes(&self) -> Vec<&'static str> {
        self.bindings
            .iter()
            .filter(|b| b.access.writes())
            .map(|b| b.name)
            .chain(self.attachments.iter().copied())
            .collect()
    }

    pub(super) fn layout_entries(&self) -> Vec<wgpu::BindGroupLayoutEntry> {
        self.numbered()
            .map(|(i, b)| b.access.layout_entry(i))
            .collect()
    }
}

#[derive(Debug, thiserror::Error)]
pub enum GraphError {
    /// A scene buffer (what, bytes) past the device's `max_buffer_size`.
    #[error("the scene's {0} need a {1}-byte buffer and this device allows {2}")]
    TooLarge(&'static str, u64, u64),
    #[error("pass {pass}: no resource named {name:?}")]
    Missing {
        pass: &'static str,
        name: &'static str,
    },
    #[error("pass {pass}: {name:?} is a {found}, but the pass binds it as {wanted:?}")]
    Kind {
        pass: &'static str,
        name: &'static str,
        found: &'static str,
        wanted: Access,
    },
}

/// A GPU resource the graph can bind.
#[derive(Debug, Clone)]
pub enum Resource {
    Buffer(wgpu::Buffer),
    Texture(wgpu::Texture, wgpu::TextureView),
    Sampler(wgpu::Sampler),
}

/// Named resources: one stream's targets with the scene's and the renderer's shared ones.
#[derive(Debug, Default, Clone)]
pub struct Resources {
    map: HashMap<&'static str, Resource>,
}

impl Resources {
    pub fn buffer(&mut self, name: &'static str, buffer: wgpu::Buffer) {
        self.map.insert(name, Resource::Buffer(buffer));
    }

    pub fn texture(&mut self, name: &'static str, texture: wgpu::Texture) {
        let view = gpu::view(&texture);
        self.map.insert(name, Resource::Texture(texture, view));
    }

    /// A texture bound as an array of layers (`texture_2d_array`), whatever its layer count.
    pub fn texture_array(&mut self, name: &'static str, texture: wgpu::Texture) {
        let view = texture.create_view(&wgpu::TextureViewDescriptor {
            dimension: Some(wgpu::TextureViewDimension::D2Array),
            ..Default::default()
        });
        self.map.insert(name, Resource::Texture(texture, view));
    }

    pub fn sampler(&mut self, name: &'static str, sampler: wgpu::Sampler) {
        self.map.insert(name, Resource::Sampler(sampler));
    }

    /// Adds every resource of `other` (same names are replaced).
    pub fn extend(&mut self, other: &Resources) {
        self.map
            .extend(other.map.iter().map(|(k, v)| (*k, v.clone())));
    }

    pub fn get(&self, name: &'static str) -> Option<&Resource> {
        self.map.get(name)
    }

    pub fn get_buffer(&self, name: &'static str) -> Option<&wgpu::Buffer> {
        match self.map.get(name) {
            Some(Resource::Buffer(b)) => Some(b),
            _ => None,
        }
    }

    pub fn get_texture(&self, name: &'static str) -> Option<(&wgpu::Texture, &wgpu::TextureView)> {
        match self.map.get(name) {
            Some(Resource::Texture(t, v)) => Some((t, v)),
            _ => None,
        }
    }

    /// Bind group for `decl`, each name first looked up in `routes` (ports), then here.
    pub fn bind(
        &self,
        device: &wgpu::Device,
        layout: &wgpu::BindGroupLayout,
        decl: &PassDecl,
        routes: &Routes,
    ) -> Result<wgpu::BindGroup, GraphError> {
        let mut entries = Vec::with_capacity(decl.bindings.len());
        for (i, b) in decl.numbered() {
            let name = routes.resolve(b.name);
            let missing = GraphError::Missing {
                pass: decl.label,
                name,
            };
            let resource = match (self.map.get(name).ok_or(missing)?, b.access) {
                (
                    Resource::Texture(_, view),
                    Access::Texture
                    | Access::TextureArray
                    | Access::Layers
                    | Access::UintTexture
                    | Access::WriteUint,
                ) => wgpu::BindingResource::TextureView(view),
                (Resource::Sampler(s), Access::Sampler) => wgpu::BindingResource::Sampler(s),
                (Resource::Buffer(buf), Access::DynamicUniform { size }) => {
                    wgpu::BindingResource::Buffer(wgpu::BufferBinding {
                        buffer: buf,
                        offset: 0,
                        size: wgpu::BufferSize::new(size),
                    })
                }
                (Resource::Buffer(buf), Access::Uniform | Access::Read | Access::ReadWrite) => {
                    buf.as_entire_binding()
                }
                (r, wanted) => {
                    return Err(GraphError::Kind {
                        pass: decl.label,
                        name,
                        found: match r {
                            Resource::Buffer(_) => "buffer",
                            Resource::Texture(..) => "texture",
                            Resource::Sampler(_) => "sampler",
                        },
                        wanted,
                    })
                }
            };
            entries.push(wgpu::BindGroupEntry {
                binding: i,
                resource,
            });
        }
        Ok(device.create_bind_group(&wgpu::BindGroupDescriptor {
            label: Some(decl.label),
            layout,
            entries: &entries,
        }))
    }
}

/// Ports and the resources they stand for while a frame is recorded.
#[derive(Debug, Default, Clone)]
pub struct Routes(HashMap<&'static str, &'static str>);

impl Routes {
    pub fn set(&mut self, port: &'static str, to: &'static str) {
        self.0.insert(port, to);
    }

    /// The resource a name stands for: its route if it is a port, else itself.
    pub fn resolve(&self, name: &'static str) -> &'static str {
        self.0.get(name).copied().unwrap_or(name)
    }
}

/// What a cached bind group was built from: the pass and the resource behind each binding.
#[derive(Debug, Clone, PartialEq, Eq, Hash)]
pub struct BindKey {
    pub pass: &'static str,
    pub resources: Vec<&'static str>,
}

/// One dispatch inside a compute pass.
pub struct Dispatch {
    pub pipeline: wgpu::ComputePipeline,
    pub bind_group: wgpu::BindGroup,
    pub offsets: Vec<u32>,
    pub size: DispatchSize,
}

pub enum DispatchSize {
    /// The frame in 8×8 tiles.
    Frame,
    Groups(u32, u32, u32),
    /// Workgroup counts read from a buffer at a byte offset.
    Indirect(wgpu::Buffer, u64),
}

/// Records one frame's passes: the encoder, the named resources and their cached bind groups.
pub struct Recorder<'a> {
    pub device: &'a wgpu::Device,
    pub queue: &'a wgpu::Queue,
    pub encoder: &'a mut wgpu::CommandEncoder,
    pub pipelines: &'a mut Pipelines,
    pub resources: &'a Resources,
    pub binds: &'a mut HashMap<BindKey, wgpu::BindGroup>,
    pub routes: Routes,
    pub timer: &'a mut PassTimer,
    pub size: (u32, u32),
    /// The frame's MODE_* bits, as its uniforms hold them.
    pub mode: u32,
    /// The kinds of material the scene has (`materials::KIND_*` bits).
    pub scene_kinds: u32,
    /// The frame's translucency rung (`Rung::id`), as its uniforms hold it.
    pub rung: u32,
}

impl Recorder<'_> {
    /// Points a port at a resource for the passes recorded after this.
    pub fn route(&mut self, port: &'static str, to: &'static str) {
        self.routes.set(port, to);
    }

    pub fn buffer(&self, name: &'static str) -> Result<&wgpu::Buffer, GraphError> {
        let name = self.routes.resolve(name);
        self.resources.get_buffer(name).ok_or(GraphError::Missing {
            pass: "frame",
            name,
        })
    }

    pub fn view(&self, name: &'static str) -> Result<&wgpu::TextureView, GraphError> {
        let name = self.routes.resolve(name);
        self.resources
            .get_texture(name)
            .map(|(_, v)| v)
            .ok_or(GraphError::Missing {
                pass: "frame",
                name,
            })
    }

    /// The pass's bind group for the current routes, built on first use.
    pub fn bind_group(&mut self, decl: &PassDecl) -> Result<wgpu::BindGroup, GraphError> {
        let key = BindKey {
            pass: decl.label,
            resources: decl
                .bindings
                .iter()
                .map(|b| self.routes.resolve(b.name))
                .collect(),
        };
        if let Some(bg) = self.binds.get(&key) {
            return Ok(bg.clone());
        }
        let layout = self.pipelines.layout(decl);
        let bg = self
            .resources
            .bind(self.device, &layout, decl, &self.routes)?;
        self.binds.insert(key, bg.clone());
        Ok(bg)
    }

    /// A dispatch of `entry` over the frame with the pass's current bind group.
    pub fn frame_dispatch(
        &mut self,
        decl: &PassDecl,
        entry: &'static str,
    ) -> Result<Dispatch, GraphError> {
        self.dispatch(decl, entry, DispatchSize::Frame)
    }

    pub fn dispatch(
        &mut self,
        decl: &PassDecl,
        entry: &'static str,
        size: DispatchSize,
    ) -> Result<Dispatch, GraphError> {
        self.dispatch_by(decl, entry, size, Specialised::default())
    }

    /// Specialised for this frame's mode bits: branches on modes the frame is not in cost
    /// nothing, which on a software adapter, where all of a shader's code shapes its cost,
    /// measured a third off the sampling pass (docs/foveation.md).
    pub fn by_mode(&self) -> Specialised {
        Specialised {
            mode: Some(self.mode),
            ..Default::default()
        }
    }

    /// Specialised for the kinds of material the scene has and the frame's translucency rung
    /// (the shading shader's `SCENE_KINDS`, `FRAME_RUNG`): other kinds' and rungs' branches
    /// are compiled out.
    pub fn by_scene(&self) -> Specialised {
        Specialised {
            scene_kinds: Some(self.scene_kinds),
            rung: Some(self.rung),
            ..Default::default()
        }
    }

    /// A dispatch whose pipeline is specialised as `by` says.
    pub fn dispatch_by(
        &mut self,
        decl: &PassDecl,
        entry: &'static str,
        size: DispatchSize,
        by: Specialised,
    ) -> Result<Dispatch, GraphError> {
        let label = if entry == "main" { decl.label } else { entry };
        Ok(Dispatch {
            pipeline: self.pipelines.compute_for(decl, entry, label, by),
            bind_group: self.bind_group(decl)?,
            offsets: Vec::new(),
            size,
        })
    }

    /// One compute pass, timed under `label`, running `dispatches` in order.
    pub fn compute(&mut self, label: &'static str, dispatches: &[Dispatch]) {
        let (w, h) = self.size;
        let mut pass = self
            .encoder
            .begin_compute_pass(&wgpu::ComputePassDescriptor {
                label: Some(label),
                timestamp_writes: self.timer.compute(label),
            });
        for d in dispatches {
            run(&mut pass, d, (w, h));
        }
    }

    /// The common case: one pass, one `main` dispatch over the frame.
    pub fn run_frame_pass(&mut self, decl: &PassDecl) -> Result<(), GraphError> {
        let d = self.frame_dispatch(decl, "main")?;
        self.compute(decl.label, &[d]);
        Ok(())
    }
}

/// Records one dispatch into `pass`; `size` is the frame's, for `DispatchSize::Frame`.
pub fn run(pass: &mut wgpu::ComputePass<'_>, d: &Dispatch, (w, h): (u32, u32)) {
    pass.set_pipeline(&d.pipeline);
    pass.set_bind_group(0, &d.bind_group, &d.offsets);
    match &d.size {
        DispatchSize::Frame => pass.dispatch_workgroups(w.div_ceil(8), h.div_ceil(8), 1),
        DispatchSize::Groups(x, y, z) => pass.dispatch_workgroups(*x, *y, *z),
        DispatchSize::Indirect(buffer, offset) => {
            pass.dispatch_workgroups_indirect(buffer, *offset)
        }
    }
}
