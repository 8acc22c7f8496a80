//! The frame's uniforms: the Rust twin of `struct Frame` in `shaders/common.wgsl`.

use bytemuck::{Pod, Zeroable};

pub const MODE_FOVEATED: u32 = 1;
pub const MODE_SALIENCY: u32 = 2;
pub const MODE_MOTION: u32 = 4;
pub const MODE_WHITE_NOISE: u32 = 8;
pub const MODE_REPROJECTION: u32 = 16;
pub const MODE_SIBSON: u32 = 32;
pub const MODE_DOF: u32 = 64;
pub const MODE_DIRECT_ONLY: u32 = 128;

pub const FLAG_COVERED: u32 = 1;
pub const FLAG_SAMPLED: u32 = 2;
pub const FLAG_REUSED: u32 = 4;

#[repr(C)]
#[derive(Clone, Copy, Pod, Zeroable, Debug, Default)]
pub struct FrameUniform {
    pub view_proj: [[f32; 4]; 4],
    pub inv_view_proj: [[f32; 4]; 4],
    pub prev_view_proj: [[f32; 4]; 4],
    pub eye: [f32; 4],
    pub prev_eye: [f32; 4],
    pub to_light: [f32; 4],
    pub light: [f32; 4],
    pub albedo_ambient: [f32; 4],
    pub background: [f32; 4],
    pub size: [u32; 4],
    pub gaze: [f32; 4],
    pub viewing: [f32; 4],
    pub acuity: [f32; 4],
    pub temporal: [f32; 4],
    pub tile: [u32; 4],
    pub marker: [f32; 4],
    pub photon: [f32; 4],
    pub cut: [f32; 4],
}

#[cfg(test)]
mod tests {
    #[test]
    fn uniform_size_matches_the_wgsl_struct() {
        // 3 mat4x4 + 15 vec4: any drift from common.wgsl shows up here first.
        assert_eq!(std::mem::size_of::<super::FrameUniform>(), 3 * 64 + 15 * 16);
    }
}
