//! Sampling pass: per-pixel sampling probability (MAR, saliency, motion, depth of field), the
//! blue- or white-noise decision, and the reprojection cache test for pixels not chosen.
//! Writes probability, flags, reused colours and the seeds jump flooding starts from.

use crate::render::gpu::{self, FramePass, FLOAT};

pub const SHADER: &str = include_str!("../../../shaders/sampling.wgsl");

pub fn new(device: &wgpu::Device) -> FramePass {
    FramePass::new(
        device,
        "sampling",
        SHADER,
        &[
            gpu::uniform(0, false),
            gpu::texture(1, FLOAT),
            gpu::texture(2, FLOAT),
            gpu::storage_buffer(3, true),
            gpu::texture(4, FLOAT),
            gpu::storage_buffer(5, true),
            gpu::texture(6, FLOAT),
            gpu::storage_buffer(7, false),
            gpu::storage_buffer(8, false),
            gpu::storage_buffer(9, false),
            gpu::storage_buffer(10, false),
        ],
    )
}
