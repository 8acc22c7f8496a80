//! Shadow map of the key light: the whole scene rendered from the light, orthographically over
//! the scene's bounding sphere, into a depth image the shading passes test against with a
//! tent-filtered 3×3 PCF (`shadow_factor` in `shaders/common.wgsl`). Like the photon map it
//! depends on geometry and light only, so it is rendered once per light direction.

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

pub const PASS: PassDecl = PassDecl {
    label: "shadow",
    shader: include_str!("../../../shaders/shadow.wgsl"),
    first_binding: 1,
    bindings: &[uniform("shadow.uniform")],
    attachments: &["shadow.depth", "shadow.z"],
    entry_points: &["vs_main", "fs_main"],
};

/// One scene's shadow map: its texture (bound by the shading passes as `shadow.depth`) and
/// what it was rendered for.
pub struct ShadowMap {
    pub resources: Resources,
    bind: wgpu::BindGroup,
    pub built_for: Option<Vec3>,
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
    )
}

impl ShadowMap {
    pub fn new(device: &wgpu::Device, pipelines: &mut Pipelines) -> Result<ShadowMap, GraphError> {
        let mut r = Resources::default();
        let usage = wgpu::TextureUsages::RENDER_ATTACHMENT | wgpu::TextureUsages::TEXTURE_BINDING;
        r.texture(
            "shadow.depth",
            gpu::texture_2d(
                device,
                "shadow.depth",
                (SIDE, SIDE),
                wgpu::TextureFormat::R32Float,
                usage,
            ),
        );
        r.texture(
            "shadow.z",
            gpu::texture_2d(
                device,
                "shadow.z",
                (SIDE, SIDE),
                wgpu::TextureFormat::Depth32Float,
                wgpu::TextureUsages::RENDER_ATTACHMENT,
            ),
        );
        r.buffer(
            "shadow.uniform",
            device.create_buffer(&wgpu::BufferDescriptor {
                label: Some("shadow.uniform"),
                size: 64,
                usage: wgpu::BufferUsages::UNIFORM | wgpu::BufferUsages::COPY_DST,
                mapped_at_creation: false,
            }),
        );
        let bind = r.bind(device, &pipelines.layout(&PASS), &PASS, &Routes::default())?;
        Ok(ShadowMap {
            resources: r,
            bind,
            built_for: None,
        })
    }

    /// Renders the map for `view` (built for `to_light`).
    #[allow(clippy::too_many_arguments)]
    pub fn build(
        &mut self,
        queue: &wgpu::Queue,
        encoder: &mut wgpu::CommandEncoder,
        pipelines: &mut Pipelines,
        mesh: &MeshBuffers,
        view: &ShadowView,
        to_light: Vec3,
        timer: &mut PassTimer,
    ) -> Result<(), GraphError> {
        let missing = |name| GraphError::Missing {
            pass: PASS.label,
            name,
        };
        let uniform = self
            .resources
            .get_buffer("shadow.uniform")
            .ok_or(missing("shadow.uniform"))?;
        queue.write_buffer(
            uniform,
            0,
            bytemuck::bytes_of(&view.view_proj.to_cols_array_2d()),
        );
        let target = |name| {
            self.resources
                .get_texture(name)
                .map(|(_, v)| v)
                .ok_or(missing(name))
        };
        let pipeline = pipelines.render(&PASS, pipeline);
        let mut pass = encoder.begin_render_pass(&wgpu::RenderPassDescriptor {
            label: Some(PASS.label),
            color_attachments: &[Some(wgpu::RenderPassColorAttachment {
                view: target("shadow.depth")?,
                depth_slice: None,
                resolve_target: None,
                ops: wgpu::Operations {
                    // Nothing there: as far as the map reaches, so nothing is shadowed.
                    load: wgpu::LoadOp::Clear(wgpu::Color {
                        r: 1.0,
                        g: 0.0,
                        b: 0.0,
                        a: 0.0,
                    }),
                    store: wgpu::StoreOp::Store,
                },
            })],
            depth_stencil_attachment: Some(wgpu::RenderPassDepthStencilAttachment {
                view: target("shadow.z")?,
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
        super::gbuffer::draw_mesh(&mut pass, &pipeline, &self.bind, mesh);
        drop(pass);
        self.built_for = Some(to_light);
        Ok(())
    }
}
