//! Output pass: linear colour to sRGB bytes, the sampling overlays, and the gaze marker that
//! proves to the viewer the frame answers their gaze (drawn at the position the server used).

use crate::render::gpu::{self, FramePass};

pub const SHADER: &str = include_str!("../../../shaders/output.wgsl");

pub fn new(device: &wgpu::Device) -> FramePass {
    FramePass::new(
        device,
        "output",
        SHADER,
        &[
            gpu::uniform(0, false),
            gpu::storage_buffer(1, true),
            gpu::storage_buffer(2, true),
            gpu::storage_buffer(3, true),
            gpu::storage_buffer(4, false),
        ],
    )
}

/// Marker ring radius and thickness in pixels: about 3% of the shorter side, never so small
/// that a thumbnail loses it.
pub fn marker_size(width: u32, height: u32) -> (f32, f32) {
    let radius = (0.03 * width.min(height) as f32).max(5.0);
    (radius, (0.22 * radius).max(1.5))
}
