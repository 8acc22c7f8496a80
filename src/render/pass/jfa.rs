//! Jump flooding: ⌈log2 N⌉ + 1 passes ping-ponging two seed textures, after which every pixel
//! holds its (nearly always exactly) nearest shaded sample. The jump size of each pass comes
//! from a uniform buffer slot selected by dynamic offset.

use crate::render::gpu;
use crate::render::timer::PassTimer;

pub const SHADER: &str = include_str!("../../../shaders/jfa.wgsl");
pub const LABEL: &str = "jfa";
/// Uniform slots must start at multiples of the device's offset alignment (256 by default).
pub const SLOT: u64 = 256;

pub struct JfaPass {
    pipeline: wgpu::ComputePipeline,
    pub layout: wgpu::BindGroupLayout,
}

impl JfaPass {
    pub fn new(device: &wgpu::Device) -> JfaPass {
        let module = gpu::shader(device, LABEL, SHADER);
        let layout = gpu::layout(
            device,
            LABEL,
            &[
                gpu::uniform(0, false),
                gpu::storage_buffer(1, true),
                gpu::storage_buffer(2, false),
                gpu::uniform(3, true),
            ],
        );
        let pipeline = gpu::compute_pipeline(device, LABEL, &module, "main", &layout);
        JfaPass { pipeline, layout }
    }

    /// Runs every step; `bind_groups[i]` reads the input of step i and writes its output.
    pub fn encode(
        &self,
        encoder: &mut wgpu::CommandEncoder,
        bind_groups: &[&wgpu::BindGroup],
        size: (u32, u32),
        timer: &mut PassTimer,
    ) {
        let mut pass = encoder.begin_compute_pass(&wgpu::ComputePassDescriptor {
            label: Some(LABEL),
            timestamp_writes: timer.compute(LABEL),
        });
        pass.set_pipeline(&self.pipeline);
        for (i, bg) in bind_groups.iter().enumerate() {
            pass.set_bind_group(0, *bg, &[(i as u64 * SLOT) as u32]);
            pass.dispatch_workgroups(size.0.div_ceil(8), size.1.div_ceil(8), 1);
        }
    }
}
