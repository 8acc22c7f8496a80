//! Shading pass: the frame's shading where it is needed, either over the compacted list
//! (indirect dispatch, cost ∝ samples) or over the whole frame with a mask.

use crate::render::gpu::{self, FLOAT};
use crate::render::timer::PassTimer;

pub const SHADER: &str = include_str!("../../../shaders/shade.wgsl");
pub const LABEL: &str = "shade";

pub struct ShadePass {
    list: wgpu::ComputePipeline,
    grid: wgpu::ComputePipeline,
    pub layout: wgpu::BindGroupLayout,
}

impl ShadePass {
    pub fn new(device: &wgpu::Device) -> ShadePass {
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
                gpu::storage_buffer(7, true),
                gpu::texture(8, FLOAT),
                gpu::storage_buffer(9, true),
                gpu::storage_buffer(10, true),
                gpu::texture(11, FLOAT),
            ],
        );
        let list = gpu::compute_pipeline(device, "shade.list", &module, "shade_list", &layout);
        let grid = gpu::compute_pipeline(device, "shade.grid", &module, "shade_grid", &layout);
        ShadePass { list, grid, layout }
    }

    /// Shades the listed pixels; the workgroup count comes from `counter[1..4]`.
    pub fn encode_list(
        &self,
        encoder: &mut wgpu::CommandEncoder,
        bind_group: &wgpu::BindGroup,
        counter: &wgpu::Buffer,
        timer: &mut PassTimer,
    ) {
        let mut pass = encoder.begin_compute_pass(&wgpu::ComputePassDescriptor {
            label: Some(LABEL),
            timestamp_writes: timer.compute(LABEL),
        });
        pass.set_pipeline(&self.list);
        pass.set_bind_group(0, bind_group, &[]);
        pass.dispatch_workgroups_indirect(counter, 4);
    }

    pub fn encode_grid(
        &self,
        encoder: &mut wgpu::CommandEncoder,
        bind_group: &wgpu::BindGroup,
        size: (u32, u32),
        timer: &mut PassTimer,
    ) {
        gpu::dispatch_frame(encoder, LABEL, &self.grid, bind_group, size, timer);
    }
}
