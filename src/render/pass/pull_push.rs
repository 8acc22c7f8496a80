//! Pull-push reconstruction (foveated frames with `reconstruction: pull_push`): moments pulled
//! up a pyramid of 2×2 cells, planes pushed back down, then every pixel filled. Replaces jump
//! flooding and the resolve pass for those frames; O(N) work instead of N log N plus a window.
//! The pyramid is kept in two texture atlases (odd and even levels); see the shader for why.
//! Each dispatch writes its level to a staging buffer that is then copied into the atlas: on
//! the software adapter a buffer store costs a seventh of a storage-texture store, and a copy
//! is a memcpy. The three dispatches nearest the pixels (the pull from them, level 1's push,
//! the fill) run only the tiles `pull_push_tiles` lists.
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
use crate::render::pass::pull_push_tiles;

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
/// row, `Level::row` texels a row. Level 1's moments are never stored (`push_level1` merges
/// them again from the pixels), so the moments' largest staged level is 2 and the planes' 1.
/// The moments' six layers take two buffers of three (a software adapter binds at most
/// 128 MiB of storage).
pub const MOMENTS_STAGED: [&str; 2] =
    ["pull_push.moments_staged[0]", "pull_push.moments_staged[1]"];
pub const PLANES_STAGED: &str = "pull_push.planes_staged";
/// Layers in each moments staging buffer.
const STAGED_MOMENT_LAYERS: u32 = MOMENT_LAYERS / 2;
/// Every staging buffer with its layers and the largest level it stages, as the targets
/// create them.
pub const STAGED: [(&str, u32, u32); 3] = [
    (MOMENTS_STAGED[0], STAGED_MOMENT_LAYERS, 2),
    (MOMENTS_STAGED[1], STAGED_MOMENT_LAYERS, 2),
    (PLANES_STAGED, PLANE_LAYERS, 1),
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
        read(pull_push_tiles::TILES),
    ],
    attachments: &[],
    entry_points: &["pull_pixels", "pull", "push", "push_level1", "push_pixels"],
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
    /// The shader's struct is 64 bytes: its size rounds up to its 8-byte alignment.
    _pad: u32,
}

/// Levels above the pixels the GPU keeps (at least one, so a 1×1 frame has a top cell).
pub fn levels(width: u32, height: u32) -> u32 {
    level_count(width, height).max(1)
}

/// The levels after a parity's first (`first`: 1 odd, 2 even), stacked in a column.
fn column(width: u32, height: u32, first: u32) -> impl Iterator<Item = u32> {
    (first + 2..=levels(width, height)).step_by(2)
}

/// The column's width (its first level's) and height.
fn column_size(width: u32, height: u32, first: u32) -> (u32, u32) {
    let w = column(width, height, first).next();
    let h = column(width, height, first).map(|k| level_size(width, height, k).1);
    (w.map_or(0, |k| level_size(width, height, k).0), h.sum())
}

/// Where level `l` (≥ 1) sits in its parity's atlas: the later levels stacked in a column at
/// the left edge, the parity's first level to its right. Moments never hold level 1, so the
/// odd moments atlas is the column alone.
fn origin(width: u32, height: u32, l: u32) -> [u32; 2] {
    let first = 2 - l % 2;
    if l == first {
        return [column_size(width, height, first).0, 0];
    }
    let above = column(width, height, first).take_while(|&k| k < l);
    [0, above.map(|k| level_size(width, height, k).1).sum()]
}

/// Texel size of the atlas of levels with parity `odd`, with its first level or without
/// (`first`; moments of level 1 are never kept), 1×1 where it holds none.
pub fn atlas_size(width: u32, height: u32, odd: bool, first: bool) -> (u32, u32) {
    let top = levels(width, height);
    let f = if odd { 1 } else { 2 };
    let (cw, ch) = column_size(width, height, f);
    let (w, h) = if first && f <= top {
        let (fw, fh) = level_size(width, height, f);
        (cw + fw, fh.max(ch))
    } else {
        (cw, ch)
    };
    (w.max(1), h.max(1))
}

/// Whether the moments atlas of this parity holds its first level: level 2 yes, level 1 no.
pub fn moments_hold_first(odd: bool) -> bool {
    !odd
}

/// Bytes of both atlases' moment and plane layers at this frame size.
pub fn pyramid_bytes(width: u32, height: u32) -> u64 {
    let texels = |odd, first| {
        let (w, h) = atlas_size(width, height, odd, first);
        u64::from(w) * u64::from(h)
    };
    let moments = texels(false, moments_hold_first(false)) + texels(true, moments_hold_first(true));
    let planes = texels(false, true) + texels(true, true);
    (moments * u64::from(MOMENT_LAYERS) + planes * u64::from(PLANE_LAYERS)) * 16
        + STAGED
            .iter()
            .map(|&(_, layers, l)| staged_bytes(width, height, layers, l))
            .sum::<u64>()
}

/// Texels a staging row holds for a level `w` cells wide: copies take rows of 256 bytes.
fn staged_row(w: u32) -> u32 {
    w.next_multiple_of(wgpu::COPY_BYTES_PER_ROW_ALIGNMENT / 16)
}

/// Bytes of a staging buffer of `layers` layers whose largest level is `l`.
pub fn staged_bytes(width: u32, height: u32, layers: u32, l: u32) -> u64 {
    let (w, h) = level_size(width, height, l);
    u64::from(staged_row(w)) * u64::from(h.max(1)) * u64::from(layers) * 16
}

/// Bytes of the level uniforms: one slot per dispatch.
pub fn levels_bytes(width: u32, height: u32) -> u64 {
    SLOT * (2 * u64::from(levels(width, height)) + 1)
}

/// One slot per dispatch: pull_pixels (level 2, from the pixels), pull per level from 3, push
/// per level from the top (level 1: push_level1), push_pixels (as level 0).
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
    let mut out = Vec::new();
    if top >= 2 {
        let mut first = base(2, 0.0);
        near(&mut first, 1);
        out.push(("pull_pixels", first));
    }
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
        let entry = match l {
            0 => "push_pixels",
            1 => "push_level1",
            _ => "push",
        };
        out.push((entry, s));
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

/// Invocations a dispatch needs per axis: one per cell pulling; pushing, one per 2×2 quads
/// of cells (quads start at odd cells, so a side of n has n/2 + 1 of them).
fn dispatch_cells(entry: &str, size: [u32; 2]) -> [u32; 2] {
    if entry.starts_with("push") {
        size.map(|n| (n / 2 + 1).div_ceil(2))
    } else {
        size
    }
}

/// Parts a frame in parts runs the dispatches in: the pulls and the pushes down to level 2,
/// level 1's push, the pixel fill (about 40%, 30% and 30% of the time).
pub const PARTS: u32 = 3;

/// Fills the frame in place (`shade.color`, whose samples the next frame's history already
/// holds: `frame::record_reconstruction`), every dispatch (`part` None) or those of one of
/// [`PARTS`]; from then on `frame.color` is the reconstructed colour.
pub fn record(f: &mut Recorder, part: Option<u32>) -> Result<(), GraphError> {
    let (width, height) = f.size;
    let slots = slots(width, height);
    let n = slots.len();
    if part.unwrap_or(0) == 0 {
        // The level uniforms, once a frame: later parts find them in place.
        let mut bytes = vec![0u8; n * SLOT as usize];
        for (i, (_, s)) in slots.iter().enumerate() {
            let at = i * SLOT as usize;
            bytes[at..at + std::mem::size_of::<Level>()].copy_from_slice(bytemuck::bytes_of(s));
        }
        f.queue
            .write_buffer(f.buffer("pull_push.levels")?, 0, &bytes);
    }
    // Level 1's push is the last dispatch but the fill.
    let split = slots
        .iter()
        .position(|(e, _)| *e == "push_level1")
        .unwrap_or(n);
    let range = match part {
        None => 0..n,
        Some(0) => 0..split,
        Some(1) => split..(split + 1).min(n),
        Some(_) => (split + 1).min(n)..n,
    };
    if range.is_empty() {
        return Ok(());
    }
    if range.start == 0 {
        pull_push_tiles::record(f)?;
        // The pull from the pixels skips tiles without a sample: their cells stay zero, which
        // `load_cell` reads as empty (a memset, timed with the frame only).
        for name in MOMENTS_STAGED {
            let b = f.buffer(name)?.clone();
            f.encoder.clear_buffer(&b, 0, None);
        }
    }
    let mut dispatches = Vec::with_capacity(range.len());
    for i in range.clone() {
        let (entry, s) = &slots[i];
        route(f, s.level, entry.starts_with("pull"));
        let [w, h] = dispatch_cells(entry, s.size);
        let listed = |offset| {
            Ok(DispatchSize::Indirect(
                f.buffer(pull_push_tiles::ARGS)?.clone(),
                offset,
            ))
        };
        let size = match *entry {
            "push_pixels" => listed(0)?,
            "pull_pixels" => listed(pull_push_tiles::PULL_ARGS)?,
            "push_level1" => listed(pull_push_tiles::LEVEL1_ARGS)?,
            _ => DispatchSize::Groups(w.div_ceil(8), h.div_ceil(8), 1),
        };
        let mut d = f.dispatch(&PASS, entry, size)?;
        d.offsets = vec![(i as u64 * SLOT) as u32];
        dispatches.push(d);
    }
    // A pass per dispatch, each level copied into its atlas before the next reads it; timed
    // as one.
    let span = f.timer.span(PASS.label);
    let last = dispatches.len() - 1;
    for (k, ((entry, s), d)) in slots[range].iter().zip(&dispatches).enumerate() {
        {
            let mut pass = f.encoder.begin_compute_pass(&wgpu::ComputePassDescriptor {
                label: Some(PASS.label),
                timestamp_writes: f.timer.part(span, k == 0, k == last),
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

/// Copies the level a dispatch wrote from its staging buffers into its atlas.
fn stage(f: &mut Recorder, pulling: bool, s: &Level) -> Result<(), GraphError> {
    let atlas = |kind: [&'static str; 2]| kind[(s.level % 2) as usize];
    if !pulling {
        return copy(f, PLANES_STAGED, atlas(PLANES), 0, PLANE_LAYERS, s);
    }
    for (i, staged) in MOMENTS_STAGED.into_iter().enumerate() {
        let first = i as u32 * STAGED_MOMENT_LAYERS;
        copy(f, staged, atlas(MOMENTS), first, STAGED_MOMENT_LAYERS, s)?;
    }
    Ok(())
}

/// Copies `layers` layers of level `r` from `staged` into `atlas`, from layer `first` on.
fn copy(
    f: &mut Recorder,
    staged: &'static str,
    atlas: &'static str,
    first: u32,
    layers: u32,
    r: &Level,
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
                offset: 0,
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

#[cfg(test)]
mod tests {
    use super::*;

    /// Every level lies inside its atlases and apart from the other levels of its parity, and
    /// the moments atlases hold every level but 1 (which is never stored), at odd, tiny and
    /// the largest sizes a session may ask for.
    #[test]
    fn levels_tile_their_atlases() {
        for (w, h) in [
            (1, 1),
            (3, 2),
            (97, 61),
            (641, 479),
            (1280, 720),
            (3840, 2160),
        ] {
            let top = levels(w, h);
            for odd in [false, true] {
                let own: Vec<u32> = (1..=top).filter(|l| (l % 2 == 1) == odd).collect();
                let rect = |l: u32| {
                    let ([x, y], (lw, lh)) = (origin(w, h, l), level_size(w, h, l));
                    (x, y, x + lw, y + lh)
                };
                for &l in &own {
                    let (x0, y0, x1, y1) = rect(l);
                    let (pw, ph) = atlas_size(w, h, odd, true);
                    assert!(x1 <= pw && y1 <= ph, "{w}x{h} level {l} outside the planes");
                    if l >= 2 {
                        let (mw, mh) = atlas_size(w, h, odd, moments_hold_first(odd));
                        assert!(
                            x1 <= mw && y1 <= mh,
                            "{w}x{h} level {l} outside the moments"
                        );
                    }
                    for &k in own.iter().filter(|&&k| k != l) {
                        let (a0, b0, a1, b1) = rect(k);
                        let apart = x1 <= a0 || a1 <= x0 || y1 <= b0 || b1 <= y0;
                        assert!(apart, "{w}x{h}: levels {l} and {k} overlap");
                    }
                }
            }
            // Level 1's moments are not kept: the odd moments atlas is smaller than its planes'.
            if top >= 3 {
                let (mw, mh) = atlas_size(w, h, true, moments_hold_first(true));
                let (pw, ph) = atlas_size(w, h, true, true);
                assert!(u64::from(mw) * u64::from(mh) < u64::from(pw) * u64::from(ph) / 4);
            }
        }
    }
}
