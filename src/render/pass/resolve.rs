//! Resolve pass: background, shaded and reused pixels as they are, the rest reconstructed from
//! the jump-flooding result (nearest sample or windowed approximate Sibson).

use crate::render::gpu::{self, FramePass, FLOAT, UINT};

pub const SHADER: &str = include_str!("../../../shaders/resolve.wgsl");

pub fn new(device: &wgpu::Device) -> FramePass {
    FramePass::new(
        device,
        "resolve",
        SHADER,
        &[
            gpu::uniform(0, false),
            gpu::texture(1, FLOAT),
            gpu::texture(2, UINT),
            gpu::texture(3, FLOAT),
            gpu::storage_texture(4, wgpu::TextureFormat::Rgba16Float),
            gpu::texture(5, FLOAT),
        ],
    )
}
