//! Extra punctual lights on the GPU: the Rust twin of `struct PunctualLight` in
//! `shaders/common.wgsl`, uploaded once per scene as `lights.scene`.

use bytemuck::{Pod, Zeroable};
use wgpu::util::DeviceExt;

use crate::scene::{LightSpec, Scene};

pub const DIRECTIONAL: u32 = 0;
pub const POINT: u32 = 1;
pub const SPOT: u32 = 2;

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
}

pub fn gpu_light(l: &LightSpec) -> GpuLight {
    let rgb = |c: [f32; 3], i: f32| [c[0] * i, c[1] * i, c[2] * i];
    let with = |v: [f32; 3], w: f32| [v[0], v[1], v[2], w];
    match *l {
        LightSpec::Directional {
            to_light,
            color,
            intensity,
        } => GpuLight {
            position_kind: with(
                glam::Vec3::from(to_light).normalize_or_zero().into(),
                DIRECTIONAL as f32,
            ),
            color_range: with(rgb(color, intensity), 0.0),
            ..Default::default()
        },
        LightSpec::Point {
            position,
            color,
            intensity,
            range,
        } => GpuLight {
            position_kind: with(position, POINT as f32),
            color_range: with(rgb(color, intensity), range.unwrap_or(0.0)),
            ..Default::default()
        },
        LightSpec::Spot {
            position,
            direction,
            color,
            intensity,
            range,
            inner_deg,
            outer_deg,
        } => GpuLight {
            position_kind: with(position, SPOT as f32),
            color_range: with(rgb(color, intensity), range.unwrap_or(0.0)),
            axis_cos_outer: with(
                glam::Vec3::from(direction).normalize_or_zero().into(),
                outer_deg.to_radians().cos(),
            ),
            cone: [inner_deg.to_radians().cos(), 0.0, 0.0, 0.0],
        },
    }
}

/// The scene's extra lights (one unused entry when it has none: storage buffers cannot be
/// empty).
pub fn upload(device: &wgpu::Device, scene: &Scene) -> wgpu::Buffer {
    let mut lights: Vec<GpuLight> = scene.file.lights.iter().map(gpu_light).collect();
    if lights.is_empty() {
        lights.push(GpuLight::default());
    }
    device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
        label: Some("lights.scene"),
        contents: bytemuck::cast_slice(&lights),
        usage: wgpu::BufferUsages::STORAGE,
    })
}
