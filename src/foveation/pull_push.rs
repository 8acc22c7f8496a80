//! Pull-push reconstruction: seed 000's screen-space hierarchical interpolation applied to the
//! foveated samples, as the CPU twin of `shaders/pull_push.wgsl` (same order of operations, f32).
//!
//! *Pull* builds a pyramid of 2×2 reductions up to one cell. Each cell keeps first-order moments
//! of the samples under it: their weight W, mean position x̄, mean value c̄, the position scatter
//! S = Σw(x − x̄)(x − x̄)ᵀ and the cross term T = Σw(x − x̄)(c − c̄)ᵀ. Four children merge exactly
//! (parallel-axis theorem), so a cell knows the least-squares plane through its samples without
//! visiting them again. As in Gortler et al. 1996, W is clamped to 1 after each merge (all
//! weight-proportional moments scaled alike): a coarse level fills holes but never outvotes a
//! finer one that has samples.
//!
//! *Push* goes back down and gives every cell a plane: its value at the cell centre and a
//! gradient. The coarse estimate at a cell is the bilinear blend of its four parents' planes
//! evaluated at its centre; the cell's own gradient solves (S + λI)g = T + λ·g_coarse, so a cell
//! whose samples span two dimensions trusts them and one with a single sample (or a line of
//! them) falls back on the coarse gradient; its own value is c̄ moved from x̄ to the centre along
//! g; the two estimates mix as W·own + (1 − W)·coarse. Every step is exact for a linear
//! function, so linear ramps are reproduced wherever the frame holds three samples not on a line,
//! away from the border. Work: 4/3 N cells up and down, O(N) in all, against JFA's N log N.
//!
//! What is reconstructed is the ratio of each sample to [`proxy`], the key light's Lambert term
//! on the G-buffer's albedo and normal: the pixel's own proxy multiplies the result back, so
//! textures and normal maps stay sharp without samples, and the pixel's depth and material weight
//! the four parents so planes from another surface or material (whose ratio to the proxy jumps:
//! an emitter beside a wall) barely reach across a silhouette or a material boundary.

/// Reconstruction works on colour / (proxy + FLOOR), the proxy being what the G-buffer alone
/// predicts ([`proxy`]): texture, normal-map and shading-normal detail then come back per pixel,
/// and a black texel cannot blow a sample up without bound.
pub const DEMODULATION_FLOOR: f32 = 0.05;

/// The key light's Lambert term with the ambient on the albedo, plus the floor: the divisor of
/// the reconstructed ratio. Twin of `proxy` in `shaders/pull_push.wgsl` (and `lambert` in
/// `shaders/common.wgsl`). `light` is the light's colour times its intensity.
pub fn proxy(
    albedo: [f32; 3],
    normal: [f32; 3],
    to_light: [f32; 3],
    light: [f32; 3],
    ambient: f32,
) -> [f32; 3] {
    let len = normal.iter().map(|v| v * v).sum::<f32>().sqrt();
    let n = if len > 1e-20 {
        normal.map(|v| v / len)
    } else {
        [0.0; 3]
    };
    let cos = (n[0] * to_light[0] + n[1] * to_light[1] + n[2] * to_light[2]).max(0.0);
    std::array::from_fn(|c| albedo[c] * light[c] * (cos + ambient) + DEMODULATION_FLOOR)
}

/// λ in units of W·s² (s the cell's side in pixels): a cell of uniformly spread samples has
/// S ≈ W·s²/12·I per axis, so its own scatter outweighs the coarse gradient four to one.
pub const LAMBDA: f32 = 1.0 / 48.0;

/// Relative depth difference at which a parent's plane counts half (joint-bilateral weights):
/// planes from another surface (the floor behind a sphere) barely reach across a silhouette.
pub const DEPTH_TOLERANCE: f32 = 0.05;

/// Material-id difference at which a parent's plane counts half. Ids are categories, yet a cell
/// mixing materials carries their mean: a mix of ids 1 and 3 passes for id 2, a rare coincidence
/// that only loosens the weighting there.
pub const MATERIAL_TOLERANCE: f32 = 0.25;

/// Where a pixel's plane belongs: its distance from the eye and its material id.
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct Key {
    pub depth: f32,
    pub material: f32,
}

/// λ at the top cell, which has no coarse gradient to lean on (zero would bias it): only enough
/// to keep a frame whose samples lie on one line solvable.
pub const LAMBDA_TOP: f32 = 1e-6;

/// One cell's moments (pull) or, after push, its plane (`c` at the centre, `t` the gradient).
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct Cell {
    pub w: f32,
    /// Mean sample position, pixels (pixel centres at +0.5).
    pub mean: [f32; 2],
    /// Mean depth (any unit) and material id of the samples; after push, those the plane
    /// belongs to.
    pub depth: f32,
    pub material: f32,
    /// Spread of depth and material id among the samples (weighted variances): a cell that
    /// straddles an edge lends its plane less, however its means happen to fall.
    pub depth_var: f32,
    pub material_var: f32,
    pub c: [f32; 3],
    /// Position scatter: xx, xy, yy.
    pub s: [f32; 3],
    /// Cross moments per axis and channel; after push, the gradient per axis and channel.
    pub t: [[f32; 3]; 2],
    /// Smallest and largest sample value, any channel, under the cell (after push: around it).
    /// One pair for all channels rather than one per channel: the bound is there to stop a plane
    /// going below zero or far above the brightest sample, and two floats fit the spare slots of
    /// the GPU's plane, whose every vec4 is loaded four times per pixel.
    pub range: [f32; 2],
}

/// A range that holds nothing (its union with any range is that range).
pub const EMPTY_RANGE: [f32; 2] = [f32::INFINITY, f32::NEG_INFINITY];

fn union(a: &[f32; 2], b: &[f32; 2]) -> [f32; 2] {
    [a[0].min(b[0]), a[1].max(b[1])]
}

impl Cell {
    /// A sample at pixel (x, y).
    pub fn sample(x: u32, y: u32, c: [f32; 3], key: Key) -> Cell {
        Cell {
            w: 1.0,
            mean: [x as f32 + 0.5, y as f32 + 0.5],
            depth: key.depth,
            material: key.material,
            c,
            range: [c[0].min(c[1]).min(c[2]), c[0].max(c[1]).max(c[2])],
            ..Cell::default()
        }
    }

    /// Moments and plane empty, range empty.
    pub fn empty() -> Cell {
        Cell {
            range: EMPTY_RANGE,
            ..Cell::default()
        }
    }

    /// The exact merge of up to four children, then W clamped to 1.
    pub fn merge(children: &[Cell]) -> Cell {
        let mut out = Cell::empty();
        for ch in children {
            out.w += ch.w;
            out.range = union(&out.range, &ch.range);
        }
        if out.w <= 0.0 {
            return out;
        }
        for ch in children {
            let k = ch.w / out.w;
            for a in 0..2 {
                out.mean[a] += k * ch.mean[a];
            }
            out.depth += k * ch.depth;
            out.material += k * ch.material;
            for (o, c) in out.c.iter_mut().zip(ch.c) {
                *o += k * c;
            }
        }
        for ch in children.iter().filter(|c| c.w > 0.0) {
            let k = ch.w / out.w;
            out.depth_var += k * (ch.depth_var + (ch.depth - out.depth).powi(2));
            out.material_var += k * (ch.material_var + (ch.material - out.material).powi(2));
            let d = [ch.mean[0] - out.mean[0], ch.mean[1] - out.mean[1]];
            out.s[0] += ch.s[0] + ch.w * d[0] * d[0];
            out.s[1] += ch.s[1] + ch.w * d[0] * d[1];
            out.s[2] += ch.s[2] + ch.w * d[1] * d[1];
            for (t, (ch_t, d)) in out.t.iter_mut().zip(ch.t.iter().zip(d)) {
                for c in 0..3 {
                    t[c] += ch_t[c] + ch.w * d * (ch.c[c] - out.c[c]);
                }
            }
        }
        if out.w > 1.0 {
            let k = 1.0 / out.w;
            out.w = 1.0;
            for v in &mut out.s {
                *v *= k;
            }
            for row in &mut out.t {
                for v in row {
                    *v *= k;
                }
            }
        }
        out
    }
}

/// Cells per side at `level` (level 0: pixels).
pub fn level_size(width: u32, height: u32, level: u32) -> (u32, u32) {
    let s = 1u32 << level;
    (width.div_ceil(s), height.div_ceil(s))
}

/// Pull levels above the pixels: the top level is one cell.
pub fn level_count(width: u32, height: u32) -> u32 {
    let n = width.max(height).max(1);
    n.next_power_of_two().trailing_zeros()
}

/// The coarse estimate at a level-`level` cell's centre from the completed level above: value
/// and gradient blended from the four parents' planes evaluated there, bilinearly and by how
/// close each parent's depth and material are to `key` (`None`: the parents' blend). Each
/// plane is exact for a linear function, so any normalised weights keep it exact. The result's
/// range is the union of the parents' sample ranges.
pub fn coarse_plane(
    parent: &[Cell],
    parent_size: (u32, u32),
    level: u32,
    (x, y): (u32, u32),
    key: Option<Key>,
) -> Cell {
    let s = (1u32 << level) as f32;
    let centre = [(x as f32 + 0.5) * s, (y as f32 + 0.5) * s];
    let ps = 2.0 * s;
    // Parent-grid coordinates of this centre, measured from parent centres.
    let u = [centre[0] / ps - 0.5, centre[1] / ps - 0.5];
    let base = [u[0].floor(), u[1].floor()];
    let f = [u[0] - base[0], u[1] - base[1]];
    let mut parents = [(Cell::default(), [0.0f32; 2], 0.0f32); 4];
    for (i, (k, wxy)) in parent_indices(parent_size, base, f).into_iter().enumerate() {
        let (px, py) = (k % parent_size.0, k / parent_size.0);
        let pc = [(px as f32 + 0.5) * ps, (py as f32 + 0.5) * ps];
        parents[i] = (parent[k as usize], pc, wxy);
    }
    let target = key.unwrap_or_else(|| Key {
        depth: parents.iter().map(|(p, _, k)| k * p.depth).sum(),
        material: parents.iter().map(|(p, _, k)| k * p.material).sum(),
    });
    // The expected squared difference between the target and a sample under the parent:
    // the means' difference squared plus the parent's spread.
    let weight = |p: &Cell, k: f32| {
        let scale = (DEPTH_TOLERANCE * target.depth.abs()).max(1e-12);
        let r2 = ((p.depth - target.depth).powi(2) + p.depth_var) / (scale * scale);
        let m2 = ((p.material - target.material).powi(2) + p.material_var)
            / (MATERIAL_TOLERANCE * MATERIAL_TOLERANCE);
        k / ((1.0 + r2) * (1.0 + m2))
    };
    let mut total: f32 = parents.iter().map(|(p, _, k)| weight(p, *k)).sum();
    // Every parent on another surface: plain bilinear rather than dividing by nothing.
    let bilateral = total > 1e-6;
    if !bilateral {
        total = 1.0;
    }
    let mut out = Cell {
        depth: target.depth,
        material: target.material,
        ..Cell::empty()
    };
    for (p, pc, k) in &parents {
        out.range = union(&out.range, &p.range);
        let k = if bilateral { weight(p, *k) } else { *k } / total;
        let d = [centre[0] - pc[0], centre[1] - pc[1]];
        for ch in 0..3 {
            out.c[ch] += k * (p.c[ch] + p.t[0][ch] * d[0] + p.t[1][ch] * d[1]);
            out.t[0][ch] += k * p.t[0][ch];
            out.t[1][ch] += k * p.t[1][ch];
        }
    }
    out
}

/// The four bilinear parents of a point at parent-grid position `base` + `f` (`f` in [0, 1)),
/// clamped into the parent level (edge cells stand in past its border): index and weight.
fn parent_indices(parent_size: (u32, u32), base: [f32; 2], f: [f32; 2]) -> [(u32, f32); 4] {
    let mut out = [(0, 0.0); 4];
    let mut i = 0;
    for (dy, wy) in [(0, 1.0 - f[1]), (1, f[1])] {
        for (dx, wx) in [(0, 1.0 - f[0]), (1, f[0])] {
            let px = (base[0] as i64 + dx).clamp(0, i64::from(parent_size.0) - 1) as u32;
            let py = (base[1] as i64 + dy).clamp(0, i64::from(parent_size.1) - 1) as u32;
            out[i] = (py * parent_size.0 + px, wx * wy);
            i += 1;
        }
    }
    out
}

/// `v` at cell (x, y) of a level (a pixel, or an empty level-1 cell) clamped per channel
/// between the smallest and largest value of its four parents at their own centres, where the
/// cell lies inside their square (not in the level's outer ring). A linear ratio there is
/// bilinear in the corners and never leaves them; a plane fitted to a highlight's steep flank,
/// evaluated a pixel away, does (a dark dot beside the highlight, inside the wider range of
/// the samples around). The GPU (`within_corners` in the shader) applies the same bound.
pub fn within_corners(
    parent: &[Cell],
    parent_size: (u32, u32),
    (x, y): (u32, u32),
    v: [f32; 3],
) -> [f32; 3] {
    let u = [(x as f32 + 0.5) / 2.0 - 0.5, (y as f32 + 0.5) / 2.0 - 0.5];
    let base = [u[0].floor(), u[1].floor()];
    // At the border the parents are clamped and their square does not hold the pixel, where a
    // linear ratio rightly extrapolates.
    let inside = |b: f32, n: u32| b >= 0.0 && b + 1.0 < n as f32;
    if !(inside(base[0], parent_size.0) && inside(base[1], parent_size.1)) {
        return v;
    }
    let parents = parent_indices(parent_size, base, [u[0] - base[0], u[1] - base[1]]);
    std::array::from_fn(|ch| {
        let values = parents.map(|(k, _)| parent[k as usize].c[ch]);
        let lo = values.iter().copied().fold(f32::INFINITY, f32::min);
        let hi = values.iter().copied().fold(f32::NEG_INFINITY, f32::max);
        // As WGSL's clamp: min(max(v, lo), hi), which never panics.
        v[ch].max(lo).min(hi)
    })
}

/// Completes one cell from its pulled moments and the coarse plane at its centre; `ridge` is
/// [`LAMBDA`], or [`LAMBDA_TOP`] at the top cell. Pixels (level 0) are kept within the sample
/// values under and around them (the union of their parents' ranges), so a plane cannot
/// overshoot past what the samples hold (a highlight's flank extrapolated below zero); a linear
/// function meets that bound only outside its samples' hull. Coarser cells are not bounded:
/// a partial cell at the frame's edge has its centre outside the frame, where the plane rightly
/// extrapolates.
pub fn complete(cell: &Cell, coarse: &Cell, ridge: f32, level: u32, (x, y): (u32, u32)) -> Cell {
    let range = union(&cell.range, &coarse.range);
    let bound = |v: f32| {
        if level == 0 && range[0] <= range[1] {
            v.clamp(range[0], range[1])
        } else {
            v
        }
    };
    if cell.w <= 0.0 {
        let mut out = *coarse;
        for ch in 0..3 {
            out.c[ch] = bound(out.c[ch]);
        }
        return out;
    }
    let side = (1u32 << level) as f32;
    let lambda = ridge * cell.w * side * side;
    let (a, b, d) = (cell.s[0] + lambda, cell.s[1], cell.s[2] + lambda);
    let det = a * d - b * b;
    let centre = [(x as f32 + 0.5) * side, (y as f32 + 0.5) * side];
    let off = [centre[0] - cell.mean[0], centre[1] - cell.mean[1]];
    let mut out = Cell {
        w: 1.0,
        mean: centre,
        depth: cell.depth,
        material: cell.material,
        depth_var: cell.depth_var,
        material_var: cell.material_var,
        range,
        ..Cell::default()
    };
    for ch in 0..3 {
        let rx = cell.t[0][ch] + lambda * coarse.t[0][ch];
        let ry = cell.t[1][ch] + lambda * coarse.t[1][ch];
        let g = if det > 0.0 {
            [(d * rx - b * ry) / det, (a * ry - b * rx) / det]
        } else {
            [coarse.t[0][ch], coarse.t[1][ch]]
        };
        let own = cell.c[ch] + g[0] * off[0] + g[1] * off[1];
        let v = cell.w * own + (1.0 - cell.w) * coarse.c[ch];
        out.c[ch] = bound(v);
        out.t[0][ch] = g[0];
        out.t[1][ch] = g[1];
    }
    out
}

/// Fills every pixel from the samples (`None`: no sample) and every pixel's depth and material.
/// Pixels with a sample keep it.
pub fn reconstruct(
    width: u32,
    height: u32,
    samples: &[Option<[f32; 3]>],
    keys: &[Key],
) -> Vec<[f32; 3]> {
    pyramid(width, height, samples, keys)[0]
        .iter()
        .map(|c| c.c)
        .collect()
}

/// Every level after push, pixels first: each cell's plane (value at its centre, gradient).
pub fn pyramid(
    width: u32,
    height: u32,
    samples: &[Option<[f32; 3]>],
    keys: &[Key],
) -> Vec<Vec<Cell>> {
    let mut levels: Vec<Vec<Cell>> = vec![(0..width * height)
        .map(|k| match samples[k as usize] {
            Some(c) => Cell::sample(k % width, k / width, c, keys[k as usize]),
            None => Cell::empty(),
        })
        .collect()];
    let top = level_count(width, height);
    for l in 1..=top {
        let (cw, chh) = level_size(width, height, l - 1);
        let (pw, ph) = level_size(width, height, l);
        let child = &levels[(l - 1) as usize];
        let mut next = Vec::with_capacity((pw * ph) as usize);
        for y in 0..ph {
            for x in 0..pw {
                let mut kids = Vec::with_capacity(4);
                for (dx, dy) in [(0, 0), (1, 0), (0, 1), (1, 1)] {
                    let (cx, cy) = (2 * x + dx, 2 * y + dy);
                    if cx < cw && cy < chh {
                        kids.push(child[(cy * cw + cx) as usize]);
                    }
                }
                next.push(Cell::merge(&kids));
            }
        }
        levels.push(next);
    }
    // The top cell has no parent: its coarse plane is flat zero.
    let top_cell = levels[top as usize][0];
    levels[top as usize][0] = complete(&top_cell, &Cell::empty(), LAMBDA_TOP, top, (0, 0));
    for l in (0..top).rev() {
        let (w, h) = level_size(width, height, l);
        let parent_size = level_size(width, height, l + 1);
        let (lower, upper) = levels.split_at_mut(l as usize + 1);
        let parent = &upper[0];
        let cells = &mut lower[l as usize];
        for y in 0..h {
            for x in 0..w {
                let k = (y * w + x) as usize;
                let cell = cells[k];
                // Pixels know their depth and material from the G-buffer; a cell with samples,
                // theirs.
                let target = if l == 0 {
                    Some(keys[k])
                } else {
                    (cell.w > 0.0).then_some(Key {
                        depth: cell.depth,
                        material: cell.material,
                    })
                };
                let mut coarse = coarse_plane(parent, parent_size, l, (x, y), target);
                // Pixels and level 1's empty cells, whose values the pixels are bounded by.
                if l <= 1 && cell.w <= 0.0 {
                    coarse.c = within_corners(parent, parent_size, (x, y), coarse.c);
                }
                cells[k] = complete(&cell, &coarse, LAMBDA, l, (x, y));
            }
        }
    }
    levels
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn merging_is_exact_for_a_plane() {
        let f = |x: f32, y: f32| [2.0 * x - 0.5 * y + 1.0, 0.0, x * 0.1];
        let pts = [(0u32, 0u32), (1, 0), (1, 1)];
        let cells: Vec<Cell> = pts
            .iter()
            .map(|&(x, y)| Cell::sample(x, y, f(x as f32 + 0.5, y as f32 + 0.5), Key::default()))
            .collect();
        let m = Cell::merge(&cells);
        // W clamps to 1; the plane through the three samples is still recovered exactly, both
        // alone (top cell) and leaning on an exact coarse gradient.
        assert_eq!(m.w, 1.0);
        let done = complete(&m, &Cell::empty(), LAMBDA_TOP, 1, (0, 0));
        let mut coarse = Cell::empty();
        coarse.t = [[2.0, 0.0, 0.1], [-0.5, 0.0, 0.0]];
        let leaning = complete(&m, &coarse, LAMBDA, 1, (0, 0));
        for d in [done, leaning] {
            assert!(
                (d.t[0][0] - 2.0).abs() < 1e-3 && (d.t[1][0] + 0.5).abs() < 1e-3,
                "{d:?}"
            );
            let centre = f(1.0, 1.0);
            assert!((d.c[0] - centre[0]).abs() < 1e-4 && (d.c[2] - centre[2]).abs() < 1e-4);
        }
    }

    #[test]
    fn levels_reach_one_cell() {
        assert_eq!(level_count(1, 1), 0);
        assert_eq!(level_count(640, 480), 10);
        assert_eq!(level_size(640, 480, 10), (1, 1));
        assert_eq!(level_size(5, 3, 1), (3, 2));
    }
}
