//! Everything one stream (a session, or one `fovea render`) needs on the GPU at one frame size:
//! the G-buffer, the sampling and reconstruction textures, the history the next frame reuses,
//! the compaction list, and the bind groups tying them to the passes. Kept per stream because
//! history belongs to one viewer's sequence of frames.

use super::gpu::{self, view};
use super::pass::{gbuffer, jfa, output};
use super::renderer::Passes;
use super::uniforms::FrameUniform;
use super::RenderError;
use crate::foveation::reconstruct::jfa_steps;

use wgpu::TextureFormat as F;
use wgpu::TextureUsages as U;

pub struct FrameTargets {
    pub width: u32,
    pub height: u32,
    pub uniform: wgpu::Buffer,
    pub depth: wgpu::TextureView,
    pub normal_distance: wgpu::Texture,
    pub albedo: wgpu::Texture,
    pub previous: wgpu::Texture,
    pub history_color: wgpu::Texture,
    pub history_normal_distance: wgpu::Texture,
    pub probability: wgpu::Texture,
    pub flags: wgpu::Texture,
    pub color: wgpu::Texture,
    pub seeds: wgpu::Texture,
    /// Jump flooding ping-pong; the result lands in `jfa_result`.
    pub jfa_a: wgpu::Texture,
    pub jfa_b: wgpu::Texture,
    pub resolved: wgpu::Texture,
    /// Owned here; passes reach it through bind groups.
    _dof_color: wgpu::Texture,
    pub final_image: wgpu::Texture,
    pub final_view: wgpu::TextureView,
    /// `[count, workgroups x, y, z]` for the indirect shading dispatch.
    pub counter: wgpu::Buffer,
    pub jfa_steps: usize,
    pub bind: Bindings,
    readback: wgpu::Buffer,
    counter_readback: wgpu::Buffer,
    padded_row: u32,
    /// Last frame's camera, and whether its buffers may be reused.
    pub prev_view_proj: glam::Mat4,
    pub prev_eye: glam::Vec3,
    pub has_history: bool,
    pub frame_index: u32,
    /// Per-step jump sizes for the JFA passes (bound through `bind.jfa`).
    _jump: wgpu::Buffer,
}

pub struct Bindings {
    pub gbuffer: wgpu::BindGroup,
    pub sampling: wgpu::BindGroup,
    pub compact: wgpu::BindGroup,
    pub shade: wgpu::BindGroup,
    pub jfa: Vec<wgpu::BindGroup>,
    pub resolve: wgpu::BindGroup,
    pub dof: wgpu::BindGroup,
    pub output_resolved: wgpu::BindGroup,
    pub output_dof: wgpu::BindGroup,
}

impl FrameTargets {
    pub fn new(
        device: &wgpu::Device,
        queue: &wgpu::Queue,
        passes: &Passes,
        rank_map: &wgpu::TextureView,
        width: u32,
        height: u32,
    ) -> FrameTargets {
        let size = (width, height);
        let tex = |label, format, usage| gpu::texture_2d(device, label, size, format, usage);
        let attach = U::RENDER_ATTACHMENT | U::TEXTURE_BINDING | U::COPY_SRC;
        let store = U::STORAGE_BINDING | U::TEXTURE_BINDING | U::COPY_SRC;
        let depth = tex("gbuffer.depth", gbuffer::DEPTH, U::RENDER_ATTACHMENT);
        let normal_distance = tex("gbuffer.normal_distance", gbuffer::NORMAL_DISTANCE, attach);
        let albedo = tex("gbuffer.albedo", gbuffer::ALBEDO, attach);
        let previous = tex("gbuffer.previous", gbuffer::PREVIOUS, attach);
        let history_color = tex("history.color", F::Rgba16Float, U::TEXTURE_BINDING | U::COPY_DST);
        let history_normal_distance = tex("history.normal_distance", gbuffer::NORMAL_DISTANCE, U::TEXTURE_BINDING | U::COPY_DST);
        let probability = tex("sampling.probability", F::R32Float, store);
        let flags = tex("sampling.flags", F::R32Uint, store);
        let color = tex("shade.color", F::Rgba16Float, store);
        let seeds = tex("sampling.seeds", F::R32Uint, store);
        let jfa_a = tex("jfa.a", F::R32Uint, store);
        let jfa_b = tex("jfa.b", F::R32Uint, store);
        let resolved = tex("resolve.color", F::Rgba16Float, store);
        let dof = tex("dof.color", F::Rgba16Float, store);
        let final_image = tex("output.final", output::FORMAT, store | U::RENDER_ATTACHMENT);

        let uniform = device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("frame.uniform"),
            size: std::mem::size_of::<FrameUniform>() as u64,
            usage: wgpu::BufferUsages::UNIFORM | wgpu::BufferUsages::COPY_DST,
            mapped_at_creation: false,
        });
        let buffer = |label, size: u64, usage| device.create_buffer(&wgpu::BufferDescriptor { label: Some(label), size, usage, mapped_at_creation: false });
        use wgpu::BufferUsages as B;
        let list = buffer("compact.list", u64::from(width) * u64::from(height) * 4, B::STORAGE);
        let counter = buffer("compact.counter", 16, B::STORAGE | B::INDIRECT | B::COPY_SRC | B::COPY_DST);
        let steps = jfa_steps(width, height);
        // Room for the longest step list; each frame writes the steps it runs.
        let jump = buffer("jfa.steps", jfa::SLOT * steps.len() as u64, B::UNIFORM | B::COPY_DST);
        let _ = queue;
        let align = wgpu::COPY_BYTES_PER_ROW_ALIGNMENT;
        let padded_row = (width * 4).div_ceil(align) * align;
        let readback = buffer("output.readback", u64::from(padded_row) * u64::from(height), B::COPY_DST | B::MAP_READ);
        let counter_readback = buffer("compact.counter.readback", 16, B::COPY_DST | B::MAP_READ);

        let u = uniform.as_entire_binding();
        let v = |t: &wgpu::Texture| view(t);
        let (nd, alb, prev, hc, hnd) = (v(&normal_distance), v(&albedo), v(&previous), v(&history_color), v(&history_normal_distance));
        let (prob, fl, col, sd, ja, jb) = (v(&probability), v(&flags), v(&color), v(&seeds), v(&jfa_a), v(&jfa_b));
        let (res, dv, fin) = (v(&resolved), v(&dof), v(&final_image));
        use wgpu::BindingResource::TextureView as T;
        let gbuffer_bg = gpu::bind(device, "gbuffer", &passes.gbuffer.layout, &[u.clone()]);
        let sampling = passes.sampling.bind(
            device,
            &[u.clone(), T(&nd), T(&alb), T(&prev), T(rank_map), T(&hc), T(&hnd), T(&prob), T(&fl), T(&col), T(&sd)],
        );
        let compact = gpu::bind(device, "compact", &passes.compact.layout, &[u.clone(), T(&fl), list.as_entire_binding(), counter.as_entire_binding()]);
        let shade = gpu::bind(
            device,
            "shade",
            &passes.shade.layout,
            &[u.clone(), T(&nd), T(&alb), T(&fl), list.as_entire_binding(), counter.as_entire_binding(), T(&col)],
        );
        let jump_binding = wgpu::BindingResource::Buffer(wgpu::BufferBinding { buffer: &jump, offset: 0, size: wgpu::BufferSize::new(16) });
        // Step 0 reads the seeds; then a → b, b → a, …
        let jfa_groups: Vec<wgpu::BindGroup> = (0..steps.len())
            .map(|i| {
                let (src, dst) = match (i, i % 2) {
                    (0, _) => (&sd, &ja),
                    (_, 1) => (&ja, &jb),
                    _ => (&jb, &ja),
                };
                gpu::bind(device, "jfa", &passes.jfa.layout, &[u.clone(), T(src), T(dst), jump_binding.clone()])
            })
            .collect();
        let nearest = if steps.len() % 2 == 1 { &ja } else { &jb };
        let resolve = passes.resolve.bind(device, &[u.clone(), T(&col), T(nearest), T(&alb), T(&res), T(&nd)]);
        let dof_bg = passes.dof.bind(device, &[u.clone(), T(&res), T(&nd), T(&dv)]);
        let output_resolved = passes.output.bind(device, &[u.clone(), T(&res), T(&fl), T(&prob), T(&fin)]);
        let output_dof = passes.output.bind(device, &[u.clone(), T(&dv), T(&fl), T(&prob), T(&fin)]);
        FrameTargets {
            width,
            height,
            uniform,
            depth: view(&depth),
            final_view: fin.clone(),
            normal_distance,
            albedo,
            previous,
            history_color,
            history_normal_distance,
            probability,
            flags,
            color,
            seeds,
            jfa_a,
            jfa_b,
            resolved,
            _dof_color: dof,
            final_image,
            counter,
            jfa_steps: steps.len(),
            bind: Bindings {
                gbuffer: gbuffer_bg,
                sampling,
                compact,
                shade,
                jfa: jfa_groups,
                resolve,
                dof: dof_bg,
                output_resolved,
                output_dof,
            },
            readback,
            counter_readback,
            padded_row,
            prev_view_proj: glam::Mat4::IDENTITY,
            prev_eye: glam::Vec3::ZERO,
            has_history: false,
            frame_index: 0,
            _jump: jump,
        }
    }

    /// Writes this frame's jump sizes, one per uniform slot.
    pub fn write_jfa_steps(&self, queue: &wgpu::Queue, steps: &[u32]) {
        let mut bytes = vec![0u8; steps.len() * jfa::SLOT as usize];
        for (i, s) in steps.iter().enumerate() {
            let at = i * jfa::SLOT as usize;
            bytes[at..at + 4].copy_from_slice(&s.to_le_bytes());
        }
        queue.write_buffer(&self._jump, 0, &bytes);
    }

    /// The texture holding each pixel's nearest seed after jump flooding.
    pub fn jfa_result(&self) -> &wgpu::Texture {
        if self.jfa_steps % 2 == 1 {
            &self.jfa_a
        } else {
            &self.jfa_b
        }
    }

    pub fn gbuffer_views(&self) -> (wgpu::TextureView, wgpu::TextureView, wgpu::TextureView) {
        (view(&self.normal_distance), view(&self.albedo), view(&self.previous))
    }

    /// Encodes the copies that make this frame next frame's history.
    pub fn keep_history(&self, encoder: &mut wgpu::CommandEncoder) {
        let whole = wgpu::Extent3d { width: self.width, height: self.height, depth_or_array_layers: 1 };
        encoder.copy_texture_to_texture(self.color.as_image_copy(), self.history_color.as_image_copy(), whole);
        encoder.copy_texture_to_texture(self.normal_distance.as_image_copy(), self.history_normal_distance.as_image_copy(), whole);
    }

    /// Copies the final image and the sample count to host memory.
    pub fn read_back(&self, device: &wgpu::Device, queue: &wgpu::Queue) -> Result<(Vec<u8>, u32), RenderError> {
        let mut encoder = device.create_command_encoder(&wgpu::CommandEncoderDescriptor { label: Some("readback") });
        encoder.copy_texture_to_buffer(
            self.final_image.as_image_copy(),
            wgpu::TexelCopyBufferInfo {
                buffer: &self.readback,
                layout: wgpu::TexelCopyBufferLayout { offset: 0, bytes_per_row: Some(self.padded_row), rows_per_image: Some(self.height) },
            },
            wgpu::Extent3d { width: self.width, height: self.height, depth_or_array_layers: 1 },
        );
        encoder.copy_buffer_to_buffer(&self.counter, 0, &self.counter_readback, 0, 16);
        let submission = queue.submit([encoder.finish()]);
        let image = map_read(device, submission.clone(), &self.readback, |bytes| {
            let row = (self.width * 4) as usize;
            let mut pixels = Vec::with_capacity(row * self.height as usize);
            for chunk in bytes.chunks_exact(self.padded_row as usize) {
                pixels.extend_from_slice(&chunk[..row]);
            }
            pixels
        })?;
        let count = map_read(device, submission, &self.counter_readback, |b| u32::from_le_bytes([b[0], b[1], b[2], b[3]]))?;
        Ok((image, count))
    }
}

/// Maps `buffer` after `submission` completes and hands its bytes to `read`.
pub fn map_read<T>(
    device: &wgpu::Device,
    submission: wgpu::SubmissionIndex,
    buffer: &wgpu::Buffer,
    read: impl FnOnce(&[u8]) -> T,
) -> Result<T, RenderError> {
    let (tx, rx) = std::sync::mpsc::channel();
    buffer.map_async(wgpu::MapMode::Read, .., move |r| {
        let _ = tx.send(r);
    });
    device
        .poll(wgpu::PollType::Wait { submission_index: Some(submission), timeout: None })
        .map_err(|e| RenderError::Readback(format!("waiting for the copy: {e}")))?;
    match rx.recv() {
        Ok(Ok(())) => {}
        Ok(Err(e)) => return Err(RenderError::Readback(format!("map failed: {e}"))),
        Err(_) => return Err(RenderError::Readback("map callback never ran".into())),
    }
    let out = {
        let view = buffer.get_mapped_range(..).map_err(|e| RenderError::Readback(format!("mapped range: {e}")))?;
        read(&view)
    };
    buffer.unmap();
    Ok(out)
}
