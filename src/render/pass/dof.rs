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
            gpu::storage_buffer(1, true),
            gpu::texture(2, FLOAT),
            gpu::storage_buffer(3, false),
        ],
    )
}
