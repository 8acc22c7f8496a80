//! Sampling pass: per-pixel sampling probability (MAR, saliency, motion, depth of field), the
//! blue- or white-noise decision, and the reprojection cache test for pixels not chosen.
//! Writes probability, flags, reused colours and the seeds jump flooding starts from.

use crate::render::gpu::{self, FramePass, FLOAT};

pub const SHADER: &str = include_str!("../../../shaders/sampling.wgsl");

pub fn new(device: &wgpu::Device) -> FramePass {
    use wgpu::TextureFormat as F;
    FramePass::new(
        device,
        "sampling",
        SHADER,
        &[
            gpu::uniform(0, false),
            gpu::texture(1, FLOAT),
            gpu::texture(2, FLOAT),
            gpu::texture(3, FLOAT),
            gpu::texture(4, FLOAT),
            gpu::texture(5, FLOAT),
            gpu::texture(6, FLOAT),
            gpu::storage_texture(7, F::R32Float),
            gpu::storage_texture(8, F::R32Uint),
            gpu::storage_texture(9, F::Rgba16Float),
            gpu::storage_texture(10, F::R32Uint),
        ],
    )
}
