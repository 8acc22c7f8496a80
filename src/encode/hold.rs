//! Foveated encoding in time: a peripheral macroblock whose new content lies within what the
//! eye can tell at its eccentricity of what the client already shows there is given to the
//! encoder as shown (the stream's own decoded previous frame), so the encoder finds nothing
//! to code and skips it.
//!
//! Why: below QP 18 openh264 never settles on a still picture. Fed the same frame again and
//! again it re-codes it in every P-frame, for ever: 460 bytes a frame on `bunny-marble` and
//! 2438 on `gallery` at 1280×720 (1.2 Mbit/s at 60 fps for a picture that does not change;
//! 13–17 bytes from QP 18 up, where the fovea's refinement stops too early). A still camera's
//! frames also differ all over by a fraction of a code value (the foveated render's samples
//! follow the gaze). Both cost bits in the periphery as much as in the fovea, and the spatial
//! low-pass removes neither: it moves with the gaze. Repeating the decoded block makes the
//! residual exactly zero, which re-feeding the source block would not.
//!
//! The threshold grows with eccentricity as the minimum angle of resolution does (seed 003,
//! §2b, the model of `foveated`): w(e) = m·e + w0, t(e) = `step`·w(e)/w(guard) code values
//! for a block whose nearest pixel lies at e outside the guard; within it every block is
//! coded. A block is held while its mean absolute difference from what is shown is at most
//! t/2 in each of Y, U and V and no sample differs by more than [`PEAK`]·t, so what the client
//! shows of it never strays further from the frame. Blocks near the limit are refined by the
//! encoder until they come within it, then held; a keyframe codes every block. The cost is a
//! decode of each frame, about 3 ms at 720p here, on a thread of its own (`encode::shown`).

use super::foveated::LowPass;
use super::yuv::I420;
use crate::viewing::Viewing;
use openh264::formats::YUVSource;

/// Macroblock side in luma pixels (H.264's).
pub const MB: usize = 16;
/// A block's threshold where nothing it holds is shown: held whatever changes.
pub const ALWAYS: u8 = u8::MAX;
/// A block is held while its mean absolute difference is at most half its threshold and no
/// sample differs by more than this many thresholds: the mean says whether its level moved,
/// the peak catches a thin edge that moved within it. Chosen on `bunny-marble` from 20 s on
/// the 500 Hz recording (docs/encoding-h264-foveated.md): a peak of one threshold alone
/// held few blocks at coarse quantisers, where coding error alone exceeds it.
pub const PEAK: u32 = 3;
/// The largest threshold, code values: beyond it a change is no longer subtle anywhere.
pub const MAX_STEP: u8 = 16;

#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Hold {
    /// Threshold at the guard's edge, code values.
    pub step: f64,
    /// The acuity model and the guard (`foveated::LowPass`).
    pub acuity: LowPass,
}

impl Default for Hold {
    fn default() -> Self {
        Hold {
            step: 2.0,
            acuity: LowPass::default(),
        }
    }
}

/// The threshold of a block whose nearest pixel lies `e_deg` from the gaze: 0 within the
/// guard, else `step`·w(e)/w(guard) rounded, at most `MAX_STEP`. Non-decreasing in `e_deg`.
pub fn threshold_at(e_deg: f64, hold: &Hold) -> u8 {
    let a = &hold.acuity;
    // NaN in either holds nothing.
    let inside = e_deg.is_nan() || e_deg <= a.guard_deg;
    if inside || hold.step.is_nan() || hold.step <= 0.0 {
        return 0;
    }
    let w = |e: f64| a.mar_slope * e + a.mar_w0_deg;
    let t = hold.step * w(e_deg) / w(a.guard_deg);
    t.round().min(f64::from(MAX_STEP)) as u8
}

/// The threshold of every macroblock of a `width`×`height` picture (row-major, blocks of
/// `MB`, the last row and column partial where the size is not a multiple), `gaze`
/// normalised.
pub fn thresholds(
    width: u32,
    height: u32,
    gaze: [f64; 2],
    viewing: &Viewing,
    hold: &Hold,
) -> Vec<u8> {
    let g = viewing.to_pixels(gaze);
    let (cols, rows) = blocks(width as usize, height as usize);
    let mut out = Vec::with_capacity(cols * rows);
    for by in 0..rows {
        for bx in 0..cols {
            let (x0, y0) = ((bx * MB) as f64, (by * MB) as f64);
            let x1 = ((bx + 1) * MB).min(width as usize) as f64;
            let y1 = ((by + 1) * MB).min(height as usize) as f64;
            out.push(rect_threshold([x0, y0, x1, y1], g, viewing, hold));
        }
    }
    out
}

/// The threshold of a block showing the frame's pixels in `[x0, y0, x1, y1]` (frame pixels,
/// `gaze_px` too): that of its point nearest the gaze, as no pixel of it is nearer.
pub fn rect_threshold(rect: [f64; 4], gaze_px: [f64; 2], viewing: &Viewing, hold: &Hold) -> u8 {
    let [x0, y0, x1, y1] = rect;
    let near = [gaze_px[0].clamp(x0, x1), gaze_px[1].clamp(y0, y1)];
    threshold_at(viewing.eccentricity_deg(gaze_px, near), hold)
}

/// Macroblock columns and rows of a picture.
pub fn blocks(width: usize, height: usize) -> (usize, usize) {
    (width.div_ceil(MB), height.div_ceil(MB))
}

/// Puts back into `picture` (the frame about to be encoded) the previous frame's decoded
/// content `shown` in each block whose threshold is not 0 and whose Y, U and V lie within it
/// of `shown` (mean and [`PEAK`], see the module): the encoder then finds nothing to code
/// there and skips the block; `ALWAYS` holds a block whatever it holds. Returns how many
/// blocks were held. Pictures of two sizes or a map of the wrong length hold nothing.
pub fn merge(picture: &mut I420, shown: &I420, thresholds: &[u8]) -> usize {
    let (w, h) = picture.dimensions();
    let (cols, rows) = blocks(w, h);
    if shown.dimensions() != (w, h) || thresholds.len() != cols * rows {
        return 0;
    }
    let (sy, su, sv) = (shown.y(), shown.u(), shown.v());
    let (py, pu, pv) = picture.planes_mut();
    let (cw, ch) = (w / 2, h / 2);
    // Per block of a row of blocks: summed and largest |difference| in Y, U, V, then whether
    // it is held. Whole rows at a time, so the compare runs over long contiguous samples.
    let mut tallies = vec![[Tally::default(); 3]; cols];
    let mut hold = vec![false; cols];
    // One row's |differences|, reused by every row and plane.
    let mut diff = vec![0u8; w];
    let mut held = 0;
    for by in 0..rows {
        let ts = &thresholds[by * cols..(by + 1) * cols];
        let (luma, chroma) = (band(by, MB, h), band(by, MB / 2, ch));
        tallies.fill([Tally::default(); 3]);
        if ts.iter().any(|&t| t != 0 && t != ALWAYS) {
            tally::<MB>(py, sy, w, luma.clone(), &mut diff, &mut tallies, 0);
            tally::<{ MB / 2 }>(pu, su, cw, chroma.clone(), &mut diff, &mut tallies, 1);
            tally::<{ MB / 2 }>(pv, sv, cw, chroma.clone(), &mut diff, &mut tallies, 2);
        }
        for (bx, (t, counts)) in ts.iter().zip(&tallies).enumerate() {
            let luma_n = side_in(bx, MB, w) * luma.len();
            let chroma_n = side_in(bx, MB / 2, cw) * chroma.len();
            let n = [luma_n, chroma_n, chroma_n];
            hold[bx] = match *t {
                0 => false,
                ALWAYS => true,
                t => counts.iter().zip(n).all(|(c, n)| c.within(t, n)),
            };
        }
        held += hold.iter().filter(|&&b| b).count();
        copy_held::<MB>(sy, py, w, luma, &hold);
        copy_held::<{ MB / 2 }>(su, pu, cw, chroma.clone(), &hold);
        copy_held::<{ MB / 2 }>(sv, pv, cw, chroma, &hold);
    }
    held
}

/// A block's summed and largest absolute difference in one plane.
#[derive(Debug, Clone, Copy, Default)]
struct Tally {
    sum: u32,
    peak: u8,
}

impl Tally {
    /// Within threshold `t` over `n` samples: a mean absolute difference of at most t/2 and
    /// no sample more than [`PEAK`]·t off.
    fn within(&self, t: u8, n: usize) -> bool {
        2 * u64::from(self.sum) <= u64::from(t) * n as u64
            && u32::from(self.peak) <= PEAK * u32::from(t)
    }

    fn add(&mut self, sum: u32, peak: u8) {
        self.sum += sum;
        self.peak = self.peak.max(peak);
    }
}

/// The rows of a plane `plane_h` high that blocks of side `side` in block row `by` cover.
fn band(by: usize, side: usize, plane_h: usize) -> std::ops::Range<usize> {
    (by * side).min(plane_h)..((by + 1) * side).min(plane_h)
}

/// How many of block `bx`'s columns lie in a plane `plane_w` wide.
fn side_in(bx: usize, side: usize, plane_w: usize) -> usize {
    side.min(plane_w.saturating_sub(bx * side))
}

/// Adds the differences of each block (side `S` in this plane: a constant, which measured
/// faster) over `rows` of a plane `stride` samples wide into `out[bx][plane]`; `scratch` holds
/// a row's differences (at least `stride` long).
fn tally<const S: usize>(
    a: &[u8],
    b: &[u8],
    stride: usize,
    rows: std::ops::Range<usize>,
    scratch: &mut [u8],
    out: &mut [[Tally; 3]],
    plane: usize,
) {
    let diff = &mut scratch[..stride];
    for r in rows {
        let span = r * stride..(r + 1) * stride;
        // The row's differences first, in one pass the compiler vectorises; then per block.
        for ((d, p), q) in diff.iter_mut().zip(&a[span.clone()]).zip(&b[span]) {
            *d = p.abs_diff(*q);
        }
        for (o, chunk) in out.iter_mut().zip(diff.chunks(S)) {
            let sum: u32 = chunk.iter().map(|&v| u32::from(v)).sum();
            let peak = chunk.iter().copied().fold(0, u8::max);
            o[plane].add(sum, peak);
        }
    }
}

/// Copies the held blocks' samples of `rows` from `from` into `to` (planes `stride` wide,
/// blocks of side `S`), a run of neighbouring held blocks at a time.
fn copy_held<const S: usize>(
    from: &[u8],
    to: &mut [u8],
    stride: usize,
    rows: std::ops::Range<usize>,
    hold: &[bool],
) {
    let mut bx = 0;
    while bx < hold.len() {
        if !hold[bx] {
            bx += 1;
            continue;
        }
        let start = bx;
        while bx < hold.len() && hold[bx] {
            bx += 1;
        }
        let (x0, x1) = ((start * S).min(stride), (bx * S).min(stride));
        for r in rows.clone() {
            let span = r * stride + x0..r * stride + x1;
            to[span.clone()].copy_from_slice(&from[span]);
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::viewing::Display;

    fn picture(w: usize, h: usize, seed: u32) -> I420 {
        let mut p = I420::new(w, h);
        let rgba = crate::encode::noise_rgba(w * h, seed);
        p.fill(&rgba);
        p
    }

    #[test]
    fn thresholds_are_zero_in_the_guard_and_grow_to_their_cap() {
        let hold = Hold::default();
        let g = hold.acuity.guard_deg;
        assert_eq!(threshold_at(0.0, &hold), 0);
        assert_eq!(threshold_at(g, &hold), 0);
        assert_eq!(threshold_at(f64::NAN, &hold), 0);
        assert_eq!(threshold_at(g + 1e-9, &hold), 2, "step at the guard's edge");
        let mut last = 0;
        for k in 0..2000 {
            let t = threshold_at(k as f64 * 0.05, &hold);
            assert!(t >= last, "{t} after {last} at {}°", k as f64 * 0.05);
            last = t;
        }
        assert_eq!(threshold_at(1e9, &hold), MAX_STEP);
        assert_eq!(threshold_at(30.0, &Hold { step: 0.0, ..hold }), 0);
        assert_eq!(
            threshold_at(
                30.0,
                &Hold {
                    step: f64::NAN,
                    ..hold
                }
            ),
            0
        );
    }

    #[test]
    fn blocks_around_the_gaze_take_every_change_and_far_ones_hold_more() {
        let (w, h) = (1280u32, 720u32);
        let v = Viewing::new(Display::default(), w, h);
        let hold = Hold::default();
        let t = thresholds(w, h, [0.25, 0.5], &v, &hold);
        let (cols, rows) = blocks(w as usize, h as usize);
        assert_eq!(t.len(), cols * rows);
        // The gaze's own block, and along its row outwards never less.
        let (gx, gy) = (320 / MB, 360 / MB);
        assert_eq!(t[gy * cols + gx], 0);
        let row = &t[gy * cols..(gy + 1) * cols];
        assert!(row[gx..].windows(2).all(|p| p[1] >= p[0]), "{row:?}");
        assert!(row[..=gx].windows(2).all(|p| p[0] >= p[1]), "{row:?}");
        assert!(
            row[cols - 1] > 2,
            "the far edge holds more than the guard's edge: {row:?}"
        );
        // Every block with a pixel within the guard takes every change.
        let gp = v.to_pixels([0.25, 0.5]);
        for by in 0..rows {
            for bx in 0..cols {
                let c = [(bx * MB) as f64 + 8.0, (by * MB) as f64 + 8.0];
                if v.eccentricity_deg(gp, c) <= hold.acuity.guard_deg {
                    assert_eq!(t[by * cols + bx], 0, "block ({bx}, {by})");
                }
            }
        }
    }

    /// `picture` with the given samples moved by `by` (up, or down where that would clip).
    fn moved(mut picture: I420, plane: usize, at: &[usize], by: u8) -> I420 {
        let (y, u, v) = picture.planes_mut();
        let p = match plane {
            0 => y,
            1 => u,
            _ => v,
        };
        for &i in at {
            p[i] = if p[i] > 127 { p[i] - by } else { p[i] + by };
        }
        picture
    }

    #[test]
    fn a_block_repeats_what_was_shown_while_within_its_threshold() {
        // 40×24: a partial last column and row of blocks (3 × 2).
        let (w, h) = (40, 24);
        assert_eq!(blocks(w, h), (3, 2));
        let shown = picture(w, h, 7);
        let whole_block = |bx: usize, by: usize| -> Vec<usize> {
            let (x0, y0) = (bx * MB, by * MB);
            (y0..(y0 + MB).min(h))
                .flat_map(|y| (x0..(x0 + MB).min(w)).map(move |x| y * w + x))
                .collect()
        };
        // Block 0 (threshold 0) moved by 1 everywhere; block 1 (threshold 4) by 2 everywhere,
        // a mean of half its threshold; block 2 (partial, threshold 4) by 12 at one sample,
        // three thresholds; block 3 by 3 everywhere, over half; block 4 by 13 at one sample,
        // over three; block 5 (threshold ALWAYS) by 100 everywhere.
        let mut p = moved(picture(w, h, 7), 0, &whole_block(0, 0), 1);
        p = moved(p, 0, &whole_block(1, 0), 2);
        p = moved(p, 0, &[35], 12);
        p = moved(p, 0, &whole_block(0, 1), 3);
        p = moved(p, 0, &[20 * w + 20], 13);
        p = moved(p, 0, &whole_block(2, 1), 100);
        let fresh = p.clone();
        let t = [0, 4, 4, 4, 4, ALWAYS];
        let mut out = p;
        assert_eq!(merge(&mut out, &shown, &t), 3);
        let (oy, sy, fy) = (out.y(), shown.y(), fresh.y());
        let same = |blk: Vec<usize>, of: &[u8]| blk.iter().all(|&i| oy[i] == of[i]);
        assert!(same(whole_block(0, 0), fy), "threshold 0 holds nothing");
        assert!(same(whole_block(1, 0), sy), "a mean of t/2 is held");
        assert!(same(whole_block(2, 0), sy), "a peak of 3t is held");
        assert!(same(whole_block(0, 1), fy), "a mean over t/2 is taken");
        assert!(same(whole_block(1, 1), fy), "a peak over 3t is taken");
        assert!(same(whole_block(2, 1), sy), "ALWAYS holds anything");
    }

    #[test]
    fn a_change_in_one_plane_takes_the_whole_block() {
        let (w, h) = (32, 16);
        let shown = picture(w, h, 3);
        // Y moved by 1 in both blocks, V by 9 at one sample of the second (chroma 16 × 8).
        let all: Vec<usize> = (0..w * h).collect();
        let p = moved(picture(w, h, 3), 0, &all, 1);
        let p = moved(p, 2, &[8 + 3 * 16], 9);
        let mut out = p.clone();
        assert_eq!(merge(&mut out, &shown, &[2, 2]), 1);
        let (oy, ou, ov) = (out.y(), out.u(), out.v());
        let (sy, su, sv) = (shown.y(), shown.u(), shown.v());
        let (py, pv) = (p.y(), p.v());
        assert!(
            (0..16).all(|x| oy[x] == sy[x] && ou[x / 2] == su[x / 2]),
            "block 0 held"
        );
        assert!((16..32).all(|x| oy[x] == py[x]), "block 1 taken, Y with V");
        assert_eq!(ov[8 + 3 * 16], pv[8 + 3 * 16]);
        assert_ne!(ov[8 + 3 * 16], sv[8 + 3 * 16]);
    }

    /// The rule of `merge` one block at a time, sample by sample: its twin.
    fn merge_by_block(picture: &mut I420, shown: &I420, thresholds: &[u8]) -> usize {
        let (w, h) = picture.dimensions();
        let (cols, rows) = blocks(w, h);
        assert_eq!(
            thresholds.len(),
            cols * rows,
            "the twin takes whole maps only"
        );
        let planes = |q: &I420| [q.y().to_vec(), q.u().to_vec(), q.v().to_vec()];
        let (from, mut to) = (planes(shown), planes(picture));
        let mut held = 0;
        for (i, &t) in thresholds.iter().enumerate() {
            let (bx, by) = (i % cols, i / cols);
            let cells = |k: usize| {
                let (side, pw, ph) = match k {
                    0 => (MB, w, h),
                    _ => (MB / 2, w / 2, h / 2),
                };
                let (x0, y0) = (bx * side, by * side);
                let ys = y0..(y0 + side).min(ph);
                ys.flat_map(move |y| (x0..(x0 + side).min(pw)).map(move |x| y * pw + x))
            };
            let within = |k: usize| {
                let d: Vec<u8> = cells(k).map(|j| to[k][j].abs_diff(from[k][j])).collect();
                let sum: u64 = d.iter().map(|&v| u64::from(v)).sum();
                let peak = d.iter().copied().max().unwrap_or(0);
                2 * sum <= u64::from(t) * d.len() as u64 && u32::from(peak) <= PEAK * u32::from(t)
            };
            if t == ALWAYS || (t != 0 && (0..3).all(within)) {
                for k in 0..3 {
                    for j in cells(k).collect::<Vec<_>>() {
                        to[k][j] = from[k][j];
                    }
                }
                held += 1;
            }
        }
        let (y, u, v) = picture.planes_mut();
        y.copy_from_slice(&to[0]);
        u.copy_from_slice(&to[1]);
        v.copy_from_slice(&to[2]);
        held
    }

    #[test]
    fn the_row_wise_merge_is_the_block_by_block_rule() {
        let mut seed = 11u32;
        let mut next = move || {
            seed = seed.wrapping_mul(1_664_525).wrapping_add(1_013_904_223);
            seed >> 8
        };
        for (w, h) in [(2, 2), (18, 6), (40, 24), (66, 34), (96, 50), (128, 64)] {
            let shown = picture(w, h, next());
            // Every sample moved by 0–5 (a sixth of blocks by up to 40 at one sample), so
            // thresholds of 1–8 hold some blocks and take others.
            let mut fresh = shown.clone();
            let (y, u, v) = fresh.planes_mut();
            for plane in [y, u, v] {
                for s in plane.iter_mut() {
                    *s = s.saturating_add((next() % 6) as u8);
                }
                let n = plane.len();
                plane[next() as usize % n] = 255;
            }
            let (cols, rows) = blocks(w, h);
            let choice = [0, 1, 2, 3, 4, 8, ALWAYS];
            let t: Vec<u8> = (0..cols * rows)
                .map(|_| choice[next() as usize % choice.len()])
                .collect();
            let (mut a, mut b) = (fresh.clone(), fresh);
            let held = merge(&mut a, &shown, &t);
            assert_eq!(held, merge_by_block(&mut b, &shown, &t), "{w}×{h}");
            assert!(held > 0 || cols * rows < 4, "{w}×{h}: nothing held");
            assert_eq!((a.y(), a.u(), a.v()), (b.y(), b.u(), b.v()), "{w}×{h}");
        }
    }

    #[test]
    fn pictures_of_two_sizes_or_a_wrong_map_hold_nothing() {
        let shown = picture(32, 32, 1);
        let mut p = picture(32, 16, 2);
        let planes = |q: &I420| [q.y(), q.u(), q.v()].concat();
        let before = planes(&p);
        assert_eq!(merge(&mut p, &shown, &[ALWAYS, ALWAYS]), 0);
        assert_eq!(planes(&p), before);
        let shown = picture(32, 16, 1);
        assert_eq!(
            merge(&mut p, &shown, &[ALWAYS]),
            0,
            "one threshold for two blocks"
        );
        assert_eq!(planes(&p), before);
    }
}
