//! Light-space photons (seed 000): the translucent objects rendered from the light into a
//! photon map, which the pyramid pass (`pyramid.rs`) reduces into a quad-tree of clusters.
//! Depends on geometry and light only, so it is built once per static scene and shared by
//! every frame.

use glam::{Mat4, Vec3};

use super::gbuffer::{mesh_pipeline, MeshBuffers, IRRADIANCE};
use super::pyramid;
use crate::render::gpu;
use crate::render::graph::{
    read, texture, uniform, GraphError, PassDecl, Pipelines, Resources, Routes,
};
use crate::render::timer::PassTimer;
use crate::scene::Scene;

/// Photon map side: 64² photons. Light spreads millimetres in the shipped media, and a bunny
/// texel covers ~1.6 mm, so finer maps add cost, not detail (measured in the bench).
pub const SIDE: u32 = crate::scene::plan::PHOTON_MAP_SIDE;
/// Levels 64, 32, …, 1.
pub const LEVELS: u32 = 7;
/// Traversal starts from the 4×4 level (seed 000 starts from 8×8 of a 512² map).
pub const START_LEVEL: u32 = 4;

pub const PASS: PassDecl = PassDecl {
    label: "photons",
    shader: include_str!("../../../shaders/photons.wgsl"),
    // Binding 0 is the frame uniform of the shared prelude, which the photon pass never uses.
    first_binding: 1,
    bindings: &[
        uniform("photons.uniform"),
        read("materials.scene"),
        read("lights.scene"),
        texture("shadow.atlas"),
        texture("shadow.tile_views"),
    ],
    attachments: &[
        "photons.position",
        "photons.normal",
        "photons.irradiance",
        "photons.depth",
    ],
    entry_points: &["vs_main", "fs_main"],
};

#[repr(C)]
#[derive(Clone, Copy, bytemuck::Pod, bytemuck::Zeroable)]
struct PhotonUniform {
    light_view_proj: [[f32; 4]; 4],
    to_light: [f32; 4],
    light: [f32; 4],
    params: [f32; 4],
    /// The key light's shadow map: world → map, and (depth bias, normal offset, 1 when the
    /// photons test it, side), as in the frame uniform.
    shadow_view_proj: [[f32; 4]; 4],
    shadow_params: [f32; 4],
    /// x: the extra punctual lights the photons carry.
    extra: [u32; 4],
}

pub fn node_count() -> u64 {
    (0..LEVELS)
        .map(|l| u64::from((SIDE >> l).max(1)).pow(2))
        .sum()
}

/// One scene's photon map and pyramid on the GPU.
pub struct PhotonMap {
    pub resources: Resources,
    raster_bind: wgpu::BindGroup,
    pyramid_bind: wgpu::BindGroup,
    /// What it was built for.
    pub built_for: Option<PhotonInputs>,
}

impl PhotonMap {
    pub fn nodes(&self) -> Option<&wgpu::Buffer> {
        self.resources.get_buffer("photons.nodes")
    }

    /// The pyramid as the shading pass reads it (`pyramid::copy_to_texels`).
    pub fn node_texels(&self) -> Option<&wgpu::Texture> {
        self.resources
            .get_texture("photons.node_texels")
            .map(|(t, _)| t)
    }
}

/// What a photon map depends on besides the scene: the light's direction and radiosity's
/// irradiance (which snapshot, and whether its interreflected part is included).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct PhotonInputs {
    pub to_light: Vec3,
    pub gi_version: u64,
    pub indirect: bool,
    /// Photons behind an opaque occluder (the key light's shadow map) carry no light.
    pub shadowed: bool,
}

fn raster_pipeline(device: &wgpu::Device, pipelines: &mut Pipelines) -> wgpu::RenderPipeline {
    let layout = pipelines.layout(&PASS);
    let module = pipelines.module(&PASS);
    let targets = [
        wgpu::TextureFormat::Rgba32Float,
        wgpu::TextureFormat::Rgba32Float,
        IRRADIANCE,
    ];
    // Both faces: the light may see an object's inside through an open mesh.
    mesh_pipeline(device, PASS.label, &layout, &module, &targets, None, &[])
}

/// The photon and pyramid pipelines (shared by every scene).
pub struct PhotonPass {
    raster: wgpu::RenderPipeline,
    pyramid: pyramid::PyramidPipelines,
}

impl PhotonPass {
    pub fn new(device: &wgpu::Device, pipelines: &mut Pipelines) -> PhotonPass {
        PhotonPass {
            raster: raster_pipeline(device, pipelines),
            pyramid: pyramid::PyramidPipelines::new(pipelines),
        }
    }

    /// Allocates a scene's photon map; `materials` must mark every translucent material.
    /// `shared` holds the scene's `materials.scene`, `lights.scene`, and its shadow maps
    /// (`shadow.depth`, `shadow.atlas`, `shadow.tile_views`).
    pub fn create_map(
        &self,
        device: &wgpu::Device,
        pipelines: &mut Pipelines,
        shared: &Resources,
    ) -> Result<PhotonMap, GraphError> {
        use wgpu::BufferUsages as B;
        use wgpu::TextureFormat as F;
        let usage = wgpu::TextureUsages::RENDER_ATTACHMENT | wgpu::TextureUsages::TEXTURE_BINDING;
        let tex =
            |label, format, usage| gpu::texture_2d(device, label, (SIDE, SIDE), format, usage);
        let buffer = |label, size: u64, usage| {
            device.create_buffer(&wgpu::BufferDescriptor {
                label: Some(label),
                size,
                usage,
                mapped_at_creation: false,
            })
        };
        let mut r = Resources::default();
        r.texture(
            "photons.position",
            tex("photons.position", F::Rgba32Float, usage),
        );
        r.texture(
            "photons.normal",
            tex("photons.normal", F::Rgba32Float, usage),
        );
        r.texture(
            "photons.irradiance",
            tex("photons.irradiance", IRRADIANCE, usage),
        );
        let depth_usage = wgpu::TextureUsages::RENDER_ATTACHMENT;
        r.texture(
            "photons.depth",
            tex("photons.depth", F::Depth32Float, depth_usage),
        );
        let nodes_usage = B::STORAGE | B::COPY_SRC;
        let nodes = buffer("photons.nodes", pyramid::nodes_bytes(), nodes_usage);
        r.buffer("photons.nodes", nodes);
        let texels_usage = wgpu::TextureUsages::COPY_DST | wgpu::TextureUsages::TEXTURE_BINDING;
        let texels = gpu::texture_2d(
            device,
            "photons.node_texels",
            pyramid::texels_size(),
            F::Rgba32Float,
            texels_usage,
        );
        r.texture("photons.node_texels", texels);
        let uniform_size = std::mem::size_of::<PhotonUniform>() as u64;
        let uniform = buffer("photons.uniform", uniform_size, B::UNIFORM | B::COPY_DST);
        r.buffer("photons.uniform", uniform);
        let levels = pyramid::SLOT * u64::from(LEVELS);
        r.buffer(
            "pyramid.levels",
            buffer("pyramid.levels", levels, B::UNIFORM | B::COPY_DST),
        );
        r.extend(shared);
        let routes = Routes::default();
        let raster_bind = r.bind(device, &pipelines.layout(&PASS), &PASS, &routes)?;
        let pyramid_bind = r.bind(
            device,
            &pipelines.layout(&pyramid::PASS),
            &pyramid::PASS,
            &routes,
        )?;
        Ok(PhotonMap {
            resources: r,
            raster_bind,
            pyramid_bind,
            built_for: None,
        })
    }

    /// Renders the photon map for the light direction in `inputs` and builds the pyramid.
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
    ) -> Result<(), GraphError> {
        let missing = |name| GraphError::Missing {
            pass: PASS.label,
            name,
        };
        let uniform = map
            .resources
            .get_buffer("photons.uniform")
            .ok_or(missing("photons.uniform"))?;
        queue.write_buffer(
            uniform,
            0,
            bytemuck::bytes_of(&photon_uniform(scene, inputs)),
        );
        let view = |name| {
            map.resources
                .get_texture(name)
                .map(|(_, v)| v)
                .ok_or(missing(name))
        };
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
        {
            let mut pass = encoder.begin_render_pass(&wgpu::RenderPassDescriptor {
                label: Some(PASS.label),
                color_attachments: &[
                    attach(view("photons.position")?),
                    attach(view("photons.normal")?),
                    attach(view("photons.irradiance")?),
                ],
                depth_stencil_attachment: Some(wgpu::RenderPassDepthStencilAttachment {
                    view: view("photons.depth")?,
                    depth_ops: Some(wgpu::Operations {
                        load: wgpu::LoadOp::Clear(1.0),
                        store: wgpu::StoreOp::Store,
                    }),
                    stencil_ops: None,
                }),
                timestamp_writes: timer.render(PASS.label),
                occlusion_query_set: None,
                multiview_mask: None,
            });
            super::gbuffer::draw_mesh(&mut pass, &self.raster, &map.raster_bind, mesh);
        }
        let levels = map
            .resources
            .get_buffer("pyramid.levels")
            .ok_or(missing("pyramid.levels"))?;
        self.pyramid
            .record(queue, encoder, levels, &map.pyramid_bind, timer);
        let nodes = map.nodes().ok_or(missing("photons.nodes"))?;
        let texels = map.node_texels().ok_or(missing("photons.node_texels"))?;
        pyramid::copy_to_texels(encoder, nodes, texels);
        map.built_for = Some(inputs);
        Ok(())
    }
}

/// The light camera: orthographic, around the translucent objects' bounding sphere.
fn photon_uniform(scene: &Scene, inputs: PhotonInputs) -> PhotonUniform {
    let to_light = inputs.to_light;
    let shadow = super::shadow::shadow_view(scene, to_light);
    let (centre, radius) = translucent_bounds(scene);
    let up = if to_light.cross(Vec3::Y).length() < 1e-3 {
        Vec3::X
    } else {
        Vec3::Y
    };
    let view = Mat4::look_at_rh(centre + to_light * (radius + 1.0), centre, up);
    let proj = Mat4::orthographic_rh(-radius, radius, -radius, radius, 0.01, 2.0 * radius + 2.0);
    let texel = 2.0 * radius / SIDE as f32;
    let mm = scene.file.mm_per_unit as f32;
    let light = scene.file.light;
    PhotonUniform {
        light_view_proj: (proj * view).to_cols_array_2d(),
        to_light: to_light
            .extend(f32::from(u8::from(inputs.indirect)))
            .to_array(),
        light: (Vec3::from(light.color) * light.intensity)
            .extend(0.0)
            .to_array(),
        params: [SIDE as f32, (texel * mm) * (texel * mm), texel, 0.0],
        shadow_view_proj: shadow.view_proj.to_cols_array_2d(),
        shadow_params: [
            shadow.params[0],
            shadow.params[1],
            f32::from(u8::from(inputs.shadowed)),
            shadow.params[3],
        ],
        extra: [scene.file.lights.len() as u32, 0, 0, 0],
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
    scene.translucent_bounds()
}
