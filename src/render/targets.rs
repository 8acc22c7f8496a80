//! Everything one stream (a session, or one `fovea render`) needs on the GPU at one frame size:
//! the G-buffer, the per-pixel buffers of sampling and reconstruction, the history the next
//! frame reuses, the compaction list, and the bind groups tying them to the passes. Kept per
//! stream because history belongs to one viewer's sequence of frames.

use super::gpu::{self, view};
use super::pass::{gbuffer, jfa};
use super::renderer::{Passes, SceneGpu};
use super::uniforms::FrameUniform;
use super::RenderError;
use crate::foveation::reconstruct::jfa_steps;

use wgpu::BufferUsages as B;
use wgpu::TextureUsages as U;

pub struct FrameTargets {
    pub width: u32,
    pub height: u32,
    pub uniform: wgpu::Buffer,
    pub depth: wgpu::TextureView,
    pub normal_distance: wgpu::Texture,
    pub albedo: wgpu::Texture,
    pub blurred_normal: wgpu::Texture,
    pub irradiance: wgpu::Texture,
    pub history_normal_distance: wgpu::Texture,
    /// Per-pixel buffers, row-major.
    pub probability: wgpu::Buffer,
    pub flags: wgpu::Buffer,
    pub color: wgpu::Buffer,
    pub history_color: wgpu::Buffer,
    pub seeds: wgpu::Buffer,
    /// Jump flooding ping-pong; see `jfa_result`.
    pub jfa_a: wgpu::Buffer,
    pub jfa_b: wgpu::Buffer,
    pub resolved: wgpu::Buffer,
    /// Packed RGBA8 rows, exactly the output image.
    pub final_image: wgpu::Buffer,
    /// `[count, workgroups x, y, z]` for the indirect shading dispatch.
    pub counter: wgpu::Buffer,
    pub jfa_steps: usize,
    pub bind: Bindings,
    readback: wgpu::Buffer,
    counter_readback: wgpu::Buffer,
    /// Last frame's camera, and whether its buffers may be reused.
    pub prev_view_proj: glam::Mat4,
    pub prev_eye: glam::Vec3,
    pub has_history: bool,
    pub frame_index: u32,
    /// The scene plan at this size gives some material its subsurface rungs.
    pub needs_dipole: bool,
    /// The scene's materials as this frame size's plan shades them.
    _materials: wgpu::Buffer,
    /// Owned here; passes reach them through bind groups.
    _dof: wgpu::Buffer,
    _diffused: [wgpu::Buffer; 2],
    jump: wgpu::Buffer,
}

pub struct Bindings {
    pub gbuffer: wgpu::BindGroup,
    pub sampling: wgpu::BindGroup,
    pub compact: wgpu::BindGroup,
    pub shade: wgpu::BindGroup,
    pub jfa: Vec<wgpu::BindGroup>,
    pub resolve: wgpu::BindGroup,
    /// Depth of field from the shaded colour (full mode) or the resolved one (foveated).
    pub dof_from_color: wgpu::BindGroup,
    pub dof_from_resolved: wgpu::BindGroup,
    /// Output from the shaded colour, the resolved colour, or the depth-of-field result.
    pub output_color: wgpu::BindGroup,
    pub output_resolved: wgpu::BindGroup,
    pub output_dof: wgpu::BindGroup,
    /// Irradiance → a, a → b (horizontal), b → a (vertical).
    pub screen_diffusion: [wgpu::BindGroup; 3],
}

impl FrameTargets {
    pub fn new(
        device: &wgpu::Device,
        passes: &Passes,
        rank_map: &wgpu::TextureView,
        scene: &SceneGpu,
        materials: wgpu::Buffer,
        width: u32,
        height: u32,
    ) -> FrameTargets {
        let size = (width, height);
        let pixels = u64::from(width) * u64::from(height);
        let tex = |label, format, usage| gpu::texture_2d(device, label, size, format, usage);
        let attach = U::RENDER_ATTACHMENT | U::TEXTURE_BINDING | U::COPY_SRC;
        let depth = tex("gbuffer.depth", gbuffer::DEPTH, U::RENDER_ATTACHMENT);
        let normal_distance = tex("gbuffer.normal_distance", gbuffer::NORMAL_DISTANCE, attach);
        let albedo = tex("gbuffer.albedo", gbuffer::ALBEDO, attach);
        let blurred_normal = tex("gbuffer.blurred_normal", gbuffer::BLURRED_NORMAL, attach);
        let irradiance = tex("gbuffer.irradiance", gbuffer::IRRADIANCE, attach);
        let history_normal_distance = tex(
            "history.normal_distance",
            gbuffer::NORMAL_DISTANCE,
            U::TEXTURE_BINDING | U::COPY_DST,
        );

        let buffer = |label, size: u64, usage| {
            device.create_buffer(&wgpu::BufferDescriptor {
                label: Some(label),
                size,
                usage,
                mapped_at_creation: false,
            })
        };
        let per_pixel = |label, bytes: u64| {
            buffer(
                label,
                pixels * bytes,
                B::STORAGE | B::COPY_SRC | B::COPY_DST,
            )
        };
        let probability = per_pixel("sampling.probability", 4);
        let flags = per_pixel("sampling.flags", 4);
        let color = per_pixel("shade.color", 16);
        let history_color = per_pixel("history.color", 16);
        let seeds = per_pixel("sampling.seeds", 4);
        let jfa_a = per_pixel("jfa.a", 4);
        let jfa_b = per_pixel("jfa.b", 4);
        let resolved = per_pixel("resolve.color", 16);
        let dof = per_pixel("dof.color", 16);
        let final_image = per_pixel("output.final", 4);
        let diffused = [
            per_pixel("screen_diffusion.a", 16),
            per_pixel("screen_diffusion.b", 16),
        ];
        let list = per_pixel("compact.list", 4);
        let counter = buffer(
            "compact.counter",
            16,
            B::STORAGE | B::INDIRECT | B::COPY_SRC | B::COPY_DST,
        );
        let uniform = buffer(
            "frame.uniform",
            std::mem::size_of::<FrameUniform>() as u64,
            B::UNIFORM | B::COPY_DST,
        );
        let steps = jfa_steps(width, height);
        // Room for the longest step list; each frame writes the steps it runs.
        let jump = buffer(
            "jfa.steps",
            jfa::SLOT * steps.len() as u64,
            B::UNIFORM | B::COPY_DST,
        );
        let readback = buffer("output.readback", pixels * 4, B::COPY_DST | B::MAP_READ);
        let counter_readback = buffer("compact.counter.readback", 16, B::COPY_DST | B::MAP_READ);

        let u = uniform.as_entire_binding();
        let (nd, alb, blur, hnd) = (
            view(&normal_distance),
            view(&albedo),
            view(&blurred_normal),
            view(&history_normal_distance),
        );
        use wgpu::BindingResource::TextureView as T;
        fn b(buf: &wgpu::Buffer) -> wgpu::BindingResource<'_> {
            buf.as_entire_binding()
        }
        let gbuffer_bg = gpu::bind(
            device,
            "gbuffer",
            &passes.gbuffer.layout,
            &[u.clone(), b(&scene.materials)],
        );
        let sampling = passes.sampling.bind(
            device,
            &[
                u.clone(),
                T(&nd),
                T(&alb),
                b(&materials),
                T(rank_map),
                b(&history_color),
                T(&hnd),
                b(&probability),
                b(&flags),
                b(&color),
                b(&seeds),
            ],
        );
        let compact = gpu::bind(
            device,
            "compact",
            &passes.compact.layout,
            &[u.clone(), b(&flags), b(&list), b(&counter)],
        );
        let nodes = scene
            .photons
            .as_ref()
            .map(|p| &p.nodes)
            .unwrap_or(&scene.no_photons);
        let shade = gpu::bind(
            device,
            "shade",
            &passes.shade.layout,
            &[
                u.clone(),
                T(&nd),
                T(&alb),
                b(&flags),
                b(&list),
                b(&counter),
                b(&color),
                b(&materials),
                T(&blur),
                b(nodes),
                b(&diffused[0]),
                T(&view(&irradiance)),
            ],
        );
        let diffusion = |src: &wgpu::Buffer, dst: &wgpu::Buffer| {
            gpu::bind(
                device,
                "screen_diffusion",
                &passes.screen_diffusion.layout,
                &[
                    u.clone(),
                    T(&nd),
                    T(&alb),
                    b(&materials),
                    b(&scene.reach),
                    b(src),
                    b(dst),
                ],
            )
        };
        let screen_diffusion = [
            diffusion(&diffused[1], &diffused[0]),
            diffusion(&diffused[0], &diffused[1]),
            diffusion(&diffused[1], &diffused[0]),
        ];
        let jump_binding = wgpu::BindingResource::Buffer(wgpu::BufferBinding {
            buffer: &jump,
            offset: 0,
            size: wgpu::BufferSize::new(16),
        });
        // Step 0 reads the seeds; then a → b, b → a, …
        let jfa_groups: Vec<wgpu::BindGroup> = (0..steps.len())
            .map(|i| {
                let (src, dst) = match (i, i % 2) {
                    (0, _) => (&seeds, &jfa_a),
                    (_, 1) => (&jfa_a, &jfa_b),
                    _ => (&jfa_b, &jfa_a),
                };
                gpu::bind(
                    device,
                    "jfa",
                    &passes.jfa.layout,
                    &[u.clone(), b(src), b(dst), jump_binding.clone()],
                )
            })
            .collect();
        let nearest = if steps.len() % 2 == 1 { &jfa_a } else { &jfa_b };
        let resolve = passes.resolve.bind(
            device,
            &[
                u.clone(),
                b(&color),
                b(nearest),
                T(&alb),
                b(&resolved),
                T(&nd),
                b(&flags),
            ],
        );
        let dof_from_color = passes
            .dof
            .bind(device, &[u.clone(), b(&color), T(&nd), b(&dof)]);
        let dof_from_resolved = passes
            .dof
            .bind(device, &[u.clone(), b(&resolved), T(&nd), b(&dof)]);
        let output = |src: &wgpu::Buffer| {
            passes.output.bind(
                device,
                &[
                    u.clone(),
                    b(src),
                    b(&flags),
                    b(&probability),
                    b(&final_image),
                ],
            )
        };
        let bind = Bindings {
            gbuffer: gbuffer_bg,
            sampling,
            compact,
            shade,
            jfa: jfa_groups,
            resolve,
            dof_from_color,
            dof_from_resolved,
            output_color: output(&color),
            output_resolved: output(&resolved),
            output_dof: output(&dof),
            screen_diffusion,
        };
        FrameTargets {
            width,
            height,
            uniform,
            depth: view(&depth),
            normal_distance,
            albedo,
            blurred_normal,
            irradiance,
            history_normal_distance,
            probability,
            flags,
            color,
            history_color,
            seeds,
            jfa_a,
            jfa_b,
            resolved,
            final_image,
            counter,
            jfa_steps: steps.len(),
            bind,
            readback,
            counter_readback,
            prev_view_proj: glam::Mat4::IDENTITY,
            prev_eye: glam::Vec3::ZERO,
            has_history: false,
            frame_index: 0,
            needs_dipole: false,
            _materials: materials,
            _dof: dof,
            _diffused: diffused,
            jump,
        }
    }

    /// Writes this frame's jump sizes, one per uniform slot.
    pub fn write_jfa_steps(&self, queue: &wgpu::Queue, steps: &[u32]) {
        let mut bytes = vec![0u8; steps.len() * jfa::SLOT as usize];
        for (i, s) in steps.iter().enumerate() {
            let at = i * jfa::SLOT as usize;
            bytes[at..at + 4].copy_from_slice(&s.to_le_bytes());
        }
        queue.write_buffer(&self.jump, 0, &bytes);
    }

    /// The buffer holding each pixel's nearest seed after jump flooding.
    pub fn jfa_result(&self) -> &wgpu::Buffer {
        if self.jfa_steps % 2 == 1 {
            &self.jfa_a
        } else {
            &self.jfa_b
        }
    }

    pub fn gbuffer_views(&self) -> [wgpu::TextureView; 4] {
        [
            view(&self.normal_distance),
            view(&self.albedo),
            view(&self.blurred_normal),
            view(&self.irradiance),
        ]
    }

    /// Encodes the copies that make this frame next frame's history.
    pub fn keep_history(&self, encoder: &mut wgpu::CommandEncoder) {
        let whole = wgpu::Extent3d {
            width: self.width,
            height: self.height,
            depth_or_array_layers: 1,
        };
        encoder.copy_buffer_to_buffer(&self.color, 0, &self.history_color, 0, self.color.size());
        encoder.copy_texture_to_texture(
            self.normal_distance.as_image_copy(),
            self.history_normal_distance.as_image_copy(),
            whole,
        );
    }

    /// Copies the final image and the sample count to host memory.
    pub fn read_back(
        &self,
        device: &wgpu::Device,
        queue: &wgpu::Queue,
    ) -> Result<(Vec<u8>, u32), RenderError> {
        let mut encoder = device.create_command_encoder(&wgpu::CommandEncoderDescriptor {
            label: Some("readback"),
        });
        encoder.copy_buffer_to_buffer(
            &self.final_image,
            0,
            &self.readback,
            0,
            self.final_image.size(),
        );
        encoder.copy_buffer_to_buffer(&self.counter, 0, &self.counter_readback, 0, 16);
        let submission = queue.submit([encoder.finish()]);
        let image = map_read(device, submission.clone(), &self.readback, |bytes| {
            bytes.to_vec()
        })?;
        let count = map_read(device, submission, &self.counter_readback, |b| {
            u32::from_le_bytes([b[0], b[1], b[2], b[3]])
        })?;
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
        .poll(wgpu::PollType::Wait {
            submission_index: Some(submission),
            timeout: None,
        })
        .map_err(|e| RenderError::Readback(format!("waiting for the copy: {e}")))?;
    match rx.recv() {
        Ok(Ok(())) => {}
        Ok(Err(e)) => return Err(RenderError::Readback(format!("map failed: {e}"))),
        Err(_) => return Err(RenderError::Readback("map callback never ran".into())),
    }
    let out = {
        let view = buffer
            .get_mapped_range(..)
            .map_err(|e| RenderError::Readback(format!("mapped range: {e}")))?;
        read(&view)
    };
    buffer.unmap();
    Ok(out)
}
