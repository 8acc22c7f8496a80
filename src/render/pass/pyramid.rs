//! Photon pyramid (seed 000): the photon map's texels become leaves, then each level reduces
//! 2×2 nodes of the one below into a cluster (flux-weighted position, summed flux, extent).

use super::photons::{node_count, LEVELS, SIDE};
use crate::render::graph::{dynamic_uniform, read, texture, uniform, write, PassDecl, Pipelines};
use crate::render::timer::PassTimer;

/// Uniform slots must start at multiples of the device's offset alignment (256 by default).
pub const SLOT: u64 = 256;

/// Nodes per row of `photons.node_texels`, each node three rgba32float texels in a row
/// (position and extent, flux, area): 256 nodes make 12 KiB, a whole number of the 256-byte
/// rows a buffer-to-texture copy needs.
const NODES_PER_ROW: u32 = 256;

/// Texel size of `photons.node_texels`.
pub fn texels_size() -> (u32, u32) {
    let rows = node_count().div_ceil(u64::from(NODES_PER_ROW)) as u32;
    (3 * NODES_PER_ROW, rows)
}

/// Bytes of `photons.nodes`: whole rows of the texel copy.
pub fn nodes_bytes() -> u64 {
    u64::from(texels_size().1) * u64::from(NODES_PER_ROW) * 48
}

/// Copies the built pyramid into the texture the shading pass reads it from. The shading pass
/// visits several nodes per pixel at addresses that differ per pixel; a software adapter
/// fetches such texels for a whole SIMD row at once but loads buffer values one lane at a time
/// (an extra node load per visit cost gallery's full frame 35% more, 640x480, lavapipe).
pub fn copy_to_texels(
    encoder: &mut wgpu::CommandEncoder,
    nodes: &wgpu::Buffer,
    texels: &wgpu::Texture,
) {
    let (width, height) = texels_size();
    encoder.copy_buffer_to_texture(
        wgpu::TexelCopyBufferInfo {
            buffer: nodes,
            layout: wgpu::TexelCopyBufferLayout {
                offset: 0,
                bytes_per_row: Some(width * 16),
                rows_per_image: Some(height),
            },
        },
        texels.as_image_copy(),
        wgpu::Extent3d {
            width,
            height,
            depth_or_array_layers: 1,
        },
    );
}

pub const PASS: PassDecl = PassDecl {
    label: "pyramid",
    shader: include_str!("../../../shaders/pyramid.wgsl"),
    // Binding 0 is the frame uniform of the shared prelude, which the pyramid never uses.
    first_binding: 1,
    bindings: &[
        dynamic_uniform("pyramid.levels", 16),
        uniform("photons.uniform"),
        read("materials.scene"),
        texture("photons.position"),
        texture("photons.normal"),
        write("photons.nodes"),
        texture("photons.irradiance"),
        texture("shadow.depth"),
    ],
    attachments: &[],
    entry_points: &["leaves", "reduce"],
};

pub struct PyramidPipelines {
    leaves: wgpu::ComputePipeline,
    reduce: wgpu::ComputePipeline,
}

impl PyramidPipelines {
    pub fn new(pipelines: &mut Pipelines) -> PyramidPipelines {
        PyramidPipelines {
            leaves: pipelines.compute(&PASS, "leaves", "pyramid.leaves"),
            reduce: pipelines.compute(&PASS, "reduce", "pyramid.reduce"),
        }
    }

    /// Writes each level's `[level, side, offset, offset of the level below]` into its slot of
    /// `levels`, then builds the levels finest first.
    pub fn record(
        &self,
        queue: &wgpu::Queue,
        encoder: &mut wgpu::CommandEncoder,
        levels: &wgpu::Buffer,
        bind: &wgpu::BindGroup,
        timer: &mut PassTimer,
    ) {
        let mut slots = vec![0u8; (SLOT * u64::from(LEVELS)) as usize];
        let (mut offset, mut below) = (0u32, 0u32);
        for l in 0..LEVELS {
            let side = (SIDE >> l).max(1);
            let v = [l, side, offset, below];
            let at = (SLOT * u64::from(l)) as usize;
            slots[at..at + 16].copy_from_slice(bytemuck::cast_slice(&v));
            below = offset;
            offset += side * side;
        }
        queue.write_buffer(levels, 0, &slots);
        let mut pass = encoder.begin_compute_pass(&wgpu::ComputePassDescriptor {
            label: Some(PASS.label),
            timestamp_writes: timer.compute(PASS.label),
        });
        for l in 0..LEVELS {
            let side = (SIDE >> l).max(1);
            pass.set_pipeline(if l == 0 { &self.leaves } else { &self.reduce });
            pass.set_bind_group(0, bind, &[(SLOT * u64::from(l)) as u32]);
            pass.dispatch_workgroups(side.div_ceil(8), side.div_ceil(8), 1);
        }
    }
}
