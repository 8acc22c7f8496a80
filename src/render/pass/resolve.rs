//! Resolve pass: background, shaded and reused pixels as they are, the rest reconstructed from
//! the jump-flooding result (nearest sample or windowed approximate Sibson).

use crate::render::gpu::{self, FramePass, FLOAT};

pub const SHADER: &str = include_str!("../../../shaders/resolve.wgsl");

pub fn new(device: &wgpu::Device) -> FramePass {
    FramePass::new(
        device,
        "resolve",
        SHADER,
        &[
            gpu::uniform(0, false),
            gpu::storage_buffer(1, true),
            gpu::storage_buffer(2, true),
            gpu::texture(3, FLOAT),
            gpu::storage_buffer(4, false),
            gpu::texture(5, FLOAT),
            gpu::storage_buffer(6, true),
        ],
    )
}
