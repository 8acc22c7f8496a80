//! Output pass: linear colour to sRGB bytes, with the sampling overlays.

use crate::render::gpu::{self, FramePass, FLOAT, UINT};

pub const SHADER: &str = include_str!("../../../shaders/output.wgsl");
pub const FORMAT: wgpu::TextureFormat = wgpu::TextureFormat::Rgba8Unorm;

pub fn new(device: &wgpu::Device) -> FramePass {
    FramePass::new(
        device,
        "output",
        SHADER,
        &[
            gpu::uniform(0, false),
            gpu::texture(1, FLOAT),
            gpu::texture(2, UINT),
            gpu::texture(3, FLOAT),
            gpu::storage_texture(4, FORMAT),
        ],
    )
}
