//! Depth-of-field pass: blurs each pixel by the eye's blur circle for the current pupil and the
//! depth under the gaze.

use crate::render::gpu::{self, FramePass, FLOAT};

pub const SHADER: &str = include_str!("../../../shaders/dof.wgsl");

pub fn new(device: &wgpu::Device) -> FramePass {
    FramePass::new(
        device,
        "dof",
        SHADER,
        &[
            gpu::uniform(0, false),
            gpu::texture(1, FLOAT),
            gpu::texture(2, FLOAT),
            gpu::storage_texture(3, wgpu::TextureFormat::Rgba16Float),
        ],
    )
}
