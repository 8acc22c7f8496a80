//! Marker pass: draws the gaze marker over the frame, proving to the viewer that the frame
//! answers their gaze (the position is the one the server used, after any prediction).

use bytemuck::{Pod, Zeroable};

use crate::render::timer::PassTimer;

pub const SHADER: &str = include_str!("../../../shaders/marker.wgsl");
pub const LABEL: &str = "marker";

#[repr(C)]
#[derive(Clone, Copy, Pod, Zeroable)]
struct MarkerUniform {
    centre_radius_thickness: [f32; 4],
}

/// Ring radius and thickness in pixels for a frame: about 3% of the shorter side, never so small
/// that a thumbnail loses it.
pub fn marker_size(width: u32, height: u32) -> (f32, f32) {
    let radius = (0.03 * width.min(height) as f32).max(5.0);
    (radius, (0.22 * radius).max(1.5))
}

pub struct MarkerPass {
    pipeline: wgpu::RenderPipeline,
    uniform: wgpu::Buffer,
    bind_group: wgpu::BindGroup,
}

impl MarkerPass {
    pub fn new(device: &wgpu::Device) -> MarkerPass {
        let module = device.create_shader_module(wgpu::ShaderModuleDescriptor {
            label: Some(LABEL),
            source: wgpu::ShaderSource::Wgsl(SHADER.into()),
        });
        let layout = device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
            label: Some(LABEL),
            entries: &[wgpu::BindGroupLayoutEntry {
                binding: 0,
                visibility: wgpu::ShaderStages::FRAGMENT,
                ty: wgpu::BindingType::Buffer {
                    ty: wgpu::BufferBindingType::Uniform,
                    has_dynamic_offset: false,
                    min_binding_size: None,
                },
                count: None,
            }],
        });
        let pipeline_layout = device.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
            label: Some(LABEL),
            bind_group_layouts: &[Some(&layout)],
            immediate_size: 0,
        });
        let pipeline = device.create_render_pipeline(&wgpu::RenderPipelineDescriptor {
            label: Some(LABEL),
            layout: Some(&pipeline_layout),
            vertex: wgpu::VertexState {
                module: &module,
                entry_point: Some("vs_main"),
                compilation_options: Default::default(),
                buffers: &[],
            },
            primitive: Default::default(),
            depth_stencil: None,
            multisample: Default::default(),
            fragment: Some(wgpu::FragmentState {
                module: &module,
                entry_point: Some("fs_main"),
                compilation_options: Default::default(),
                targets: &[Some(wgpu::ColorTargetState {
                    format: super::output::FORMAT,
                    blend: Some(wgpu::BlendState::PREMULTIPLIED_ALPHA_BLENDING),
                    write_mask: wgpu::ColorWrites::ALL,
                })],
            }),
            multiview_mask: None,
            cache: None,
        });
        let uniform = device.create_buffer(&wgpu::BufferDescriptor {
            label: Some(LABEL),
            size: std::mem::size_of::<MarkerUniform>() as u64,
            usage: wgpu::BufferUsages::UNIFORM | wgpu::BufferUsages::COPY_DST,
            mapped_at_creation: false,
        });
        let bind_group = device.create_bind_group(&wgpu::BindGroupDescriptor {
            label: Some(LABEL),
            layout: &layout,
            entries: &[wgpu::BindGroupEntry { binding: 0, resource: uniform.as_entire_binding() }],
        });
        MarkerPass { pipeline, uniform, bind_group }
    }

    /// Draws the marker at normalised gaze `(x, y)` (top-left origin) over `color`.
    pub fn encode(
        &self,
        queue: &wgpu::Queue,
        encoder: &mut wgpu::CommandEncoder,
        color: &wgpu::TextureView,
        size: (u32, u32),
        gaze: [f32; 2],
        timer: &mut PassTimer,
    ) {
        let (radius, thickness) = marker_size(size.0, size.1);
        let centre = [gaze[0] * size.0 as f32, gaze[1] * size.1 as f32];
        let u = MarkerUniform { centre_radius_thickness: [centre[0], centre[1], radius, thickness] };
        queue.write_buffer(&self.uniform, 0, bytemuck::bytes_of(&u));
        let mut pass = encoder.begin_render_pass(&wgpu::RenderPassDescriptor {
            label: Some(LABEL),
            color_attachments: &[Some(wgpu::RenderPassColorAttachment {
                view: color,
                depth_slice: None,
                resolve_target: None,
                ops: wgpu::Operations { load: wgpu::LoadOp::Load, store: wgpu::StoreOp::Store },
            })],
            depth_stencil_attachment: None,
            timestamp_writes: timer.render(LABEL),
            occlusion_query_set: None,
            multiview_mask: None,
        });
        pass.set_pipeline(&self.pipeline);
        pass.set_bind_group(0, &self.bind_group, &[]);
        pass.draw(0..3, 0..1);
    }
}
