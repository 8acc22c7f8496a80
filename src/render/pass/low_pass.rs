//! Foveated encoding's low-pass as a pass (after `output`, before `i420` and the readback):
//! where the adapter is a GPU the periphery is filtered there instead of on the encoder thread,
//! and an H.264 session with foveated encoding can then read back I420. CPU twin:
//! `encode::foveated::low_pass`; the level grid both use is computed on the CPU
//! (`encode::foveated::level_grid`) and uploaded, so the two agree on every pixel's level.

use bytemuck::{Pod, Zeroable};

use crate::encode::foveated::{grid_size, level_grid, LowPass, CELL, MAX_LEVEL};
use crate::render::graph::{
    dynamic_uniform, read, uniform, write, DispatchSize, GraphError, PassDecl, Recorder,
};
use crate::viewing::Viewing;

/// Parameter slots start at multiples of the device's offset alignment.
pub const SLOT: u64 = 256;

pub const PASS: PassDecl = PassDecl {
    label: "low_pass",
    shader: include_str!("../../../shaders/low_pass.wgsl"),
    first_binding: 0,
    bindings: &[
        uniform("frame.uniform"),
        dynamic_uniform("low_pass.params", std::mem::size_of::<Params>() as u64),
        read("low_pass.grid"),
        write("output.final"),
        write("low_pass.pyramid"),
    ],
    attachments: &[],
    entry_points: &["build", "apply"],
};

/// Twin of `struct LowPass` in the shader.
#[repr(C)]
#[derive(Debug, Clone, Copy, Default, Pod, Zeroable)]
struct Params {
    level: u32,
    grid_width: u32,
    cell: u32,
    max_level: u32,
    /// Per level 0..=MAX_LEVEL: width, height, first texel in the pyramid buffer, unused.
    levels: [[u32; 4]; MAX_LEVEL + 1],
}

/// Width, height and first texel of each level (level 0: the frame, at 0).
fn level_table(width: u32, height: u32) -> [[u32; 4]; MAX_LEVEL + 1] {
    let mut t = [[0u32; 4]; MAX_LEVEL + 1];
    t[0] = [width, height, 0, 0];
    let mut offset = 0;
    for k in 1..=MAX_LEVEL {
        let (w, h) = (t[k - 1][0].div_ceil(2), t[k - 1][1].div_ceil(2));
        t[k] = [w, h, offset, 0];
        offset += w * h;
    }
    t
}

/// Bytes of the pyramid buffer at `width`×`height` (an RGB texel in 16 bytes).
pub fn pyramid_bytes(width: u32, height: u32) -> u64 {
    let t = level_table(width, height);
    let [w, h, offset, _] = t[MAX_LEVEL];
    16 * (u64::from(offset) + u64::from(w) * u64::from(h)).max(1)
}

/// Bytes of the level grid at `width`×`height`.
pub fn grid_bytes(width: u32, height: u32) -> u64 {
    let [gw, gh] = grid_size(width, height);
    4 * u64::from(gw) * u64::from(gh)
}

/// Bytes of the parameter slots: one per pyramid level and one for `apply`.
pub fn params_bytes() -> u64 {
    SLOT * (MAX_LEVEL as u64 + 1)
}

/// What the pass needs besides the image: the filter and the geometry it is judged in.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Filter {
    pub low_pass: LowPass,
    pub viewing: Viewing,
    /// Normalised gaze the periphery is measured from.
    pub gaze: [f64; 2],
}

/// Uploads the frame's level grid and parameters and records the pyramid's levels, then the
/// filter, in one compute pass.
pub fn record(f: &mut Recorder, filter: &Filter) -> Result<(), GraphError> {
    let (width, height) = f.size;
    let grid = level_grid(
        width,
        height,
        filter.gaze,
        &filter.viewing,
        &filter.low_pass,
    );
    f.queue
        .write_buffer(f.buffer("low_pass.grid")?, 0, bytemuck::cast_slice(&grid));
    let levels = level_table(width, height);
    let mut bytes = vec![0u8; params_bytes() as usize];
    for level in 0..=MAX_LEVEL {
        let p = Params {
            level: level as u32,
            grid_width: grid_size(width, height)[0],
            cell: CELL,
            max_level: MAX_LEVEL as u32,
            levels,
        };
        let at = level * SLOT as usize;
        bytes[at..at + std::mem::size_of::<Params>()].copy_from_slice(bytemuck::bytes_of(&p));
    }
    f.queue
        .write_buffer(f.buffer("low_pass.params")?, 0, &bytes);
    let mut dispatches = Vec::with_capacity(MAX_LEVEL + 1);
    for (level, [w, h, _, _]) in levels.iter().enumerate().skip(1) {
        let size = DispatchSize::Groups(w.div_ceil(8), h.div_ceil(8), 1);
        let mut d = f.dispatch(&PASS, "build", size)?;
        d.offsets = vec![(level as u64 * SLOT) as u32];
        dispatches.push(d);
    }
    let mut d = f.dispatch(&PASS, "apply", DispatchSize::Frame)?;
    d.offsets = vec![0];
    dispatches.push(d);
    f.compute(PASS.label, &dispatches);
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn levels_halve_rounding_up_and_follow_each_other_in_the_buffer() {
        let t = level_table(97, 61);
        assert_eq!(t[1], [49, 31, 0, 0]);
        assert_eq!(t[2], [25, 16, 49 * 31, 0]);
        assert_eq!(t[5], [4, 2, t[4][2] + t[4][0] * t[4][1], 0]);
        assert_eq!(pyramid_bytes(97, 61), 16 * u64::from(t[5][2] + 8));
        // A 1×1 frame keeps a texel per level.
        let one = level_table(1, 1);
        assert!(one[1..].iter().all(|l| l[0] == 1 && l[1] == 1));
    }
}
