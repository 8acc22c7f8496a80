//! Pull-push reconstruction (foveated frames with `reconstruction: pull_push`): moments pulled
//! up a pyramid of 2×2 cells, planes pushed back down, then every pixel filled. Replaces jump
//! flooding and the resolve pass for those frames; O(N) work instead of N log N plus a window.
//! The pyramid is kept in two texture atlases (odd and even levels); see the shader for why.
//! Each dispatch writes its level to a staging buffer that is then copied into the atlas: on
//! the software adapter a buffer store costs a seventh of a storage-texture store, and a copy
//! is a memcpy.
//! CPU twin: `foveation::pull_push`.

use bytemuck::{Pod, Zeroable};

use crate::foveation::pull_push::{
    level_count, level_size, DEMODULATION_FLOOR, DEPTH_TOLERANCE, LAMBDA, LAMBDA_TOP,
    MATERIAL_TOLERANCE,
};
use crate::render::frame::RECONSTRUCTED;
use crate::render::graph::{
    dynamic_uniform, layers, read, texture, uniform, write, DispatchSize, GraphError, PassDecl,
    Recorder,
};

/// Uniform slots start at multiples of the device's offset alignment (256 by default).
pub const SLOT: u64 = 256;

/// Layers of a cell's moments and of its plane, one rgba32float texel each.
pub const MOMENT_LAYERS: u32 = 6;
pub const PLANE_LAYERS: u32 = 4;

/// The atlases: odd levels in one, even levels in the other, so each dispatch reads one
/// parity and writes the other.
pub const MOMENTS: [&str; 2] = ["pull_push.moments[even]", "pull_push.moments[odd]"];
pub const PLANES: [&str; 2] = ["pull_push.planes[even]", "pull_push.planes[odd]"];
/// Where a dispatch writes its level before the copy into the atlas: layer by layer, row by
/// row, `Level::row` texels a row. The moments' six layers take two buffers of three, so that
/// no buffer outgrows `shade.color` (16 bytes a pixel): a software adapter binds at most
/// 128 MiB of storage, and six layers of level 1 at 3840×2160 are 199 MB.
pub const MOMENTS_STAGED: [&str; 2] =
    ["pull_push.moments_staged[0]", "pull_push.moments_staged[1]"];
pub const PLANES_STAGED: &str = "pull_push.planes_staged";
/// Layers in each moments staging buffer.
const STAGED_MOMENT_LAYERS: u32 = MOMENT_LAYERS / 2;
/// Every staging buffer with its layers and whether level 2 follows level 1 in it (the
/// moments: `pull_pixels` writes both levels), as the targets create them.
pub const STAGED: [(&str, u32, bool); 3] = [
    (MOMENTS_STAGED[0], STAGED_MOMENT_LAYERS, true),
    (MOMENTS_STAGED[1], STAGED_MOMENT_LAYERS, true),
    (PLANES_STAGED, PLANE_LAYERS, false),
];

pub const PASS: PassDecl = PassDecl {
    label: "pull_push",
    shader: include_str!("../../../shaders/pull_push.wgsl"),
    first_binding: 0,
    bindings: &[
        uniform("frame.uniform"),
        // Filled in place: the pixels without a sample are written, the rest stay.
        write("shade.color"),
        read("sampling.flags"),
        texture("gbuffer.albedo"),
        write(MOMENTS_STAGED[0]),
        dynamic_uniform("pull_push.levels", std::mem::size_of::<Level>() as u64),
        texture("gbuffer.normal_distance"),
        layers("pull_push.moments_in"),
        layers("pull_push.planes_in"),
        write(PLANES_STAGED),
        write(MOMENTS_STAGED[1]),
    ],
    attachments: &[],
    entry_points: &["pull_pixels", "pull", "push", "push_pixels"],
};

/// Twin of `struct Level` in the shader.
#[repr(C)]
#[derive(Debug, Clone, Copy, Default, Pod, Zeroable)]
pub struct Level {
    size: [u32; 2],
    origin: [u32; 2],
    near_size: [u32; 2],
    near_origin: [u32; 2],
    level: u32,
    has_parent: u32,
    ridge: f32,
    floor: f32,
    depth_tolerance: f32,
    material_tolerance: f32,
    /// Texels a row of the staging buffers holds at this level (copies need 256-byte rows).
    row: u32,
    /// `pull_pixels` only: the same for level 2, which it writes too (`near_*` is level 2's).
    next_row: u32,
}

/// Levels above the pixels the GPU keeps (at least one, so a 1×1 frame has a top cell).
pub fn levels(width: u32, height: u32) -> u32 {
    level_count(width, height).max(1)
}

/// Where level `l` (≥ 1) sits in its parity's atlas: the parity's first level at the corner,
/// the later (smaller) ones stacked in a column to its right.
fn origin(width: u32, height: u32, l: u32) -> [u32; 2] {
    let first = 2 - l % 2;
    if l == first {
        return [0, 0];
    }
    let x = level_size(width, height, first).0;
    let y = (first + 2..l)
        .step_by(2)
        .map(|k| level_size(width, height, k).1)
        .sum();
    [x, y]
}

/// Texel size of the atlas of levels with parity `odd` (1×1 where it holds none).
pub fn atlas_size(width: u32, height: u32, odd: bool) -> (u32, u32) {
    let top = levels(width, height);
    let first = if odd { 1 } else { 2 };
    if first > top {
        return (1, 1);
    }
    let (fw, fh) = level_size(width, height, first);
    let rest: Vec<u32> = (first + 2..=top).step_by(2).collect();
    let column_w = rest.first().map_or(0, |&k| level_size(width, height, k).0);
    let column_h = rest.iter().map(|&k| level_size(width, height, k).1).sum();
    (fw + column_w, fh.max(column_h))
}

/// Bytes of both atlases' moment and plane layers at this frame size.
pub fn pyramid_bytes(width: u32, height: u32) -> u64 {
    let texels = |odd| {
        let (w, h) = atlas_size(width, height, odd);
        u64::from(w) * u64::from(h)
    };
    (texels(false) + texels(true)) * u64::from(MOMENT_LAYERS + PLANE_LAYERS) * 16
        + STAGED
            .iter()
            .map(|&(_, layers, two)| staged_bytes(width, height, layers, two))
            .sum::<u64>()
}

/// Texels a staging row holds for a level `w` cells wide: copies take rows of 256 bytes.
fn staged_row(w: u32) -> u32 {
    w.next_multiple_of(wgpu::COPY_BYTES_PER_ROW_ALIGNMENT / 16)
}

/// Texels of level `l`'s layers in a staging buffer of `layers` layers.
fn staged_texels(width: u32, height: u32, l: u32, layers: u32) -> u64 {
    let (w, h) = level_size(width, height, l);
    u64::from(staged_row(w)) * u64::from(h.max(1)) * u64::from(layers)
}

/// Bytes of a staging buffer of `layers` layers: level 1, the largest level staged, and with
/// `two` level 2 after it (`pull_pixels` writes both levels' moments).
pub fn staged_bytes(width: u32, height: u32, layers: u32, two: bool) -> u64 {
    let level2 = if two {
        staged_texels(width, height, 2, layers)
    } else {
        0
    };
    (staged_texels(width, height, 1, layers) + level2) * 16
}

/// Bytes of the level uniforms: one slot per dispatch.
pub fn levels_bytes(width: u32, height: u32) -> u64 {
    SLOT * (2 * u64::from(levels(width, height)) + 1)
}

/// One slot per dispatch: pull_pixels (levels 1 and 2), pull per level from 3, push per level
/// from the top, push_pixels (as level 0).
fn slots(width: u32, height: u32) -> Vec<(&'static str, Level)> {
    let top = levels(width, height);
    let base = |l: u32, ridge: f32| Level {
        size: level_size(width, height, l).into(),
        origin: if l == 0 {
            [0, 0]
        } else {
            origin(width, height, l)
        },
        level: l,
        ridge,
        floor: DEMODULATION_FLOOR,
        depth_tolerance: DEPTH_TOLERANCE,
        material_tolerance: MATERIAL_TOLERANCE,
        row: staged_row(level_size(width, height, l).0),
        ..Level::default()
    };
    let near = |s: &mut Level, l: u32| {
        s.near_size = level_size(width, height, l).into();
        s.near_origin = origin(width, height, l);
    };
    let mut first = base(1, 0.0);
    if top >= 2 {
        near(&mut first, 2);
        first.next_row = staged_row(first.near_size[0]);
    }
    let mut out = vec![("pull_pixels", first)];
    for l in 3..=top {
        let mut s = base(l, 0.0);
        near(&mut s, l - 1);
        out.push(("pull", s));
    }
    for l in (0..=top).rev() {
        let mut s = base(l, if l == top { LAMBDA_TOP } else { LAMBDA });
        if l < top {
            near(&mut s, l + 1);
            s.has_parent = 1;
        }
        out.push((if l == 0 { "push_pixels" } else { "push" }, s));
    }
    out
}

/// Points the pyramid's ports at level `l`'s atlases: planes are read from the other parity
/// (the parents, pushing); moments from the other parity pulling (the children), from its own
/// pushing.
fn route(f: &mut Recorder, l: u32, pulling: bool) {
    let own = (l % 2) as usize;
    let other = 1 - own;
    f.route(
        "pull_push.moments_in",
        MOMENTS[if pulling { other } else { own }],
    );
    f.route("pull_push.planes_in", PLANES[other]);
}

/// Invocations a dispatch needs per axis: one per cell pulling, one per level-2 cell (2×2
/// level-1 cells) pulling from the pixels; pushing, one per 2×2 quads of cells (quads start
/// at odd cells, so a side of n has n/2 + 1 of them).
fn dispatch_cells(entry: &str, size: [u32; 2]) -> [u32; 2] {
    if entry.starts_with("push") {
        size.map(|n| (n / 2 + 1).div_ceil(2))
    } else if entry == "pull_pixels" {
        size.map(|n| n.div_ceil(2))
    } else {
        size
    }
}

/// Fills the frame in place (`shade.color`, whose samples the next frame's history already
/// holds: `frame::record`); from here on `frame.color` is the reconstructed colour.
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
        route(f, s.level, entry.starts_with("pull"));
        let [w, h] = dispatch_cells(entry, s.size);
        let size = DispatchSize::Groups(w.div_ceil(8), h.div_ceil(8), 1);
        let mut d = f.dispatch(&PASS, entry, size)?;
        d.offsets = vec![(i as u64 * SLOT) as u32];
        dispatches.push(d);
    }
    // A pass per dispatch, each level copied into its atlas before the next reads it; timed
    // as one.
    let span = f.timer.span(PASS.label);
    let last = dispatches.len().saturating_sub(1);
    for (i, ((entry, s), d)) in slots.iter().zip(&dispatches).enumerate() {
        {
            let mut pass = f.encoder.begin_compute_pass(&wgpu::ComputePassDescriptor {
                label: Some(PASS.label),
                timestamp_writes: f.timer.part(span, i == 0, i == last),
            });
            crate::render::graph::run(&mut pass, d, f.size);
        }
        if s.level > 0 {
            stage(f, entry.starts_with("pull"), s)?;
        }
    }
    f.route("frame.color", "shade.color");
    f.route(RECONSTRUCTED, "shade.color");
    Ok(())
}

/// Where a level sits in a staging buffer and in its atlas.
struct Region {
    size: [u32; 2],
    origin: [u32; 2],
    /// Texels a staging row holds.
    row: u32,
    /// Bytes before the level's first layer in the staging buffer.
    offset: u64,
}

/// Copies the level(s) a dispatch wrote from its staging buffers into their atlases:
/// `pull_pixels` wrote level 2 (its `near_*`) after level 1's layers.
fn stage(f: &mut Recorder, pulling: bool, s: &Level) -> Result<(), GraphError> {
    let own = Region {
        size: s.size,
        origin: s.origin,
        row: s.row,
        offset: 0,
    };
    if !pulling {
        let atlas = PLANES[(s.level % 2) as usize];
        return copy(f, PLANES_STAGED, atlas, 0, PLANE_LAYERS, &own);
    }
    let mut regions = vec![(s.level, own)];
    if s.level == 1 && s.near_size[0] > 0 {
        let (width, height) = f.size;
        let level2 = Region {
            size: s.near_size,
            origin: s.near_origin,
            row: s.next_row,
            // Level 1's layers, as `staged_bytes` sized them.
            offset: staged_texels(width, height, 1, STAGED_MOMENT_LAYERS) * 16,
        };
        regions.push((2, level2));
    }
    for (l, r) in &regions {
        let atlas = MOMENTS[(l % 2) as usize];
        for (i, staged) in MOMENTS_STAGED.into_iter().enumerate() {
            let first = i as u32 * STAGED_MOMENT_LAYERS;
            copy(f, staged, atlas, first, STAGED_MOMENT_LAYERS, r)?;
        }
    }
    Ok(())
}

/// Copies `layers` layers of the level at `r` from `staged` into `atlas`, from layer `first` on.
fn copy(
    f: &mut Recorder,
    staged: &'static str,
    atlas: &'static str,
    first: u32,
    layers: u32,
    r: &Region,
) -> Result<(), GraphError> {
    let missing = |name| GraphError::Missing {
        pass: PASS.label,
        name,
    };
    let buffer = f.resources.get_buffer(staged).ok_or(missing(staged))?;
    let texture = f.resources.get_texture(atlas).ok_or(missing(atlas))?.0;
    f.encoder.copy_buffer_to_texture(
        wgpu::TexelCopyBufferInfo {
            buffer,
            layout: wgpu::TexelCopyBufferLayout {
                offset: r.offset,
                bytes_per_row: Some(r.row * 16),
                rows_per_image: Some(r.size[1]),
            },
        },
        wgpu::TexelCopyTextureInfo {
            texture,
            mip_level: 0,
            origin: wgpu::Origin3d {
                x: r.origin[0],
                y: r.origin[1],
                z: first,
            },
            aspect: wgpu::TextureAspect::All,
        },
        wgpu::Extent3d {
            width: r.size[0],
            height: r.size[1],
            depth_or_array_layers: layers,
        },
    );
    Ok(())
}
