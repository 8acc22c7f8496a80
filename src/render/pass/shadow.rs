//! Shadow maps: the key light's (the whole scene rendered from the light, orthographically over
//! the scene's bounding sphere) and the punctual lights' (perspective, in the tiles of one atlas,
//! storing the distance to the light: one tile for a spot light, six for a point light's cube;
//! `render::lights` says which lights get them). The shading passes test against them with a
//! tent-filtered 3×3 PCF (`shadow_factor` and `spot_shadow` in `shaders/common.wgsl`). Like the
//! photon map they depend on geometry and lights only, so they are rendered once per key-light
//! direction.

use glam::{Mat4, Vec3};

use super::gbuffer::{mesh_pipeline, MeshBuffers};
use crate::render::gpu;
use crate::render::graph::{uniform, GraphError, PassDecl, Pipelines, Resources, Routes};
use crate::render::timer::PassTimer;
use crate::scene::Scene;

/// Shadow map side. Over a scene's bounding sphere: 2048 texels keep a 20 cm floor at ~0.1 mm
/// per texel; at 1024 the bunnies' contact shadows already look right.
pub const SIDE: u32 = 1024;
/// Depth bias in texels of the map's depth range (what keeps a lit plane free of acne).
const DEPTH_BIAS_TEXELS: f32 = 1.5;
/// Normal offset in texels: the lookup moves this far off the surface along its normal.
const NORMAL_OFFSET_TEXELS: f32 = 1.0;
/// Tiles in the punctual lights' atlas (a spot takes one, a point light six): lights that do not
/// fit are unshadowed.
pub const ATLAS_TILES: usize = crate::scene::plan::SHADOW_TILES;
/// Side of one tile. 512 keeps a 90° cube face at ~0.3% of the distance per texel.
pub const TILE: u32 = 512;
/// Tiles per atlas row at most (16 tiles: a 2048² atlas).
const COLUMNS: usize = 4;
/// What an empty texel holds: farther than anything (the key map stores depth in 0..1, spot
/// tiles distances, so one clear value serves both).
const FAR: f64 = 1e30;

pub const PASS: PassDecl = PassDecl {
    label: "shadow",
    shader: include_str!("../../../shaders/shadow.wgsl"),
    first_binding: 1,
    bindings: &[uniform("shadow.uniform")],
    attachments: &["shadow.depth", "shadow.z", "shadow.atlas", "shadow.atlas_z"],
    entry_points: &["vs_main", "fs_main"],
};

/// One scene's shadow maps: their textures (bound by the shading passes as `shadow.depth` and
/// `shadow.atlas`) and what they were rendered for.
pub struct ShadowMap {
    pub resources: Resources,
    /// One uniform buffer and bind group per view: the key light, then each spot tile.
    views: Vec<(wgpu::Buffer, wgpu::BindGroup)>,
    pub built_for: Option<Vec3>,
}

/// `ShadowUniform` in `shaders/shadow.wgsl`.
#[repr(C)]
#[derive(Clone, Copy, bytemuck::Pod, bytemuck::Zeroable)]
struct ShadowUniform {
    light_view_proj: [[f32; 4]; 4],
    /// xyz: the light's position; w: 1 to store the distance to it (punctual lights), 0 for depth.
    light_pos: [f32; 4],
}

/// The light camera and the bias values the shading passes need, for one light direction.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ShadowView {
    pub view_proj: Mat4,
    /// x: depth bias; y: normal offset (scene units); z: 1 (shadows on); w: side.
    pub params: [f32; 4],
}

/// The light's orthographic camera around the scene's bounding sphere.
pub fn shadow_view(scene: &Scene, to_light: Vec3) -> ShadowView {
    let (lo, hi) = scene.mesh.bounds();
    let centre = (lo + hi) * 0.5;
    let radius = ((hi - lo).length() * 0.5).max(1e-4);
    let up = if to_light.cross(Vec3::Y).length() < 1e-3 {
        Vec3::X
    } else {
        Vec3::Y
    };
    let margin = radius * 0.05;
    let view = Mat4::look_at_rh(centre + to_light * (radius + margin), centre, up);
    let depth_range = 2.0 * radius + 2.0 * margin;
    let proj = Mat4::orthographic_rh(-radius, radius, -radius, radius, 0.0, depth_range);
    let texel = 2.0 * radius / SIDE as f32;
    ShadowView {
        view_proj: proj * view,
        params: [
            DEPTH_BIAS_TEXELS * texel / depth_range,
            NORMAL_OFFSET_TEXELS * texel,
            1.0,
            SIDE as f32,
        ],
    }
}

fn pipeline(
    device: &wgpu::Device,
    layout: &wgpu::BindGroupLayout,
    module: &wgpu::ShaderModule,
) -> wgpu::RenderPipeline {
    // Both faces: the light sees an open mesh's inside, and a one-sided leaf still shadows.
    mesh_pipeline(
        device,
        PASS.label,
        layout,
        module,
        &[wgpu::TextureFormat::R32Float],
        None,
        &[],
    )
}

impl ShadowMap {
    /// Maps for the key light and `tiles` punctual-light tiles (the atlas sized to hold them).
    pub fn new(
        device: &wgpu::Device,
        pipelines: &mut Pipelines,
        tiles: usize,
    ) -> Result<ShadowMap, GraphError> {
        let mut r = Resources::default();
        let usage = wgpu::TextureUsages::RENDER_ATTACHMENT | wgpu::TextureUsages::TEXTURE_BINDING;
        let depth = wgpu::TextureUsages::RENDER_ATTACHMENT;
        let tiles = tiles.min(ATLAS_TILES);
        let columns = atlas_columns(tiles);
        let rows = tiles.div_ceil(columns).max(1);
        let atlas = (columns as u32 * TILE, rows as u32 * TILE);
        for (name, size, format, usage) in [
            (
                "shadow.depth",
                (SIDE, SIDE),
                wgpu::TextureFormat::R32Float,
                usage,
            ),
            (
                "shadow.z",
                (SIDE, SIDE),
                wgpu::TextureFormat::Depth32Float,
                depth,
            ),
            ("shadow.atlas", atlas, wgpu::TextureFormat::R32Float, usage),
            (
                "shadow.atlas_z",
                atlas,
                wgpu::TextureFormat::Depth32Float,
                depth,
            ),
        ] {
            r.texture(name, gpu::texture_2d(device, name, size, format, usage));
        }
        let layout = pipelines.layout(&PASS);
        let mut views = Vec::new();
        for _ in 0..=tiles {
            let buffer = device.create_buffer(&wgpu::BufferDescriptor {
                label: Some("shadow.uniform"),
                size: std::mem::size_of::<ShadowUniform>() as u64,
                usage: wgpu::BufferUsages::UNIFORM | wgpu::BufferUsages::COPY_DST,
                mapped_at_creation: false,
            });
            let mut one = r.clone();
            one.buffer("shadow.uniform", buffer.clone());
            views.push((
                buffer,
                one.bind(device, &layout, &PASS, &Routes::default())?,
            ));
        }
        Ok(ShadowMap {
            resources: r,
            views,
            built_for: None,
        })
    }

    /// Renders the key light's map for `view` (built for `to_light`) and the punctual lights'
    /// tiles (`tiles`: view-projection and the light's position, in atlas order).
    #[allow(clippy::too_many_arguments)]
    pub fn build(
        &mut self,
        queue: &wgpu::Queue,
        encoder: &mut wgpu::CommandEncoder,
        pipelines: &mut Pipelines,
        mesh: &MeshBuffers,
        view: &ShadowView,
        tiles: &[(Mat4, Vec3)],
        to_light: Vec3,
        timer: &mut PassTimer,
    ) -> Result<(), GraphError> {
        let missing = |name| GraphError::Missing {
            pass: PASS.label,
            name,
        };
        let target = |name| {
            self.resources
                .get_texture(name)
                .map(|(_, v)| v.clone())
                .ok_or(missing(name))
        };
        let pipeline = pipelines.render(&PASS, 0, pipeline);
        let key = ShadowUniform {
            light_view_proj: view.view_proj.to_cols_array_2d(),
            light_pos: [0.0; 4],
        };
        queue.write_buffer(&self.views[0].0, 0, bytemuck::bytes_of(&key));
        {
            let (colour, depth) = (target("shadow.depth")?, target("shadow.z")?);
            let mut pass = begin(encoder, &colour, &depth, timer.render(PASS.label));
            super::gbuffer::draw_mesh(&mut pass, &pipeline, &self.views[0].1, mesh);
        }
        let (colour, depth) = (target("shadow.atlas")?, target("shadow.atlas_z")?);
        let mut pass = begin(encoder, &colour, &depth, None);
        let columns = atlas_columns(tiles.len());
        for (i, (view_proj, position)) in tiles.iter().take(self.views.len() - 1).enumerate() {
            let u = ShadowUniform {
                light_view_proj: view_proj.to_cols_array_2d(),
                light_pos: position.extend(1.0).to_array(),
            };
            queue.write_buffer(&self.views[i + 1].0, 0, bytemuck::bytes_of(&u));
            let (x, y) = tile_origin(i, columns);
            let side = TILE as f32;
            pass.set_viewport(x as f32, y as f32, side, side, 0.0, 1.0);
            super::gbuffer::draw_mesh(&mut pass, &pipeline, &self.views[i + 1].1, mesh);
        }
        drop(pass);
        self.built_for = Some(to_light);
        Ok(())
    }
}

/// Tiles per row of an atlas holding `tiles` (at least one, so an empty atlas is one tile).
pub fn atlas_columns(tiles: usize) -> usize {
    tiles.clamp(1, COLUMNS)
}

/// Top-left texel of tile `i` in an atlas `columns` tiles wide.
fn tile_origin(i: usize, columns: usize) -> (u32, u32) {
    let (x, y) = (i % columns, i / columns);
    (x as u32 * TILE, y as u32 * TILE)
}

/// A render pass that clears `colour` to `FAR` and `depth` to 1.
fn begin<'e>(
    encoder: &'e mut wgpu::CommandEncoder,
    colour: &wgpu::TextureView,
    depth: &wgpu::TextureView,
    timestamps: Option<wgpu::RenderPassTimestampWrites<'e>>,
) -> wgpu::RenderPass<'e> {
    encoder.begin_render_pass(&wgpu::RenderPassDescriptor {
        label: Some(PASS.label),
        color_attachments: &[Some(wgpu::RenderPassColorAttachment {
            view: colour,
            depth_slice: None,
            resolve_target: None,
            ops: wgpu::Operations {
                // Nothing there: farther than anything, so nothing is shadowed.
                load: wgpu::LoadOp::Clear(wgpu::Color {
                    r: FAR,
                    g: 0.0,
                    b: 0.0,
                    a: 0.0,
                }),
                store: wgpu::StoreOp::Store,
            },
        })],
        depth_stencil_attachment: Some(wgpu::RenderPassDepthStencilAttachment {
            view: depth,
            depth_ops: Some(wgpu::Operations {
                load: wgpu::LoadOp::Clear(1.0),
                store: wgpu::StoreOp::Store,
            }),
            stencil_ops: None,
        }),
        timestamp_writes: timestamps,
        occlusion_query_set: None,
        multiview_mask: None,
    })
}
