//! Compaction pass: the sampled pixels become one dense list (stream compaction, the thesis's
//! CSR reordering), and the count becomes the indirect dispatch of the shading pass.

use crate::render::gpu;
use crate::render::timer::PassTimer;

pub const SHADER: &str = include_str!("../../../shaders/compact.wgsl");
pub const LABEL: &str = "compact";

pub struct CompactPass {
    compact: wgpu::ComputePipeline,
    args: wgpu::ComputePipeline,
    pub layout: wgpu::BindGroupLayout,
}

impl CompactPass {
    pub fn new(device: &wgpu::Device) -> CompactPass {
        let module = gpu::shader(device, LABEL, SHADER);
        let layout = gpu::layout(
            device,
            LABEL,
            &[
                gpu::uniform(0, false),
                gpu::storage_buffer(1, true),
                gpu::storage_buffer(2, false),
                gpu::storage_buffer(3, false),
            ],
        );
        let compact = gpu::compute_pipeline(device, LABEL, &module, "main", &layout);
        let args = gpu::compute_pipeline(
            device,
            "compact.indirect_args",
            &module,
            "indirect_args",
            &layout,
        );
        CompactPass {
            compact,
            args,
            layout,
        }
    }

    /// `counter` must be zeroed before this runs (the caller clears it in the same encoder).
    pub fn encode(
        &self,
        encoder: &mut wgpu::CommandEncoder,
        bind_group: &wgpu::BindGroup,
        size: (u32, u32),
        timer: &mut PassTimer,
    ) {
        gpu::dispatch_frame(encoder, LABEL, &self.compact, bind_group, size, timer);
        let mut pass = encoder.begin_compute_pass(&wgpu::ComputePassDescriptor {
            label: Some("compact.indirect_args"),
            timestamp_writes: timer.compute(LABEL),
        });
        pass.set_pipeline(&self.args);
        pass.set_bind_group(0, bind_group, &[]);
        pass.dispatch_workgroups(1, 1, 1);
    }
}
