//! Which workgroups pull-push's three dispatches nearest the pixels run, each dispatched
//! indirectly from a list: the fill only on 32×32 tiles with a covered pixel without a sample,
//! the pull from the pixels only on tiles with a sample (its other cells are empty, and the
//! staging buffers it writes are cleared first, zeros being an empty cell), and level 1's push
//! only where a listed fill tile reads its planes (nothing else reads them). On the software
//! adapter a workgroup costs the same whether or not its lanes find work, so the background
//! and the fully sampled fovea were paid for in full. Output unchanged: a tile left out has
//! nothing to write that is read.

use crate::render::graph::{read, uniform, write, DispatchSize, GraphError, PassDecl, Recorder};
use crate::render::uniforms::{FLAG_COVERED, FLAG_REUSED, FLAG_SAMPLED};

pub const MARKS: &str = "pull_push.tile_marks";
pub const ARGS: &str = "pull_push.tile_args";
pub const TILES: &str = "pull_push.tiles";

pub const PASS: PassDecl = PassDecl {
    label: "pull_push_tiles",
    shader: include_str!("../../../shaders/pull_push_tiles.wgsl"),
    first_binding: 0,
    bindings: &[
        uniform("frame.uniform"),
        read("sampling.flags"),
        write(MARKS),
        write(ARGS),
        write(TILES),
    ],
    attachments: &[],
    entry_points: &["mark", "list"],
};

/// The fill's workgroups along a side of `n` pixels: an invocation per two 2×2 quads of
/// pixels, quads starting at odd pixels (`n/2 + 1` of them), 8 invocations a group.
pub fn push_groups(n: u32) -> u32 {
    (n / 2 + 1).div_ceil(2).div_ceil(8)
}

/// The fill's workgroups (one per 32×32 tile of pixels, from pixel −1).
pub fn fill_grid(width: u32, height: u32) -> (u32, u32) {
    (push_groups(width), push_groups(height))
}

/// The pull's workgroups (one per 32×32 tile of pixels, from pixel 0): never more along a
/// side than the fill's.
pub fn pull_grid(width: u32, height: u32) -> (u32, u32) {
    (width.div_ceil(32), height.div_ceil(32))
}

/// Level 1's push's workgroups (one per 32×32 cells of level 1 from cell −1, 64×64 pixels):
/// the push's grid at level 1's size, never more along a side than the fill's.
pub fn level1_grid(width: u32, height: u32) -> (u32, u32) {
    (
        push_groups(width.div_ceil(2)),
        push_groups(height.div_ceil(2)),
    )
}

/// Byte offsets of the pull's and level 1's indirect arguments in [`ARGS`] (the fill's at 0).
pub const PULL_ARGS: u64 = 12;
pub const LEVEL1_ARGS: u64 = 24;
/// Bytes of [`ARGS`]: three indirect dispatches.
pub const ARGS_BYTES: u64 = 36;

/// Bytes of the marks (two words a fill tile) and of the lists (three, interleaved).
pub fn bytes(width: u32, height: u32) -> (u64, u64) {
    let (x, y) = fill_grid(width, height);
    let tiles = u64::from(x.max(1)) * u64::from(y.max(1));
    (8 * tiles, 12 * tiles)
}

/// CPU twin of the shader: how many workgroups the fill, the pull and level 1's push list for
/// these per-pixel flags.
pub fn needed(width: u32, height: u32, flags: &[u32]) -> (u32, u32, u32) {
    let (gx, gy) = fill_grid(width, height);
    let (px, py) = pull_grid(width, height);
    let mut fill = vec![false; (gx * gy) as usize];
    let mut pull = vec![false; (px * py) as usize];
    for y in 0..height {
        for x in 0..width {
            let f = flags[(y * width + x) as usize];
            let sample = f & (FLAG_SAMPLED | FLAG_REUSED) != 0;
            if f & FLAG_COVERED != 0 && !sample {
                // Fill tile k holds pixels 32k − 1 … 32k + 30.
                fill[((y + 1) / 32 * gx + (x + 1) / 32) as usize] = true;
            }
            if f & FLAG_COVERED != 0 && sample {
                pull[(y / 32 * px + x / 32) as usize] = true;
            }
        }
    }
    // Fill tile k reads level-1 cells 16k − 1 … 16k + 15, level 1's workgroup j writes
    // 32j − 1 … 32j + 30: j runs where a fill tile 2j − 1 … 2j + 1 (each axis) does, so tile
    // k needs the workgroups ⌊k/2⌋ … ⌈k/2⌉.
    let (lx, ly) = level1_grid(width, height);
    let mut level1 = vec![false; (lx * ly) as usize];
    for y in 0..gy {
        for x in 0..gx {
            if fill[(y * gx + x) as usize] {
                for j in (x / 2)..=x.div_ceil(2).min(lx.saturating_sub(1)) {
                    for i in (y / 2)..=y.div_ceil(2).min(ly.saturating_sub(1)) {
                        level1[(i * lx + j) as usize] = true;
                    }
                }
            }
        }
    }
    let count = |m: &[bool]| m.iter().filter(|&&m| m).count() as u32;
    (count(&fill), count(&pull), count(&level1))
}

/// Marks the tiles and lists them, before pull-push (its own timed pass).
pub fn record(f: &mut Recorder) -> Result<(), GraphError> {
    let (w, h) = f.size;
    let (gx, gy) = fill_grid(w, h);
    for name in [MARKS, ARGS] {
        let b = f.buffer(name)?.clone();
        f.encoder.clear_buffer(&b, 0, None);
    }
    let mark = f.dispatch(&PASS, "mark", DispatchSize::Groups(gx, gy, 1))?;
    let list = f.dispatch(
        &PASS,
        "list",
        DispatchSize::Groups(gx.div_ceil(8), gy.div_ceil(8), 1),
    )?;
    f.compute(PASS.label, &[mark, list]);
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_grids_are_the_push_dispatches() {
        // The fill's invocations start at pixel 4·id − 1 and cover 4 pixels: the last must
        // reach the frame's last pixel, and none start past it.
        for n in [
            1u32, 2, 3, 31, 32, 33, 62, 63, 64, 97, 480, 720, 1280, 2160, 3840,
        ] {
            let invocations = 8 * push_groups(n);
            assert!(4 * invocations > n, "{n}: pixels past the last group");
            assert!(4 * (invocations - 8) < n + 1, "{n}: a group with no pixel");
        }
    }

    #[test]
    fn each_pixel_lists_its_own_tiles_and_a_frame_without_work_lists_none() {
        let (w, h) = (200, 130);
        let (gx, gy) = fill_grid(w, h);
        let (px, py) = pull_grid(w, h);
        let (lx, ly) = level1_grid(w, h);
        assert!(px <= gx && py <= gy, "the pull's grid fits in the fill's");
        assert!(lx <= gx && ly <= gy, "level 1's grid fits in the fill's");
        // Frames with every pixel alike.
        for (every, want, why) in [
            (0, (0, 0, 0), "background needs none"),
            (
                FLAG_COVERED | FLAG_SAMPLED,
                (0, px * py, 0),
                "every pixel sampled: no fill",
            ),
            (
                FLAG_COVERED | FLAG_REUSED,
                (0, px * py, 0),
                "reused samples count as samples",
            ),
            (
                FLAG_COVERED,
                (gx * gy, 0, lx * ly),
                "no sample: nothing to pull",
            ),
        ] {
            assert_eq!(needed(w, h, &vec![every; (w * h) as usize]), want, "{why}");
        }
        // Fill tiles start at pixel −1, pull tiles at 0: (30, 30) and (0, 0) share both,
        // (31, 31) is in fill tile (1, 1) and pull tile (0, 0), (32, 32) in (1, 1) of both.
        // Fill tile 0 reads level-1 cells −1 … 15 (level 1's workgroup 0: −1 … 30), tile 1
        // cells 15 … 31, in workgroups 0 and 1.
        let mut flags = vec![0; (w * h) as usize];
        for (x, y) in [(30, 30), (0, 0)] {
            flags[(y * w + x) as usize] = FLAG_COVERED;
        }
        assert_eq!(needed(w, h, &flags), (1, 0, 1));
        flags[(31 * w + 31) as usize] = FLAG_COVERED;
        assert_eq!(needed(w, h, &flags), (2, 0, 4));
        flags[(31 * w + 31) as usize] = FLAG_COVERED | FLAG_SAMPLED;
        assert_eq!(needed(w, h, &flags), (1, 1, 1));
        flags[(32 * w + 32) as usize] = FLAG_COVERED | FLAG_REUSED;
        assert_eq!(needed(w, h, &flags), (1, 2, 1));
    }
}
