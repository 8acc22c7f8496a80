//! Pull-push reconstruction (foveated frames with `reconstruction: pull_push`): moments pulled
//! up a pyramid of 2×2 cells, planes pushed back down, then every pixel filled. Replaces jump
//! flooding and the resolve pass for those frames; O(N) work instead of N log N plus a window.
//! CPU twin: `foveation::pull_push`.

use bytemuck::{Pod, Zeroable};

use crate::foveation::pull_push::{
    level_count, level_size, DEMODULATION_FLOOR, DEPTH_TOLERANCE, LAMBDA, LAMBDA_TOP,
    MATERIAL_TOLERANCE,
};
use crate::render::graph::{
    dynamic_uniform, read, texture, uniform, write, DispatchSize, GraphError, PassDecl, Recorder,
};

/// Uniform slots start at multiples of the device's offset alignment (256 by default).
pub const SLOT: u64 = 256;

/// Bytes of one pyramid cell: six vec4 (moments, depth and material with their spreads, sample
/// range; then the plane in four of them).
pub const CELL_BYTES: u64 = 96;

pub const PASS: PassDecl = PassDecl {
    label: "pull_push",
    shader: include_str!("../../../shaders/pull_push.wgsl"),
    first_binding: 0,
    bindings: &[
        uniform("frame.uniform"),
        read("shade.color"),
        read("sampling.flags"),
        texture("gbuffer.albedo"),
        write("pull_push.cells"),
        write("resolve.color"),
        dynamic_uniform("pull_push.levels", std::mem::size_of::<Level>() as u64),
        texture("gbuffer.normal_distance"),
    ],
    attachments: &[],
    entry_points: &["pull_pixels", "pull", "push", "push_pixels"],
};

/// Twin of `struct Level` in the shader.
#[repr(C)]
#[derive(Debug, Clone, Copy, Default, Pod, Zeroable)]
pub struct Level {
    size: [u32; 2],
    offset: u32,
    level: u32,
    parent_size: [u32; 2],
    parent_offset: u32,
    has_parent: u32,
    ridge: f32,
    floor: f32,
    child_offset: u32,
    depth_tolerance: f32,
    material_tolerance: f32,
    pad: [u32; 3],
}

/// Levels above the pixels the GPU keeps (at least one, so a 1×1 frame has a top cell).
pub fn levels(width: u32, height: u32) -> u32 {
    level_count(width, height).max(1)
}

/// First cell of each level 1..=L in the cell buffer, and the total cell count.
fn offsets(width: u32, height: u32) -> (Vec<u32>, u32) {
    let mut at = Vec::new();
    let mut total = 0;
    for l in 1..=levels(width, height) {
        at.push(total);
        let (w, h) = level_size(width, height, l);
        total += w * h;
    }
    (at, total)
}

/// Bytes of the cell buffer at this frame size.
pub fn cells_bytes(width: u32, height: u32) -> u64 {
    u64::from(offsets(width, height).1) * CELL_BYTES
}

/// Bytes of the level uniforms: one slot per dispatch.
pub fn levels_bytes(width: u32, height: u32) -> u64 {
    SLOT * (2 * u64::from(levels(width, height)) + 1)
}

/// One slot per dispatch: pull_pixels, pull per level, push per level from the top, push_pixels.
fn slots(width: u32, height: u32) -> Vec<(&'static str, Level)> {
    let (at, _) = offsets(width, height);
    let top = levels(width, height);
    let info = |l: u32| (level_size(width, height, l), at[(l - 1) as usize]);
    let mut out = Vec::new();
    for l in 1..=top {
        let ((w, h), offset) = info(l);
        let mut s = Level {
            size: [w, h],
            offset,
            level: l,
            floor: DEMODULATION_FLOOR,
            depth_tolerance: DEPTH_TOLERANCE,
            material_tolerance: MATERIAL_TOLERANCE,
            ..Level::default()
        };
        if l == 1 {
            out.push(("pull_pixels", s));
        } else {
            let ((cw, ch), child) = info(l - 1);
            s.parent_size = [cw, ch];
            s.child_offset = child;
            out.push(("pull", s));
        }
    }
    for l in (1..=top).rev() {
        let ((w, h), offset) = info(l);
        let mut s = Level {
            size: [w, h],
            offset,
            level: l,
            ridge: if l == top { LAMBDA_TOP } else { LAMBDA },
            floor: DEMODULATION_FLOOR,
            depth_tolerance: DEPTH_TOLERANCE,
            material_tolerance: MATERIAL_TOLERANCE,
            ..Level::default()
        };
        if l < top {
            let ((pw, ph), parent) = info(l + 1);
            (s.parent_size, s.parent_offset, s.has_parent) = ([pw, ph], parent, 1);
        }
        out.push(("push", s));
    }
    let ((pw, ph), parent) = info(1);
    out.push((
        "push_pixels",
        Level {
            size: [width, height],
            parent_size: [pw, ph],
            parent_offset: parent,
            has_parent: 1,
            floor: DEMODULATION_FLOOR,
            depth_tolerance: DEPTH_TOLERANCE,
            material_tolerance: MATERIAL_TOLERANCE,
            ..Level::default()
        },
    ));
    out
}

/// Fills the frame; from here on `frame.color` is the reconstructed colour.
pub fn record(f: &mut Recorder) -> Result<(), GraphError> {
    let (width, height) = f.size;
    let slots = slots(width, height);
    let mut bytes = vec![0u8; slots.len() * SLOT as usize];
    for (i, (_, s)) in slots.iter().enumerate() {
        let at = i * SLOT as usize;
        bytes[at..at + std::mem::size_of::<Level>()].copy_from_slice(bytemuck::bytes_of(s));
    }
    f.queue
        .write_buffer(f.buffer("pull_push.levels")?, 0, &bytes);
    let mut dispatches = Vec::with_capacity(slots.len());
    for (i, (entry, s)) in slots.iter().enumerate() {
        let size = DispatchSize::Groups(s.size[0].div_ceil(8), s.size[1].div_ceil(8), 1);
        let mut d = f.dispatch(&PASS, entry, size)?;
        d.offsets = vec![(i as u64 * SLOT) as u32];
        dispatches.push(d);
    }
    f.compute(PASS.label, &dispatches);
    f.route("frame.color", "resolve.color");
    Ok(())
}
