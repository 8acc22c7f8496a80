//! Everything one stream (a session, or one `fovea render`) needs on the GPU at one frame size:
//! the named resources of the frame graph (G-buffer, per-pixel buffers, history, compaction
//! list), the bind groups built from them, the readback buffers, and the camera of the last
//! frame. Kept per stream because history belongs to one viewer's sequence of frames.

use std::collections::HashMap;

use super::graph::{BindKey, Resources, Routes};
use super::pass::{gbuffer, i420, jfa, low_pass, pull_push, pull_push_tiles, shade};
use super::uniforms::FrameUniform;
use super::RenderError;
use crate::foveation::reconstruct::jfa_steps;

use wgpu::BufferUsages as B;
use wgpu::TextureUsages as U;

/// Per-pixel storage buffers, row-major: (name, bytes per pixel).
const PER_PIXEL: &[(&str, u64)] = &[
    ("sampling.probability", 4),
    ("sampling.flags", 4),
    ("sampling.seeds", 4),
    ("sampling.saliency", 4),
    ("shade.color", 16),
    ("history.color", 16),
    ("resolve.color", 16),
    ("dof.color", 16),
    // Packed RGBA8 rows, exactly the output image.
    ("output.final", 4),
    ("screen_diffusion.a", 16),
    ("screen_diffusion.b", 16),
    ("compact.list", 4),
];

pub struct FrameTargets {
    /// This stream's resources, with the scene's and the renderer's shared ones.
    pub resources: Resources,
    /// Bind groups built so far, by what they bind.
    pub binds: HashMap<BindKey, wgpu::BindGroup>,
    /// Where the last frame's ports pointed (`jfa.nearest`, `frame.color`).
    pub routes: Routes,
    readback: wgpu::Buffer,
    /// The I420 planes' readback (`output.i420`, 1.5 bytes a pixel plus padding).
    i420_readback: wgpu::Buffer,
    counter_readback: wgpu::Buffer,
    /// Last frame's camera, and whether its buffers may be reused.
    pub prev_view_proj: glam::Mat4,
    pub prev_eye: glam::Vec3,
    pub has_history: bool,
    pub frame_index: u32,
    /// The last frame's settings: with a still camera and the same settings its G-buffer, and
    /// so its saliency, is this frame's.
    pub prev_settings: Option<crate::settings::RenderSettings>,
    /// The MODE_* bits of the frame uniforms last written (specialised pipelines follow them).
    pub mode: u32,
    /// The translucency rung of the frame uniforms last written (shading is specialised for it).
    pub rung: u32,
    /// The scene plan at this size gives some material its subsurface rungs.
    pub needs_dipole: bool,
    /// What these targets take on the GPU, bytes ([`FrameTargets::bytes_for`]).
    pub bytes: u64,
}

/// The per-pixel textures: (name, format, usage).
fn textures() -> [(&'static str, wgpu::TextureFormat, wgpu::TextureUsages); 8] {
    let attach = U::RENDER_ATTACHMENT | U::TEXTURE_BINDING | U::COPY_SRC;
    let seeds = U::STORAGE_BINDING | U::TEXTURE_BINDING | U::COPY_SRC;
    [
        ("gbuffer.depth", gbuffer::DEPTH, U::RENDER_ATTACHMENT),
        ("gbuffer.normal_distance", gbuffer::NORMAL_DISTANCE, attach),
        ("gbuffer.albedo", gbuffer::ALBEDO, attach),
        ("gbuffer.blurred_normal", gbuffer::BLURRED_NORMAL, attach),
        ("gbuffer.irradiance", gbuffer::IRRADIANCE, attach),
        (
            "history.normal_distance",
            gbuffer::NORMAL_DISTANCE,
            U::TEXTURE_BINDING | U::COPY_DST,
        ),
        (jfa::PING, wgpu::TextureFormat::R32Uint, seeds),
        (jfa::PONG, wgpu::TextureFormat::R32Uint, seeds),
    ]
}

/// The buffers sized by the frame (or by nothing): (name, bytes, usage).
fn sized_buffers(width: u32, height: u32) -> [(&'static str, u64, wgpu::BufferUsages); 11] {
    let uniform = B::UNIFORM | B::COPY_DST;
    let (marks, tiles) = pull_push_tiles::bytes(width, height);
    let cleared = B::STORAGE | B::COPY_DST | B::COPY_SRC;
    [
        // `[count, workgroups x, y, z, band start, 0, 0, 0]`: compact.wgsl.
        (
            "compact.counter",
            32,
            B::STORAGE | B::INDIRECT | B::COPY_SRC | B::COPY_DST,
        ),
        (
            "frame.uniform",
            std::mem::size_of::<FrameUniform>() as u64,
            uniform,
        ),
        // Room for the longest step list; each frame writes the steps it runs.
        (
            "jfa.steps",
            jfa::SLOT * jfa_steps(width, height).len() as u64,
            uniform,
        ),
        (
            "pull_push.levels",
            pull_push::levels_bytes(width, height),
            uniform,
        ),
        (
            "shade.coarse",
            shade::coarse_bytes(width, height),
            B::STORAGE,
        ),
        ("low_pass.params", low_pass::params_bytes(), uniform),
        (
            "low_pass.grid",
            low_pass::grid_bytes(width, height),
            B::STORAGE | B::COPY_DST,
        ),
        (
            "low_pass.pyramid",
            low_pass::pyramid_bytes(width, height),
            B::STORAGE,
        ),
        (pull_push_tiles::MARKS, marks, cleared),
        (
            pull_push_tiles::ARGS,
            pull_push_tiles::ARGS_BYTES,
            cleared | B::INDIRECT,
        ),
        (pull_push_tiles::TILES, tiles, B::STORAGE),
    ]
}

/// The pull-push pyramid's atlases, moments and planes for each parity of level.
fn pyramid(device: &wgpu::Device, r: &mut Resources, width: u32, height: u32) {
    for odd in [false, true] {
        let sets = [
            (
                pull_push::MOMENTS,
                pull_push::MOMENT_LAYERS,
                pull_push::moments_hold_first(odd),
            ),
            (pull_push::PLANES, pull_push::PLANE_LAYERS, true),
        ];
        for (names, layers, first) in sets {
            let (w, h) = pull_push::atlas_size(width, height, odd, first);
            let name = names[usize::from(odd)];
            let texture = device.create_texture(&wgpu::TextureDescriptor {
                label: Some(name),
                size: wgpu::Extent3d {
                    width: w,
                    height: h,
                    depth_or_array_layers: layers,
                },
                mip_level_count: 1,
                sample_count: 1,
                dimension: wgpu::TextureDimension::D2,
                format: wgpu::TextureFormat::Rgba32Float,
                usage: U::COPY_DST | U::TEXTURE_BINDING,
                view_formats: &[],
            });
            r.texture_array(name, texture);
        }
    }
    for (name, layers, level) in pull_push::STAGED {
        let bytes = pull_push::staged_bytes(width, height, layers, level);
        let staging = device.create_buffer(&wgpu::BufferDescriptor {
            label: Some(name),
            size: bytes,
            // Cleared each frame: zeros are the empty cells of the pull's skipped tiles.
            usage: wgpu::BufferUsages::STORAGE
                | wgpu::BufferUsages::COPY_SRC
                | wgpu::BufferUsages::COPY_DST,
            mapped_at_creation: false,
        });
        r.buffer(name, staging);
    }
}

impl FrameTargets {
    /// Creates the stream's resources beside `shared` (the scene's and the renderer's) and
    /// `planned_materials` (the scene's materials as this frame size's plan shades them).
    pub fn new(
        device: &wgpu::Device,
        shared: &Resources,
        planned_materials: wgpu::Buffer,
        width: u32,
        height: u32,
        needs_dipole: bool,
    ) -> FrameTargets {
        let size = (width, height);
        let pixels = u64::from(width) * u64::from(height);
        let mut r = shared.clone();
        for (name, format, usage) in textures() {
            let texture = super::gpu::texture_2d(device, name, size, format, usage);
            r.texture(name, texture);
        }
        let buffer = |label, size: u64, usage| {
            device.create_buffer(&wgpu::BufferDescriptor {
                label: Some(label),
                size,
                usage,
                mapped_at_creation: false,
            })
        };
        for &(name, bytes) in PER_PIXEL {
            let usage = B::STORAGE | B::COPY_SRC | B::COPY_DST;
            r.buffer(name, buffer(name, pixels * bytes, usage));
        }
        for (name, bytes, usage) in sized_buffers(width, height) {
            r.buffer(name, buffer(name, bytes, usage));
        }
        pyramid(device, &mut r, width, height);
        let i420_bytes = i420::words(width, height).max(1) * 4;
        r.buffer(
            "output.i420",
            buffer("output.i420", i420_bytes, B::STORAGE | B::COPY_SRC),
        );
        r.buffer("materials.planned", planned_materials);
        FrameTargets {
            resources: r,
            binds: HashMap::new(),
            routes: Routes::default(),
            readback: buffer("output.readback", pixels * 4, B::COPY_DST | B::MAP_READ),
            i420_readback: buffer(
                "output.i420.readback",
                i420_bytes,
                B::COPY_DST | B::MAP_READ,
            ),
            counter_readback: buffer("compact.counter.readback", 16, B::COPY_DST | B::MAP_READ),
            prev_view_proj: glam::Mat4::IDENTITY,
            prev_eye: glam::Vec3::ZERO,
            has_history: false,
            frame_index: 0,
            prev_settings: None,
            mode: 0,
            rung: 0,
            needs_dipole,
            bytes: FrameTargets::bytes_for(width, height),
        }
    }

    /// GPU bytes of one stream's targets at `width`×`height`: the per-pixel textures and
    /// buffers and the readback (the small fixed buffers are left out).
    pub fn bytes_for(width: u32, height: u32) -> u64 {
        let texel = |f: wgpu::TextureFormat| u64::from(f.block_copy_size(None).unwrap_or(4));
        let per_pixel: u64 = textures().iter().map(|t| texel(t.1)).sum::<u64>()
            + PER_PIXEL.iter().map(|p| p.1).sum::<u64>()
            + 4;
        let tile_bytes = pull_push_tiles::bytes(width, height);
        u64::from(width) * u64::from(height) * per_pixel
            + pull_push::pyramid_bytes(width, height)
            + tile_bytes.0
            + tile_bytes.1
            + shade::coarse_bytes(width, height)
            + low_pass::pyramid_bytes(width, height)
            + 2 * 4 * i420::words(width, height)
    }

    pub fn buffer(&self, name: &'static str) -> Result<&wgpu::Buffer, RenderError> {
        self.resources
            .get_buffer(name)
            .ok_or_else(|| RenderError::Readback(format!("no buffer named {name}")))
    }

    pub fn texture(&self, name: &'static str) -> Result<&wgpu::Texture, RenderError> {
        self.resources
            .get_texture(name)
            .map(|(t, _)| t)
            .ok_or_else(|| RenderError::Readback(format!("no texture named {name}")))
    }

    /// Copies the final image (RGBA, or with `i420` the I420 pass's padded planes) and the
    /// sample count to host memory.
    pub fn read_back(
        &self,
        device: &wgpu::Device,
        queue: &wgpu::Queue,
        i420: bool,
    ) -> Result<(Vec<u8>, u32), RenderError> {
        let mut encoder = device.create_command_encoder(&wgpu::CommandEncoderDescriptor {
            label: Some("readback"),
        });
        let (image, readback) = if i420 {
            (self.buffer("output.i420")?, &self.i420_readback)
        } else {
            (self.buffer("output.final")?, &self.readback)
        };
        encoder.copy_buffer_to_buffer(image, 0, readback, 0, image.size());
        let counter = self.buffer("compact.counter")?;
        encoder.copy_buffer_to_buffer(counter, 0, &self.counter_readback, 0, 16);
        let submission = queue.submit([encoder.finish()]);
        let image = map_read(device, submission.clone(), readback, |bytes| bytes.to_vec())?;
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
