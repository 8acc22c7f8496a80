//! Light-space photons and their pyramid (seed 000): the translucent objects rendered from the
//! light into a photon map, then reduced level by level into a quad-tree of clusters. Depends
//! on geometry and light only, so it is built once per static scene and shared by every frame.

use glam::{Mat4, Vec3};

use crate::render::gpu::{self, FLOAT};
use crate::render::pass::gbuffer::{MeshBuffers, GI_LAYOUT, IRRADIANCE, VERTEX_LAYOUT};
use crate::render::timer::PassTimer;
use crate::scene::Scene;

pub const PHOTON_SHADER: &str = include_str!("../../../shaders/photons.wgsl");
pub const PYRAMID_SHADER: &str = include_str!("../../../shaders/pyramid.wgsl");
pub const LABEL: &str = "photons";
pub const PYRAMID_LABEL: &str = "pyramid";

/// Photon map side: 64² photons. Light spreads millimetres in the shipped media, and a bunny
/// texel covers ~1.6 mm, so finer maps add cost, not detail (measured in the bench).
pub const SIDE: u32 = 64;
/// Levels 64, 32, …, 1.
pub const LEVELS: u32 = 7;
/// Traversal starts from the 4×4 level (seed 000 starts from 8×8 of a 512² map).
pub const START_LEVEL: u32 = 4;
const SLOT: u64 = 256;

#[repr(C)]
#[derive(Clone, Copy, bytemuck::Pod, bytemuck::Zeroable)]
struct PhotonUniform {
    light_view_proj: [[f32; 4]; 4],
    to_light: [f32; 4],
    light: [f32; 4],
    params: [f32; 4],
}

pub fn node_count() -> u64 {
    (0..LEVELS)
        .map(|l| u64::from((SIDE >> l).max(1)).pow(2))
        .sum()
}

pub struct PhotonPass {
    raster: wgpu::RenderPipeline,
    raster_layout: wgpu::BindGroupLayout,
    leaves: wgpu::ComputePipeline,
    reduce: wgpu::ComputePipeline,
    pyramid_layout: wgpu::BindGroupLayout,
}

/// One scene's photon pyramid on the GPU.
pub struct PhotonMap {
    pub nodes: wgpu::Buffer,
    uniform: wgpu::Buffer,
    levels: wgpu::Buffer,
    position: wgpu::TextureView,
    normal: wgpu::TextureView,
    irradiance: wgpu::TextureView,
    depth: wgpu::TextureView,
    raster_bind: wgpu::BindGroup,
    pyramid_bind: wgpu::BindGroup,
    /// What it was built for.
    pub built_for: Option<PhotonInputs>,
}

/// What a photon map depends on besides the scene: the light's direction and radiosity's
/// irradiance (which snapshot, and whether its interreflected part is included).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct PhotonInputs {
    pub to_light: Vec3,
    pub gi_version: u64,
    pub indirect: bool,
}

impl PhotonPass {
    pub fn new(device: &wgpu::Device) -> PhotonPass {
        let module = gpu::shader(device, LABEL, PHOTON_SHADER);
        let raster_layout = device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
            label: Some(LABEL),
            entries: &[gpu::uniform(1, false), gpu::storage_buffer(2, true)],
        });
        let pipeline_layout = device.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
            label: Some(LABEL),
            bind_group_layouts: &[Some(&raster_layout)],
            immediate_size: 0,
        });
        let target = |f: wgpu::TextureFormat| Some(wgpu::ColorTargetState::from(f));
        let raster = device.create_render_pipeline(&wgpu::RenderPipelineDescriptor {
            label: Some(LABEL),
            layout: Some(&pipeline_layout),
            vertex: wgpu::VertexState {
                module: &module,
                entry_point: Some("vs_main"),
                compilation_options: Default::default(),
                buffers: &[Some(VERTEX_LAYOUT), Some(GI_LAYOUT)],
            },
            // Both faces: the light may see an object's inside through an open mesh.
            primitive: wgpu::PrimitiveState {
                cull_mode: None,
                ..Default::default()
            },
            depth_stencil: Some(wgpu::DepthStencilState {
                format: wgpu::TextureFormat::Depth32Float,
                depth_write_enabled: Some(true),
                depth_compare: Some(wgpu::CompareFunction::Less),
                stencil: Default::default(),
                bias: Default::default(),
            }),
            multisample: Default::default(),
            fragment: Some(wgpu::FragmentState {
                module: &module,
                entry_point: Some("fs_main"),
                compilation_options: Default::default(),
                targets: &[
                    target(wgpu::TextureFormat::Rgba32Float),
                    target(wgpu::TextureFormat::Rgba32Float),
                    target(IRRADIANCE),
                ],
            }),
            multiview_mask: None,
            cache: None,
        });
        let pyramid_module = gpu::shader(device, PYRAMID_LABEL, PYRAMID_SHADER);
        let pyramid_layout = device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
            label: Some(PYRAMID_LABEL),
            entries: &[
                gpu::uniform(1, true),
                gpu::uniform(2, false),
                gpu::storage_buffer(3, true),
                gpu::texture(4, FLOAT),
                gpu::texture(5, FLOAT),
                gpu::storage_buffer(6, false),
                gpu::texture(7, FLOAT),
            ],
        });
        let leaves = gpu::compute_pipeline(
            device,
            "pyramid.leaves",
            &pyramid_module,
            "leaves",
            &pyramid_layout,
        );
        let reduce = gpu::compute_pipeline(
            device,
            "pyramid.reduce",
            &pyramid_module,
            "reduce",
            &pyramid_layout,
        );
        PhotonPass {
            raster,
            raster_layout,
            leaves,
            reduce,
            pyramid_layout,
        }
    }

    /// Allocates a scene's photon map; `materials` must mark every translucent material.
    pub fn create_map(&self, device: &wgpu::Device, materials: &wgpu::Buffer) -> PhotonMap {
        let tex =
            |label, format, usage| gpu::texture_2d(device, label, (SIDE, SIDE), format, usage);
        let usage = wgpu::TextureUsages::RENDER_ATTACHMENT | wgpu::TextureUsages::TEXTURE_BINDING;
        let position = gpu::view(&tex(
            "photons.position",
            wgpu::TextureFormat::Rgba32Float,
            usage,
        ));
        let normal = gpu::view(&tex(
            "photons.normal",
            wgpu::TextureFormat::Rgba32Float,
            usage,
        ));
        let irradiance = gpu::view(&tex("photons.irradiance", IRRADIANCE, usage));
        let depth = gpu::view(&tex(
            "photons.depth",
            wgpu::TextureFormat::Depth32Float,
            wgpu::TextureUsages::RENDER_ATTACHMENT,
        ));
        let buffer = |label, size: u64, usage| {
            device.create_buffer(&wgpu::BufferDescriptor {
                label: Some(label),
                size,
                usage,
                mapped_at_creation: false,
            })
        };
        use wgpu::BufferUsages as B;
        let nodes = buffer("pyramid.nodes", node_count() * 32, B::STORAGE | B::COPY_SRC);
        let uniform = buffer(
            "photons.uniform",
            std::mem::size_of::<PhotonUniform>() as u64,
            B::UNIFORM | B::COPY_DST,
        );
        let levels = buffer(
            "pyramid.levels",
            SLOT * u64::from(LEVELS),
            B::UNIFORM | B::COPY_DST,
        );
        let raster_bind = gpu::bind_at(
            device,
            LABEL,
            &self.raster_layout,
            &[
                (1, uniform.as_entire_binding()),
                (2, materials.as_entire_binding()),
            ],
        );
        let level_binding = wgpu::BindingResource::Buffer(wgpu::BufferBinding {
            buffer: &levels,
            offset: 0,
            size: wgpu::BufferSize::new(16),
        });
        let pyramid_bind = gpu::bind_at(
            device,
            PYRAMID_LABEL,
            &self.pyramid_layout,
            &[
                (1, level_binding),
                (2, uniform.as_entire_binding()),
                (3, materials.as_entire_binding()),
                (4, wgpu::BindingResource::TextureView(&position)),
                (5, wgpu::BindingResource::TextureView(&normal)),
                (6, nodes.as_entire_binding()),
                (7, wgpu::BindingResource::TextureView(&irradiance)),
            ],
        );
        PhotonMap {
            nodes,
            uniform,
            levels,
            position,
            normal,
            irradiance,
            depth,
            raster_bind,
            pyramid_bind,
            built_for: None,
        }
    }

    /// Renders the photon map for light direction `to_light` and builds the pyramid.
    #[allow(clippy::too_many_arguments)]
    pub fn build(
        &self,
        queue: &wgpu::Queue,
        encoder: &mut wgpu::CommandEncoder,
        map: &mut PhotonMap,
        scene: &Scene,
        mesh: &MeshBuffers,
        inputs: PhotonInputs,
        timer: &mut PassTimer,
    ) {
        let to_light = inputs.to_light;
        // An orthographic light camera around the translucent objects' bounding sphere.
        let (centre, radius) = translucent_bounds(scene);
        let up = if to_light.cross(Vec3::Y).length() < 1e-3 {
            Vec3::X
        } else {
            Vec3::Y
        };
        let view = Mat4::look_at_rh(centre + to_light * (radius + 1.0), centre, up);
        let proj =
            Mat4::orthographic_rh(-radius, radius, -radius, radius, 0.01, 2.0 * radius + 2.0);
        let texel = 2.0 * radius / SIDE as f32;
        let mm = scene.file.mm_per_unit as f32;
        let light = scene.file.light;
        let u = PhotonUniform {
            light_view_proj: (proj * view).to_cols_array_2d(),
            to_light: to_light
                .extend(f32::from(u8::from(inputs.indirect)))
                .to_array(),
            light: (Vec3::from(light.color) * light.intensity)
                .extend(0.0)
                .to_array(),
            params: [SIDE as f32, (texel * mm) * (texel * mm), texel, 0.0],
        };
        queue.write_buffer(&map.uniform, 0, bytemuck::bytes_of(&u));
        let mut slots = vec![0u8; (SLOT * u64::from(LEVELS)) as usize];
        let mut offset = 0u32;
        let mut below = 0u32;
        for l in 0..LEVELS {
            let side = (SIDE >> l).max(1);
            let v = [l, side, offset, below];
            let at = (SLOT * u64::from(l)) as usize;
            slots[at..at + 16].copy_from_slice(bytemuck::cast_slice(&v));
            below = offset;
            offset += side * side;
        }
        queue.write_buffer(&map.levels, 0, &slots);
        {
            let attach = |view| {
                Some(wgpu::RenderPassColorAttachment {
                    view,
                    depth_slice: None,
                    resolve_target: None,
                    ops: wgpu::Operations {
                        load: wgpu::LoadOp::Clear(wgpu::Color::TRANSPARENT),
                        store: wgpu::StoreOp::Store,
                    },
                })
            };
            let mut pass = encoder.begin_render_pass(&wgpu::RenderPassDescriptor {
                label: Some(LABEL),
                color_attachments: &[
                    attach(&map.position),
                    attach(&map.normal),
                    attach(&map.irradiance),
                ],
                depth_stencil_attachment: Some(wgpu::RenderPassDepthStencilAttachment {
                    view: &map.depth,
                    depth_ops: Some(wgpu::Operations {
                        load: wgpu::LoadOp::Clear(1.0),
                        store: wgpu::StoreOp::Store,
                    }),
                    stencil_ops: None,
                }),
                timestamp_writes: timer.render(LABEL),
                occlusion_query_set: None,
                multiview_mask: None,
            });
            pass.set_pipeline(&self.raster);
            pass.set_bind_group(0, &map.raster_bind, &[]);
            pass.set_vertex_buffer(0, mesh.vertices.slice(..));
            pass.set_vertex_buffer(1, mesh.gi.slice(..));
            pass.set_index_buffer(mesh.indices.slice(..), wgpu::IndexFormat::Uint32);
            pass.draw_indexed(0..mesh.index_count, 0, 0..1);
        }
        let mut pass = encoder.begin_compute_pass(&wgpu::ComputePassDescriptor {
            label: Some(PYRAMID_LABEL),
            timestamp_writes: timer.compute(PYRAMID_LABEL),
        });
        for l in 0..LEVELS {
            let side = (SIDE >> l).max(1);
            pass.set_pipeline(if l == 0 { &self.leaves } else { &self.reduce });
            pass.set_bind_group(0, &map.pyramid_bind, &[(SLOT * u64::from(l)) as u32]);
            pass.dispatch_workgroups(side.div_ceil(8), side.div_ceil(8), 1);
        }
        map.built_for = Some(inputs);
    }
}

/// A photon's footprint as a disc: radius √(A/π) of one texel's area, in mm.
pub fn photon_radius_mm(scene: &Scene) -> f64 {
    let (_, radius) = translucent_bounds(scene);
    let texel_mm = 2.0 * f64::from(radius) / f64::from(SIDE) * scene.file.mm_per_unit;
    texel_mm / std::f64::consts::PI.sqrt()
}

/// Centre and radius of a sphere around every translucent vertex (scene units).
pub fn translucent_bounds(scene: &Scene) -> (Vec3, f32) {
    let pts: Vec<Vec3> = scene
        .mesh
        .positions
        .iter()
        .zip(&scene.mesh.material)
        .filter(|(_, m)| {
            scene
                .materials
                .get(**m as usize)
                .is_some_and(|(_, mat)| mat.is_translucent())
        })
        .map(|(p, _)| *p)
        .collect();
    if pts.is_empty() {
        return (Vec3::ZERO, 1.0);
    }
    let (lo, hi) = pts.iter().fold(
        (Vec3::splat(f32::MAX), Vec3::splat(f32::MIN)),
        |(a, b), p| (a.min(*p), b.max(*p)),
    );
    let centre = 0.5 * (lo + hi);
    let radius = pts
        .iter()
        .map(|p| p.distance(centre))
        .fold(0.0, f32::max)
        .max(1e-3);
    (centre, radius * 1.01)
}
