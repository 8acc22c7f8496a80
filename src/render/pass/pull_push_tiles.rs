//! Which workgroups pull-push's pixel fill runs: only 32×32 tiles with a covered pixel
//! without a sample, dispatched indirectly from a list. On the software adapter a workgroup
//! costs the same whether or not its lanes find work, so the background and the fully sampled
//! fovea were paid for in full. The fill's output is unchanged: a tile left out has nothing to
//! write. (Level 1's push listed the same way, only where the fill reads its planes, came out
//! slower than pushing every cell: 99–107 against 67–69 ms for all of pull-push at 1280×720.)

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

/// Bytes of the marks and of the list (a word a fill tile each).
pub fn bytes(width: u32, height: u32) -> (u64, u64) {
    let (x, y) = fill_grid(width, height);
    let tiles = u64::from(x.max(1)) * u64::from(y.max(1));
    (4 * tiles, 4 * tiles)
}

/// CPU twin of the shader: how many workgroups the fill lists for these per-pixel flags.
pub fn needed(width: u32, height: u32, flags: &[u32]) -> u32 {
    let (gx, gy) = fill_grid(width, height);
    let mut marks = vec![false; (gx * gy) as usize];
    for y in 0..height {
        for x in 0..width {
            let f = flags[(y * width + x) as usize];
            if f & FLAG_COVERED != 0 && f & (FLAG_SAMPLED | FLAG_REUSED) == 0 {
                // Tile k holds pixels 32k − 1 … 32k + 30.
                marks[((y + 1) / 32 * gx + (x + 1) / 32) as usize] = true;
            }
        }
    }
    marks.iter().filter(|&&m| m).count() as u32
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
            assert!(4 * invocations >= n + 1, "{n}: pixels past the last group");
            assert!(4 * (invocations - 8) < n + 1, "{n}: a group with no pixel");
        }
    }

    #[test]
    fn a_frame_needing_no_fill_lists_nothing_and_each_pixel_lists_its_own_tile() {
        let (w, h) = (200, 130);
        let mut flags = vec![FLAG_COVERED | FLAG_SAMPLED; (w * h) as usize];
        assert_eq!(needed(w, h, &flags), 0);
        flags
            .iter_mut()
            .for_each(|f| *f = FLAG_COVERED | FLAG_REUSED);
        assert_eq!(needed(w, h, &flags), 0, "reused samples need no fill");
        flags.iter_mut().for_each(|f| *f = 0);
        assert_eq!(needed(w, h, &flags), 0, "background needs no fill");
        // Tiles start at pixel −1: (30, 30) and (0, 0) share tile (0, 0), (31, 31) is in (1, 1).
        for (x, y) in [(30, 30), (0, 0)] {
            flags[(y * w + x) as usize] = FLAG_COVERED;
        }
        assert_eq!(needed(w, h, &flags), 1);
        flags[(31 * w + 31) as usize] = FLAG_COVERED;
        assert_eq!(needed(w, h, &flags), 2);
        flags.iter_mut().for_each(|f| *f = FLAG_COVERED);
        let (gx, gy) = fill_grid(w, h);
        assert_eq!(
            needed(w, h, &flags),
            gx * gy,
            "every tile of an unsampled frame"
        );
    }
}
