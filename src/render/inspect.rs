//! Reading a stream's intermediate images back for tests and diagnostics.

use super::frame::RECONSTRUCTED;
use super::pass::photons::SIDE as PHOTON_SIDE;
use super::pass::{jfa, pull_push_tiles};
use super::renderer::Renderer;
use super::request::Inspection;
use super::targets::map_read;
use super::uniforms::{FLAG_COVERED, FLAG_REUSED, FLAG_SAMPLED};
use super::{Gpu, RenderError};
use crate::foveation::pull_push::{self, Key};
use crate::scene::Scene;

impl Renderer {
    /// Reads back the intermediate images of a stream's last frame.
    pub fn inspect(
        &self,
        stream: u64,
        scene: &str,
        width: u32,
        height: u32,
    ) -> Result<Inspection, RenderError> {
        let key = (stream, scene.to_string(), width, height);
        let (_, t) = self
            .targets
            .iter()
            .find(|(k, _)| *k == key)
            .ok_or_else(|| {
                RenderError::Readback(format!(
                    "no frame rendered for stream {stream} at {width}x{height}"
                ))
            })?;
        let buf = |name| read_buffer(&self.gpu, t.buffer(name)?);
        let f32s = |b: Vec<u8>| -> Vec<f32> { bytemuck::pod_collect_to_vec(&b) };
        let u32s = |b: Vec<u8>| -> Vec<u32> { bytemuck::pod_collect_to_vec(&b) };
        let quads = |b: Vec<u8>| -> Vec<[f32; 4]> { bytemuck::pod_collect_to_vec(&b) };
        let nodes = self
            .scenes
            .get(scene)
            .and_then(|s| s.photons.as_ref())
            .and_then(|m| m.nodes());
        // Each list's workgroup count: the x of its indirect arguments.
        let tile_args = u32s(buf(pull_push_tiles::ARGS)?);
        let count = |offset: u64| tile_args.get(offset as usize / 4).copied().unwrap_or(0);
        Ok(Inspection {
            probability: f32s(buf("sampling.probability")?),
            flags: u32s(buf("sampling.flags")?),
            seeds: u32s(buf("sampling.seeds")?),
            nearest: u32s(read_texture(
                &self.gpu,
                t.texture(t.routes.resolve("jfa.nearest"))
                    .or_else(|_| t.texture(jfa::PING))?,
                4,
            )?),
            // The shaded colour as the next frame's history keeps it: pull-push has since
            // filled `shade.color` itself in place.
            color: quads(buf("history.color")?),
            resolved: quads(
                buf(t.routes.resolve(RECONSTRUCTED)).or_else(|_| buf("resolve.color"))?,
            ),
            albedo: bytemuck::pod_collect_to_vec(&read_texture(
                &self.gpu,
                t.texture("gbuffer.albedo")?,
                4,
            )?),
            normal_distance: quads(read_texture(
                &self.gpu,
                t.texture("gbuffer.normal_distance")?,
                16,
            )?),
            photons: match nodes {
                Some(nodes) => {
                    let n = (PHOTON_SIDE * PHOTON_SIDE) as usize;
                    // A node is 12 floats (`PhotonNode`); the covered area is left out.
                    let all: Vec<[f32; 12]> =
                        bytemuck::pod_collect_to_vec(&read_buffer(&self.gpu, nodes)?);
                    all.iter()
                        .take(n)
                        .map(|node| std::array::from_fn(|k| node[k]))
                        .collect()
                }
                None => Vec::new(),
            },
            fill_tiles: count(0),
            pull_tiles: count(pull_push_tiles::PULL_ARGS),
            level1_tiles: count(pull_push_tiles::LEVEL1_ARGS),
        })
    }
}

fn read_buffer(gpu: &Gpu, source: &wgpu::Buffer) -> Result<Vec<u8>, RenderError> {
    let buffer = gpu.device.create_buffer(&wgpu::BufferDescriptor {
        label: Some("inspect"),
        size: source.size(),
        usage: wgpu::BufferUsages::COPY_DST | wgpu::BufferUsages::MAP_READ,
        mapped_at_creation: false,
    });
    let mut encoder = gpu.device.create_command_encoder(&Default::default());
    encoder.copy_buffer_to_buffer(source, 0, &buffer, 0, source.size());
    let submission = gpu.queue.submit([encoder.finish()]);
    map_read(&gpu.device, submission, &buffer, |bytes| bytes.to_vec())
}

fn read_texture(
    gpu: &Gpu,
    texture: &wgpu::Texture,
    bytes_per_pixel: u32,
) -> Result<Vec<u8>, RenderError> {
    let (w, h) = (texture.width(), texture.height());
    let align = wgpu::COPY_BYTES_PER_ROW_ALIGNMENT;
    let row = w * bytes_per_pixel;
    let padded = row.div_ceil(align) * align;
    let buffer = gpu.device.create_buffer(&wgpu::BufferDescriptor {
        label: Some("inspect"),
        size: u64::from(padded) * u64::from(h),
        usage: wgpu::BufferUsages::COPY_DST | wgpu::BufferUsages::MAP_READ,
        mapped_at_creation: false,
    });
    let mut encoder = gpu.device.create_command_encoder(&Default::default());
    encoder.copy_texture_to_buffer(
        texture.as_image_copy(),
        wgpu::TexelCopyBufferInfo {
            buffer: &buffer,
            layout: wgpu::TexelCopyBufferLayout {
                offset: 0,
                bytes_per_row: Some(padded),
                rows_per_image: Some(h),
            },
        },
        wgpu::Extent3d {
            width: w,
            height: h,
            depth_or_array_layers: 1,
        },
    );
    let submission = gpu.queue.submit([encoder.finish()]);
    map_read(&gpu.device, submission, &buffer, |bytes| {
        bytes
            .chunks_exact(padded as usize)
            .flat_map(|c| c[..row as usize].to_vec())
            .collect()
    })
}

/// What the pull-push pass reconstructs from, rebuilt on the CPU from an inspection, for
/// `foveation::pull_push` (its GPU-vs-CPU test and the pictures of its levels).
pub struct PullPushInputs {
    /// Each pixel's proxy: what the G-buffer alone predicts of its colour.
    pub proxy: Vec<[f32; 3]>,
    /// Each shaded or reused pixel's colour over its proxy; `None` for the rest.
    pub samples: Vec<Option<[f32; 3]>>,
    /// Each pixel's depth and material id.
    pub keys: Vec<Key>,
}

impl Inspection {
    /// The pull-push inputs of this frame, lit by `scene`'s key light from `to_light`.
    pub fn pull_push_inputs(&self, scene: &Scene, to_light: glam::Vec3) -> PullPushInputs {
        let l = &scene.file.light;
        let light = l.color.map(|c| c * l.intensity);
        let proxy: Vec<[f32; 3]> = self
            .albedo
            .iter()
            .zip(&self.normal_distance)
            .map(|(a, nd)| {
                let a = a.map(|v| f32::from(v) / 255.0);
                let normal = [nd[0], nd[1], nd[2]];
                pull_push::proxy(
                    [a[0], a[1], a[2]],
                    normal,
                    to_light.to_array(),
                    light,
                    scene.file.ambient,
                )
            })
            .collect();
        let samples = self
            .flags
            .iter()
            .zip(&self.color)
            .zip(&proxy)
            .map(|((f, c), p)| {
                (f & FLAG_COVERED != 0 && f & (FLAG_SAMPLED | FLAG_REUSED) != 0)
                    .then(|| std::array::from_fn(|ch| c[ch] / p[ch]))
            })
            .collect();
        let keys = self
            .normal_distance
            .iter()
            .zip(&self.albedo)
            .map(|(nd, a)| Key {
                depth: nd[3],
                material: f32::from(a[3]),
            })
            .collect();
        PullPushInputs {
            proxy,
            samples,
            keys,
        }
    }
}
