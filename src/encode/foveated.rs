//! Foveated encoding: before any codec sees a frame, the periphery is low-passed to what the
//! eye can resolve there, so its bytes go to the fovea.
//!
//! The eye resolves features no smaller than its minimum angle of resolution, linear in
//! eccentricity e (seed 003, §2b): w(e) = m·e + w0 degrees. A pixel subtends p degrees, so at
//! e the image carries no visible detail finer than w(e)/p pixels, and it may be averaged over
//! blocks of that width: mip level L(e) = log2(w(e)/p), 0 where w(e) ≤ p. Each pixel blends
//! the two mip levels around its L (box-filtered 2×2 pyramid, read bilinearly), so blur grows
//! smoothly and monotonically with eccentricity. Within `guard_deg` of the gaze (the fovea
//! plus a margin for gaze error and latency) pixels are copied unchanged, bit for bit.
//!
//! L is evaluated exactly on a grid every `CELL` pixels and interpolated between; the guard
//! is widened by a cell's diagonal on the grid so no interpolated level reaches into it.

use crate::viewing::Viewing;

/// Grid spacing of the exact level evaluation, pixels.
pub const CELL: u32 = 8;
/// Coarsest pyramid level used (blocks of 2^MAX_LEVEL pixels).
pub const MAX_LEVEL: usize = 5;

#[derive(Debug, Clone, Copy, PartialEq)]
pub struct LowPass {
    /// MAR slope m, degrees per degree of eccentricity.
    pub mar_slope: f64,
    /// MAR at the fovea w0, degrees.
    pub mar_w0_deg: f64,
    /// Untouched within this many degrees of the gaze.
    pub guard_deg: f64,
}

impl Default for LowPass {
    fn default() -> Self {
        // The renderer's own acuity model (settings: mar_slope, mar_w0_deg) and the 5° within
        // which foveal quality is judged.
        LowPass {
            mar_slope: 0.022,
            mar_w0_deg: 1.0 / 48.0,
            guard_deg: 5.0,
        }
    }
}

/// The pyramid level at eccentricity `e_deg` for pixels of `pixel_deg`: log2(w(e)/p), at
/// least 0 and at most `MAX_LEVEL`; 0 within the guard. Non-decreasing in `e_deg`.
pub fn level_at(e_deg: f64, pixel_deg: f64, p: &LowPass) -> f32 {
    if !(e_deg > p.guard_deg) || !(pixel_deg > 0.0) {
        return 0.0;
    }
    let w = p.mar_slope * e_deg + p.mar_w0_deg;
    ((w / pixel_deg).log2().max(0.0) as f32).min(MAX_LEVEL as f32)
}

/// Size of the level grid: a corner every `CELL` pixels, covering the frame.
pub fn grid_size(width: u32, height: u32) -> [u32; 2] {
    [width.div_ceil(CELL) + 1, height.div_ceil(CELL) + 1]
}

/// The exact levels at the grid's corners (row-major, [`grid_size`]), each pixel's level being
/// the bilinear blend of its cell's four. The guard is widened by 1.5 cell diagonals here, so
/// a pixel within the guard has all four corners at level 0. The GPU pass (`low_pass`) reads
/// this very grid, so both filters agree on every level.
pub fn level_grid(
    width: u32,
    height: u32,
    gaze: [f64; 2],
    viewing: &Viewing,
    p: &LowPass,
) -> Vec<f32> {
    let pixel_deg = viewing.pixel_angle_deg();
    let gaze_px = viewing.to_pixels(gaze);
    let [gw, gh] = grid_size(width, height);
    let cell_deg = f64::from(CELL) * std::f64::consts::SQRT_2 * pixel_deg * 1.5;
    let grid_params = LowPass {
        guard_deg: p.guard_deg + cell_deg,
        ..*p
    };
    (0..gh)
        .flat_map(|j| (0..gw).map(move |i| (i, j)))
        .map(|(i, j)| {
            let at = [f64::from(i * CELL), f64::from(j * CELL)];
            level_at(
                viewing.eccentricity_deg(gaze_px, at),
                pixel_deg,
                &grid_params,
            )
        })
        .collect()
}

/// The level of every pixel, `gaze` normalised.
pub fn level_map(
    width: u32,
    height: u32,
    gaze: [f64; 2],
    viewing: &Viewing,
    p: &LowPass,
) -> Vec<f32> {
    let grid = level_grid(width, height, gaze, viewing, p);
    let gw = grid_size(width, height)[0];
    // Row by row, cell by cell: the four corners are read once per cell row, not per pixel.
    let mut out = vec![0.0f32; (width * height) as usize];
    for (y, row) in (0..height).zip(out.chunks_exact_mut(width as usize)) {
        let (j, fy) = (y / CELL, (y % CELL) as f32 / CELL as f32);
        let (above, below) = (&grid[(j * gw) as usize..], &grid[((j + 1) * gw) as usize..]);
        for (i, cell) in row.chunks_mut(CELL as usize).enumerate() {
            let (g00, g10, g01, g11) = (above[i], above[i + 1], below[i], below[i + 1]);
            for (dx, v) in cell.iter_mut().enumerate() {
                let fx = dx as f32 / CELL as f32;
                let top = g00 + (g10 - g00) * fx;
                let bottom = g01 + (g11 - g01) * fx;
                *v = top + (bottom - top) * fy;
            }
        }
    }
    out
}

/// One pyramid level: RGB, `w`×`h`.
struct Level {
    rgb: Vec<[f32; 3]>,
    w: u32,
    h: u32,
}

impl Level {
    fn at(&self, x: u32, y: u32) -> [f32; 3] {
        self.rgb[(y * self.w + x) as usize]
    }
}

/// A 2×2 box pyramid above the frame: levels 1..=MAX_LEVEL (index k − 1), each half the one
/// below (rounded up; edge pixels repeat). Level 1 is averaged straight from the bytes: the
/// frame itself is never copied to floats.
fn pyramid(rgba: &[u8], width: u32, height: u32) -> Vec<Level> {
    let mut levels: Vec<Level> = Vec::with_capacity(MAX_LEVEL);
    let (w, h) = (width.div_ceil(2), height.div_ceil(2));
    let stride = (width * 4) as usize;
    let mut rgb = Vec::with_capacity((w * h) as usize);
    for y in 0..h {
        let (y0, y1) = ((2 * y) as usize, (2 * y + 1).min(height - 1) as usize);
        let (r0, r1) = (
            &rgba[y0 * stride..][..stride],
            &rgba[y1 * stride..][..stride],
        );
        for x in 0..w {
            let (x0, x1) = ((8 * x) as usize, ((2 * x + 1).min(width - 1) * 4) as usize);
            rgb.push(std::array::from_fn(|k| {
                let (a, b) = (f32::from(r0[x0 + k]), f32::from(r0[x1 + k]));
                let (c, d) = (f32::from(r1[x0 + k]), f32::from(r1[x1 + k]));
                0.25 * (a + b + c + d)
            }));
        }
    }
    levels.push(Level { rgb, w, h });
    while levels.len() < MAX_LEVEL {
        let Some(below) = levels.last() else { break };
        let (pw, ph) = (below.w, below.h);
        let (w, h) = (pw.div_ceil(2), ph.div_ceil(2));
        let mut rgb = Vec::with_capacity((w * h) as usize);
        for y in 0..h {
            let (y0, y1) = ((2 * y) as usize, (2 * y + 1).min(ph - 1) as usize);
            let r0 = &below.rgb[y0 * pw as usize..][..pw as usize];
            let r1 = &below.rgb[y1 * pw as usize..][..pw as usize];
            for x in 0..w {
                let (x0, x1) = ((2 * x) as usize, (2 * x + 1).min(pw - 1) as usize);
                let (a, b, c, d) = (r0[x0], r0[x1], r1[x0], r1[x1]);
                rgb.push(std::array::from_fn(|k| 0.25 * (a[k] + b[k] + c[k] + d[k])));
            }
        }
        levels.push(Level { rgb, w, h });
    }
    levels
}

/// Where frame coordinate `x` falls on level `k` (of `n` samples): the two samples read
/// bilinearly and the weight of the second. Sample centres: level texel i covers frame pixels
/// i·2^k … (i+1)·2^k − 1.
fn tap(x: u32, k: usize, n: u32) -> (u32, u32, f32) {
    let s = (1u32 << k) as f32;
    let f = ((x as f32 + 0.5) / s - 0.5).clamp(0.0, (n - 1) as f32);
    let i0 = f as u32;
    (i0, (i0 + 1).min(n - 1), f - i0 as f32)
}

/// A level's row (already interpolated vertically) read at a horizontal tap.
#[inline(always)]
fn sample(row: &[[f32; 3]], (x0, x1, tx): (u32, u32, f32)) -> [f32; 3] {
    let (a, b) = (row[x0 as usize], row[x1 as usize]);
    std::array::from_fn(|c| a[c] + (b[c] - a[c]) * tx)
}

/// Writes the blend of `a` and `b` at `t` into a pixel's RGB. `as u8` saturates (and sends
/// NaN to 0); + 0.5 rounds the non-negative blend without a libm call per channel.
#[inline(always)]
fn put(px: &mut [u8], a: [f32; 3], b: [f32; 3], t: f32) {
    for c in 0..3 {
        px[c] = (a[c] + (b[c] - a[c]) * t + 0.5) as u8;
    }
}

/// The frame low-passed by eccentricity around `gaze` (normalised). Pixels whose level is 0
/// are copied exactly.
///
/// Row by row: each level a row needs is first interpolated vertically into a row buffer, so a
/// pixel costs two horizontal reads per level, not a full bilinear lookup (this more than
/// halved the filter's time at 720p; docs/encoding.md, "What encoding costs the CPU").
pub fn low_pass(
    rgba: &[u8],
    width: u32,
    height: u32,
    gaze: [f64; 2],
    viewing: &Viewing,
    p: &LowPass,
) -> Vec<u8> {
    if rgba.len() != (width * height * 4) as usize {
        return rgba.to_vec();
    }
    let levels = level_map(width, height, gaze, viewing, p);
    if levels.iter().all(|l| *l <= 0.0) {
        return rgba.to_vec();
    }
    let pyr = pyramid(rgba, width, height);
    // Horizontal taps per level, the same for every row; level 0 reads the pixel itself
    // (weight 0 on a second tap at the same place, which leaves the value exact).
    let mut xtaps: Vec<Vec<(u32, u32, f32)>> = vec![(0..width).map(|x| (x, x, 0.0)).collect()];
    xtaps.extend(
        pyr.iter()
            .enumerate()
            .map(|(j, l)| (0..width).map(|x| tap(x, j + 1, l.w)).collect()),
    );
    // Row buffers: the frame's own row (level 0), then each level's row interpolated
    // vertically.
    let mut rows: Vec<Vec<[f32; 3]>> = vec![vec![[0.0; 3]; width as usize]];
    rows.extend(pyr.iter().map(|l| vec![[0.0; 3]; l.w as usize]));
    let mut out = rgba.to_vec();
    let stride = (width * 4) as usize;
    for y in 0..height {
        let row_levels = &levels[(y * width) as usize..((y + 1) * width) as usize];
        let top = row_levels.iter().fold(0.0f32, |m, l| m.max(*l));
        if top <= 0.0 {
            continue;
        }
        let src = &rgba[y as usize * stride..][..stride];
        for (v, p) in rows[0].iter_mut().zip(src.chunks_exact(4)) {
            *v = [0, 1, 2].map(|c| f32::from(p[c]));
        }
        // Levels 1..=ceil(top) are read in this row: interpolate them vertically once.
        let needed = (top.ceil() as usize).clamp(1, MAX_LEVEL);
        for (j, (level, row)) in pyr
            .iter()
            .zip(rows[1..].iter_mut())
            .enumerate()
            .take(needed)
        {
            let (y0, y1, ty) = tap(y, j + 1, level.h);
            for (x, v) in row.iter_mut().enumerate() {
                let (a, b) = (level.at(x as u32, y0), level.at(x as u32, y1));
                *v = std::array::from_fn(|c| a[c] + (b[c] - a[c]) * ty);
            }
        }
        let dst = &mut out[y as usize * stride..][..stride];
        // Runs of pixels on the same pair of levels, so each run reads two rows and their
        // taps without choosing them per pixel.
        let mut x = 0;
        while x < row_levels.len() {
            let l = row_levels[x];
            if l <= 0.0 {
                x += 1;
                continue;
            }
            let k = (l as usize).min(MAX_LEVEL);
            let end = row_levels[x..]
                .iter()
                .position(|&m| m <= 0.0 || (m as usize).min(MAX_LEVEL) != k)
                .map_or(row_levels.len(), |n| x + n);
            let (ra, ta) = (&rows[k], &xtaps[k][x..end]);
            let run = row_levels[x..end]
                .iter()
                .zip(dst[4 * x..4 * end].chunks_exact_mut(4));
            // The level above, but for the coarsest level, which blends with nothing.
            match (rows.get(k + 1), xtaps.get(k + 1)) {
                (Some(rb), Some(tb)) => {
                    for (((&l, px), &qa), &qb) in run.zip(ta).zip(&tb[x..end]) {
                        let t = l - k as f32;
                        let a = sample(ra, qa);
                        let b = if t > 0.0 { sample(rb, qb) } else { a };
                        put(px, a, b, t);
                    }
                }
                _ => {
                    for ((&l, px), &qa) in run.zip(ta) {
                        let a = sample(ra, qa);
                        put(px, a, a, l - k as f32);
                    }
                }
            }
            x = end;
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::viewing::Display;

    fn noise(w: u32, h: u32) -> Vec<u8> {
        crate::encode::noise_rgba((w * h) as usize, 12345)
    }

    #[test]
    fn the_fovea_is_bit_identical_and_blur_grows_with_eccentricity() {
        let (w, h) = (640, 360);
        let v = Viewing::new(Display::default(), w, h);
        let p = LowPass::default();
        let img = noise(w, h);
        let gaze = [0.3, 0.5];
        let out = low_pass(&img, w, h, gaze, &v, &p);
        let g = v.to_pixels(gaze);
        let (mut inside, mut changed_far) = (0, 0);
        for y in 0..h {
            for x in 0..w {
                let i = ((y * w + x) * 4) as usize;
                let e = v.eccentricity_deg(g, [f64::from(x), f64::from(y)]);
                if e <= p.guard_deg {
                    inside += 1;
                    assert_eq!(out[i..i + 4], img[i..i + 4], "({x}, {y}) at {e:.2}°");
                } else if e > 2.0 * p.guard_deg && out[i..i + 3] != img[i..i + 3] {
                    changed_far += 1;
                }
            }
        }
        assert!(inside > 1000, "{inside} pixels in the fovea");
        assert!(changed_far > 1000, "the periphery is filtered");
        // Blur grows with eccentricity: the level along the row through the gaze, outward.
        let levels = level_map(w, h, gaze, &v, &p);
        let row = (g[1] as u32 / CELL) * CELL;
        let from = (g[0] as u32 / CELL) * CELL;
        let outward: Vec<f32> = (from..w).map(|x| levels[(row * w + x) as usize]).collect();
        assert!(
            outward.windows(2).all(|p| p[1] >= p[0] - 1e-6),
            "{outward:?}"
        );
        assert!(outward.last().copied().unwrap_or(0.0) > 1.0);
        // And the image's pixel-to-pixel variation falls with it, band by band.
        let variation = |x0: u32, x1: u32| -> f64 {
            let y = g[1] as u32;
            (x0..x1)
                .map(|x| {
                    let i = ((y * w + x) * 4) as usize;
                    (f64::from(out[i]) - f64::from(out[i + 4])).abs()
                })
                .sum::<f64>()
                / f64::from(x1 - x0)
        };
        let bands: Vec<f64> = [(200, 300), (350, 450), (500, 600)]
            .iter()
            .map(|&(a, b)| variation(a, b))
            .collect();
        assert!(bands[0] > bands[1] && bands[1] > bands[2], "{bands:?}");
    }

    /// The filter read the direct way: every pixel's two levels each sampled bilinearly in
    /// 2-D from the pyramid.
    fn direct(rgba: &[u8], w: u32, h: u32, gaze: [f64; 2], v: &Viewing, p: &LowPass) -> Vec<u8> {
        let levels = level_map(w, h, gaze, v, p);
        let pyr = pyramid(rgba, w, h);
        let read = |k: usize, x: u32, y: u32| -> [f32; 3] {
            if k == 0 {
                let i = ((y * w + x) * 4) as usize;
                return std::array::from_fn(|c| f32::from(rgba[i + c]));
            }
            let l = &pyr[k - 1];
            let ((x0, x1, tx), (y0, y1, ty)) = (tap(x, k, l.w), tap(y, k, l.h));
            let (a, b, c, d) = (l.at(x0, y0), l.at(x1, y0), l.at(x0, y1), l.at(x1, y1));
            std::array::from_fn(|i| {
                let top = a[i] + (b[i] - a[i]) * tx;
                top + (c[i] + (d[i] - c[i]) * tx - top) * ty
            })
        };
        let mut out = rgba.to_vec();
        for y in 0..h {
            for x in 0..w {
                let i = (y * w + x) as usize;
                let l = levels[i];
                if l <= 0.0 {
                    continue;
                }
                let k = (l as usize).min(MAX_LEVEL);
                let t = l - k as f32;
                let a = read(k, x, y);
                let b = if t > 0.0 && k < MAX_LEVEL {
                    read(k + 1, x, y)
                } else {
                    a
                };
                for c in 0..3 {
                    out[i * 4 + c] = (a[c] + (b[c] - a[c]) * t).round().clamp(0.0, 255.0) as u8;
                }
            }
        }
        out
    }

    #[test]
    fn row_by_row_filtering_matches_direct_bilinear_reads() {
        // Odd sizes, so every pyramid level has a repeated edge; gaze near a corner, so every
        // level up to the coarsest is read.
        for (w, h, gaze) in [
            (301, 177, [0.1, 0.2]),
            (640, 360, [0.5, 0.5]),
            (97, 1, [0.0, 0.0]),
        ] {
            let v = Viewing::new(Display::default(), w, h);
            let p = LowPass {
                guard_deg: 1.0,
                ..LowPass::default()
            };
            let img = noise(w, h);
            let (fast, slow) = (
                low_pass(&img, w, h, gaze, &v, &p),
                direct(&img, w, h, gaze, &v, &p),
            );
            let worst = fast.iter().zip(&slow).map(|(a, b)| a.abs_diff(*b)).max();
            assert!(worst <= Some(1), "{w}x{h}: {worst:?}");
            assert_ne!(fast, img, "{w}x{h}: something was filtered");
        }
    }

    #[test]
    fn levels_are_monotone_and_bounded_at_the_extremes() {
        let p = LowPass::default();
        let mut last = 0.0;
        for k in 0..2000 {
            let e = f64::from(k) * 0.05;
            let l = level_at(e, 0.02, &p);
            assert!(l >= last && (0.0..=MAX_LEVEL as f32).contains(&l));
            last = l;
        }
        assert_eq!(level_at(f64::NAN, 0.02, &p), 0.0);
        assert_eq!(level_at(30.0, 0.0, &p), 0.0);
        assert_eq!(level_at(1e300, 0.02, &p), MAX_LEVEL as f32);
        // A 1x1 frame and a frame with the gaze off it do not panic.
        let v = Viewing::new(Display::default(), 1, 1);
        assert_eq!(
            low_pass(&[1, 2, 3, 255], 1, 1, [5.0, -3.0], &v, &p).len(),
            4
        );
    }
}
