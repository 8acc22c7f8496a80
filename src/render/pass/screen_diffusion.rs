//! Screen-space diffusion passes (the middle translucency rung): irradiance, then a separable
//! blur by the dipole profile.

use crate::render::gpu::{self, FLOAT};
use crate::render::timer::PassTimer;

pub const SHADER: &str = include_str!("../../../shaders/screen_diffusion.wgsl");
pub const LABEL: &str = "screen_diffusion";

pub struct ScreenDiffusionPass {
    irradiance: wgpu::ComputePipeline,
    horizontal: wgpu::ComputePipeline,
    vertical: wgpu::ComputePipeline,
    pub layout: wgpu::BindGroupLayout,
}

impl ScreenDiffusionPass {
    pub fn new(device: &wgpu::Device) -> ScreenDiffusionPass {
        let module = gpu::shader(device, LABEL, SHADER);
        let layout = gpu::layout(
            device,
            LABEL,
            &[
                gpu::uniform(0, false),
                gpu::texture(1, FLOAT),
                gpu::texture(2, FLOAT),
                gpu::storage_buffer(3, true),
                gpu::storage_buffer(4, true),
                gpu::storage_buffer(5, true),
                gpu::storage_buffer(6, false),
            ],
        );
        ScreenDiffusionPass {
            irradiance: gpu::compute_pipeline(
                device,
                "screen_diffusion.irradiance",
                &module,
                "irradiance",
                &layout,
            ),
            horizontal: gpu::compute_pipeline(
                device,
                "screen_diffusion.horizontal",
                &module,
                "blur_horizontal",
                &layout,
            ),
            vertical: gpu::compute_pipeline(
                device,
                "screen_diffusion.vertical",
                &module,
                "blur_vertical",
                &layout,
            ),
            layout,
        }
    }

    /// `to_b` writes buffer b from a (irradiance writes a... see targets); the three bind groups
    /// are (irradiance → a), (a → b), (b → a).
    pub fn encode(
        &self,
        encoder: &mut wgpu::CommandEncoder,
        binds: [&wgpu::BindGroup; 3],
        size: (u32, u32),
        timer: &mut PassTimer,
    ) {
        let mut pass = encoder.begin_compute_pass(&wgpu::ComputePassDescriptor {
            label: Some(LABEL),
            timestamp_writes: timer.compute(LABEL),
        });
        for (pipeline, bind) in [
            (&self.irradiance, binds[0]),
            (&self.horizontal, binds[1]),
            (&self.vertical, binds[2]),
        ] {
            pass.set_pipeline(pipeline);
            pass.set_bind_group(0, bind, &[]);
            pass.dispatch_workgroups(size.0.div_ceil(8), size.1.div_ceil(8), 1);
        }
    }
}
