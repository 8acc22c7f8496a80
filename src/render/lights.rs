//! Extra punctual lights on the GPU: the Rust twin of `struct PunctualLight` in
//! `shaders/common.wgsl`, uploaded once per scene as `lights.scene`.

use bytemuck::{Pod, Zeroable};
use wgpu::util::DeviceExt;

use crate::optics::lights::Punctual;
use crate::scene::{LightSpec, Scene};

#[repr(C)]
#[derive(Clone, Copy, Pod, Zeroable, Debug, Default, PartialEq)]
pub struct GpuLight {
    /// xyz: position (point, spot) or unit vector towards the light (directional); w: kind.
    pub position_kind: [f32; 4],
    /// rgb: colour × intensity; w: range (0: none).
    pub color_range: [f32; 4],
    /// xyz: spot axis (away from the light); w: cos of the outer angle.
    pub axis_cos_outer: [f32; 4],
    /// x: cos of the inner angle.
    pub cone: [f32; 4],
    /// World → the light's shadow tile (spots with a shadow map).
    pub view_proj: [[f32; 4]; 4],
    /// x: shadow tile index, −1 for none; y: a texel's size per unit of distance from the
    /// light (sets the bias and normal offset); z: tile side.
    pub shadow: [f32; 4],
}

/// The perspective camera of a spot light's shadow map: along its axis, as wide as its outer
/// cone, from near its position to past the scene's far side. (view-projection, position, a
/// texel's size per unit distance).
pub fn spot_view(scene: &Scene, l: &LightSpec) -> Option<(glam::Mat4, glam::Vec3, f32)> {
    let LightSpec::Spot {
        position,
        direction,
        outer_deg,
        ..
    } = *l
    else {
        return None;
    };
    let pos = glam::Vec3::from(position);
    let axis = glam::Vec3::from(direction).normalize_or(-glam::Vec3::Y);
    let up = if axis.y.abs() > 0.99 {
        glam::Vec3::X
    } else {
        glam::Vec3::Y
    };
    let (lo, hi) = scene.mesh.bounds();
    let far = (0..8)
        .map(|k| {
            let corner = glam::Vec3::new(
                if k & 1 == 0 { lo.x } else { hi.x },
                if k & 2 == 0 { lo.y } else { hi.y },
                if k & 4 == 0 { lo.z } else { hi.z },
            );
            corner.distance(pos)
        })
        .fold(0.0f32, f32::max)
        * 1.01;
    let near = ((hi - lo).length() * 1e-3).max(1e-4);
    let fov = (2.0 * outer_deg).clamp(1.0, 170.0).to_radians();
    let proj = glam::Mat4::perspective_rh(fov, 1.0, near, far.max(near * 2.0));
    let view = glam::Mat4::look_at_rh(pos, pos + axis, up);
    let texel = 2.0 * (fov * 0.5).tan() / crate::render::pass::shadow::SPOT_TILE as f32;
    Some((proj * view, pos, texel))
}

/// The scene's shadowed spot lights in tile order: (view-projection, position).
pub fn shadowed_spots(scene: &Scene) -> Vec<(glam::Mat4, glam::Vec3)> {
    scene
        .file
        .lights
        .iter()
        .filter_map(|l| spot_view(scene, l))
        .take(crate::render::pass::shadow::SPOTS)
        .map(|(m, p, _)| (m, p))
        .collect()
}

pub fn gpu_light(l: &LightSpec) -> GpuLight {
    let mut g = unshadowed(l);
    g.shadow[0] = -1.0;
    g
}

fn unshadowed(l: &LightSpec) -> GpuLight {
    let p = Punctual::of(l);
    GpuLight {
        position_kind: p.at.extend(p.kind as f32).to_array(),
        color_range: p.radiance.extend(p.range).to_array(),
        axis_cos_outer: p.axis.extend(p.cos_outer).to_array(),
        cone: [p.cos_inner, 0.0, 0.0, 0.0],
        ..Default::default()
    }
}

/// The scene's extra lights (one unused entry when it has none: storage buffers cannot be
/// empty).
pub fn upload(device: &wgpu::Device, scene: &Scene) -> wgpu::Buffer {
    let mut tiles = 0;
    let mut lights: Vec<GpuLight> = scene
        .file
        .lights
        .iter()
        .map(|l| {
            let mut g = gpu_light(l);
            if let Some((view_proj, _, texel)) = spot_view(scene, l) {
                if tiles < crate::render::pass::shadow::SPOTS {
                    g.view_proj = view_proj.to_cols_array_2d();
                    g.shadow = [
                        tiles as f32,
                        texel,
                        crate::render::pass::shadow::SPOT_TILE as f32,
                        0.0,
                    ];
                    tiles += 1;
                }
            }
            g
        })
        .collect();
    if lights.is_empty() {
        lights.push(GpuLight::default());
    }
    device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
        label: Some("lights.scene"),
        contents: bytemuck::cast_slice(&lights),
        usage: wgpu::BufferUsages::STORAGE,
    })
}
