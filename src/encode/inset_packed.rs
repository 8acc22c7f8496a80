//! Inset frames for a video stream: the base and the inset packed side by side into one
//! picture, so one H.264 encoder and one browser decoder carry both. The page crops the two
//! parts out of the decoded picture and composes them as it does two JPEGs.
//!
//! The inset starts at the first macroblock column (16 pixels) at least [`GAP`] right of the
//! base, so no macroblock holds both parts: the base stays still while the inset moves with the gaze, and a
//! block that mixed them could be predicted from neither. Each part's region is filled past its
//! edge by repeating its last row and column, which costs the encoder almost nothing and keeps
//! the 4:2:0 chroma of a part's edge pixels from mixing with whatever lay beyond it. Every size
//! here is fixed by the session (frame size, inset size, base scale), so the picture's size
//! never changes mid-stream and the stream needs no keyframe when the gaze moves.

use serde::{Deserialize, Serialize};

use super::foveated::LowPass;
use super::hold::{self, Hold};
use super::inset::{self, InsetPlan};
use crate::viewing::Viewing;

/// H.264 codes 16×16 macroblocks.
const MACROBLOCK: u32 = 16;
/// Columns of the base's own edge between it and the inset: a browser scaling the base up
/// with `drawImage`'s source rectangle filters texels just outside it (measured: a line of the
/// inset's colour along the frame's right edge without them), so those must be the base's.
const GAP: u32 = 2;

/// Where the two parts lie in a packed picture: the base at its top-left, the inset at
/// (`inset_x`, 0); the picture is `width`×`height` (both even, as 4:2:0 needs).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
pub struct PackedLayout {
    pub inset_x: u32,
    pub width: u32,
    pub height: u32,
}

/// How far the gaze may drift from a video inset's centre before the inset follows it,
/// degrees. A fixating eye drifts and makes microsaccades, mostly well under 1° (seed 003's
/// fixations; Martinez-Conde et al. 2004), so within a fixation the inset stays put and the
/// encoder sees the same picture; a saccade elsewhere moves it.
pub const HOLD_DEG: f64 = 1.0;

/// The narrowest inset, degrees, whose unfeathered core holds everything within `guard_deg`
/// of the gaze wherever [`follow`] puts it (up to [`HOLD_DEG`] off): 2·(guard + hold)/(1 − 2·
/// FEATHER). For the low-pass's 5° guard, 16°.
pub fn narrowest_deg(guard_deg: f64) -> f64 {
    inset::narrowest_deg(guard_deg + HOLD_DEG)
}

/// Where a video frame's inset goes, given the one the stream's previous picture held: that one
/// while the gaze stays within [`HOLD_DEG`] of its centre (and the frame is the same size),
/// else a fresh plan with its corner on the 16-pixel grid (so its blocks line up with the
/// previous picture's). The base's scale allows for both offsets (see `inset::base_scale`),
/// and is the same for every frame of the session.
pub fn follow(
    held: Option<&InsetPlan>,
    width: u32,
    height: u32,
    gaze: [f64; 2],
    viewing: &Viewing,
    inset_deg: f64,
    acuity: &LowPass,
) -> InsetPlan {
    let p = viewing.pixel_angle_deg();
    let grid_deg = f64::from(MACROBLOCK) / 2.0 * std::f64::consts::SQRT_2 * p;
    let scale = inset::base_scale(viewing, inset_deg, acuity, HOLD_DEG.max(grid_deg));
    let fresh = inset::plan(width, height, gaze, viewing, inset_deg, acuity);
    let fresh = InsetPlan { scale, ..fresh };
    if let Some(h) = held.filter(|h| h.width == fresh.width && h.height == fresh.height) {
        let centre = [
            f64::from(h.x) + f64::from(h.width) / 2.0,
            f64::from(h.y) + f64::from(h.height) / 2.0,
        ];
        if h.scale == scale && viewing.eccentricity_deg(viewing.to_pixels(gaze), centre) <= HOLD_DEG
        {
            return *h;
        }
    }
    let on_grid = |v: u32, side: u32, max: u32| {
        let snapped = (v + MACROBLOCK / 2) / MACROBLOCK * MACROBLOCK;
        snapped.min(max - side)
    };
    InsetPlan {
        x: on_grid(fresh.x, fresh.width, width),
        y: on_grid(fresh.y, fresh.height, height),
        ..fresh
    }
}

/// The packed picture's layout for an inset `plan` on a `width`×`height` frame.
pub fn layout(plan: &InsetPlan, width: u32, height: u32) -> PackedLayout {
    let (bw, bh) = plan.base_size(width, height);
    let inset_x = (bw + GAP).div_ceil(MACROBLOCK) * MACROBLOCK;
    let even = |v: u32| v.div_ceil(2) * 2;
    PackedLayout {
        inset_x,
        width: even(inset_x + plan.width),
        height: even(bh.max(plan.height)),
    }
}

/// Each macroblock's hold threshold (`encode::hold`) in the packed picture of `plan`: a block
/// by the frame pixels it shows (one of the padding by the part's edge it repeats), and a base
/// block that the inset's unfeathered core covers, `hold::ALWAYS`: the client never shows it.
pub fn hold_thresholds(
    plan: &InsetPlan,
    l: &PackedLayout,
    (width, height): (u32, u32),
    gaze: [f64; 2],
    viewing: &Viewing,
    hold: &Hold,
) -> Vec<u8> {
    let g = viewing.to_pixels(gaze);
    let (bw, bh) = plan.base_size(width, height);
    let (s, f) = (f64::from(plan.scale), inset::FEATHER);
    let (px, py, pw, ph) = (plan.x, plan.y, plan.width, plan.height);
    let core = [
        f64::from(px) + f * f64::from(pw),
        f64::from(py) + f * f64::from(ph),
        f64::from(px + pw) - f * f64::from(pw),
        f64::from(py + ph) - f * f64::from(ph),
    ];
    let (cols, rows) = hold::blocks(l.width as usize, l.height as usize);
    let mut out = Vec::with_capacity(cols * rows);
    for by in 0..rows as u32 {
        for bx in 0..cols as u32 {
            let m = hold::MB as u32;
            let (x0, y0, x1, y1) = (bx * m, by * m, (bx + 1) * m, (by + 1) * m);
            // The part's own pixels the block shows or repeats, in its own coordinates.
            let clamp = |a0: u32, a1: u32, n: u32| (f64::from(a0.min(n - 1)), f64::from(a1.min(n)));
            let rect = if x0 < l.inset_x {
                let ((cx0, cx1), (cy0, cy1)) = (clamp(x0, x1, bw), clamp(y0, y1, bh));
                let (fw, fh) = (f64::from(width), f64::from(height));
                let r = [cx0 * s, cy0 * s, (cx1 * s).min(fw), (cy1 * s).min(fh)];
                if r[0] >= core[0] && r[1] >= core[1] && r[2] <= core[2] && r[3] <= core[3] {
                    out.push(hold::ALWAYS);
                    continue;
                }
                r
            } else {
                let (ix, iy) = (clamp(x0 - l.inset_x, x1 - l.inset_x, pw), clamp(y0, y1, ph));
                let (ox, oy) = (f64::from(px), f64::from(py));
                [ox + ix.0, oy + iy.0, ox + ix.1, oy + iy.1]
            };
            out.push(hold::rect_threshold(rect, g, viewing, hold));
        }
    }
    out
}

/// The picture (RGBA8, `layout`'s size) holding `base` (the plan's base size) and `inset`
/// (the plan's inset size), each region edge-extended.
pub fn pack(
    base: &[u8],
    inset: &[u8],
    plan: &InsetPlan,
    width: u32,
    height: u32,
) -> (Vec<u8>, PackedLayout) {
    let l = layout(plan, width, height);
    let (bw, bh) = plan.base_size(width, height);
    let mut out = Vec::with_capacity((l.width * l.height * 4) as usize);
    for y in 0..l.height {
        let by = y.min(bh - 1);
        let iy = y.min(plan.height - 1);
        for x in 0..l.width {
            let (src, w, sx, sy) = if x < l.inset_x {
                (base, bw, x.min(bw - 1), by)
            } else {
                (inset, plan.width, (x - l.inset_x).min(plan.width - 1), iy)
            };
            let i = ((sy * w + sx) * 4) as usize;
            out.extend_from_slice(&src[i..i + 4]);
        }
    }
    (out, l)
}

/// The base and the inset cropped back out of a decoded packed picture (RGBA8).
pub fn unpack(
    picture: &[u8],
    l: &PackedLayout,
    plan: &InsetPlan,
    width: u32,
    height: u32,
) -> (Vec<u8>, Vec<u8>) {
    let (bw, bh) = plan.base_size(width, height);
    let crop = |x0: u32, w: u32, h: u32| -> Vec<u8> {
        let mut part = Vec::with_capacity((w * h * 4) as usize);
        for y in 0..h {
            let row = ((y * l.width + x0) * 4) as usize;
            part.extend_from_slice(&picture[row..row + (w * 4) as usize]);
        }
        part
    };
    (crop(0, bw, bh), crop(l.inset_x, plan.width, plan.height))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::encode::inset::{plan, split};
    use crate::viewing::Display;

    fn noise(w: u32, h: u32) -> Vec<u8> {
        crate::encode::noise_rgba((w * h) as usize, 0x9e37_79b9)
    }

    #[test]
    fn the_parts_come_back_out_unchanged() {
        for (w, h, deg) in [(1280, 720, 20.0), (640, 480, 12.0), (322, 242, 30.0)] {
            let v = Viewing::new(Display::default(), w, h);
            let p = plan(w, h, [0.3, 0.6], &v, deg, &LowPass::default());
            let rgba = noise(w, h);
            let (base, inset) = split(&rgba, w, h, &p);
            let (picture, l) = pack(&base, &inset, &p, w, h);
            assert_eq!(picture.len(), (l.width * l.height * 4) as usize);
            let (b, i) = unpack(&picture, &l, &p, w, h);
            assert!(b == base && i == inset, "{w}x{h}: parts differ");
        }
    }

    #[test]
    fn the_layout_is_even_aligned_and_fixed_by_the_session() {
        let (w, h) = (1280, 720);
        let v = Viewing::new(Display::default(), w, h);
        let first = plan(w, h, [0.5, 0.5], &v, 20.0, &LowPass::default());
        let l = layout(&first, w, h);
        assert_eq!(l.inset_x % 16, 0);
        assert!(l.inset_x >= first.base_size(w, h).0 + GAP);
        assert_eq!((l.width % 2, l.height % 2), (0, 0));
        // Far fewer pixels than the frame: what makes the stream cheaper.
        assert!(l.width * l.height * 2 < w * h, "{l:?}");
        // Wherever the gaze goes, the picture keeps its size (no keyframe when the eye moves).
        for gaze in [[0.0, 0.0], [1.0, 1.0], [0.9, 0.1]] {
            let p = plan(w, h, gaze, &v, 20.0, &LowPass::default());
            assert_eq!(layout(&p, w, h), l);
        }
    }

    #[test]
    fn beyond_its_edge_each_part_repeats_its_last_pixels() {
        let p = InsetPlan {
            x: 10,
            y: 10,
            width: 6,
            height: 4,
            scale: 3,
        };
        let (w, h) = (45, 9); // base 15×3: the gap pushes the inset to the next macroblock
        let base: Vec<u8> = (0..15 * 3).flat_map(|i| [i as u8, 1, 2, 255]).collect();
        let inset: Vec<u8> = (0..6 * 4)
            .flat_map(|i| [100 + i as u8, 3, 4, 255])
            .collect();
        let (picture, l) = pack(&base, &inset, &p, w, h);
        assert_eq!(
            l,
            PackedLayout {
                inset_x: 32,
                width: 38,
                height: 4
            }
        );
        let at = |x: u32, y: u32| picture[((y * l.width + x) * 4) as usize];
        // Right of the base: its last column; below it: its last row.
        assert_eq!(at(31, 0), 14);
        assert_eq!(at(3, 3), 33);
        assert_eq!(at(31, 3), 44);
        // The inset at its own place.
        assert_eq!(at(32, 0), 100);
        assert_eq!(at(37, 3), 123);
    }

    #[test]
    fn a_video_inset_holds_through_drift_and_follows_a_saccade() {
        let (w, h) = (1280, 720);
        let v = Viewing::new(Display::default(), w, h);
        let a = LowPass::default();
        let first = follow(None, w, h, [0.5, 0.5], &v, 20.0, &a);
        assert_eq!((first.x % 16, first.y % 16), (0, 0), "{first:?}");
        // A fixation's drift (0.5°, ~13 px) keeps the inset where it was.
        let px = v.pixel_angle_deg();
        let drift = [0.5 + 0.5 / px / f64::from(w), 0.5];
        assert_eq!(follow(Some(&first), w, h, drift, &v, 20.0, &a), first);
        // A 5° saccade moves it, onto the grid, at the same scale.
        let far = [0.5 + 5.0 / px / f64::from(w), 0.5];
        let moved = follow(Some(&first), w, h, far, &v, 20.0, &a);
        assert!(moved.x > first.x && moved.x.is_multiple_of(16), "{moved:?}");
        assert_eq!(moved.scale, first.scale);
        // However it is placed, the fovea (5°) lies in the inset's unfeathered core.
        for gaze in [[0.5, 0.5], [0.41, 0.47], [0.58, 0.53]] {
            for held in [None, Some(&first)] {
                let p = follow(held, w, h, gaze, &v, 20.0, &a);
                let band = crate::encode::inset::FEATHER * f64::from(p.width);
                let [gx, gy] = v.to_pixels(gaze);
                let r = 5.0 / px;
                assert!(
                    gx - r >= f64::from(p.x) + band && gx + r <= f64::from(p.x + p.width) - band
                );
                assert!(
                    gy - r >= f64::from(p.y) + band && gy + r <= f64::from(p.y + p.height) - band
                );
            }
        }
        // The narrowest inset for the 5° guard: 16°, its core exactly 5° + the hold wide.
        let d = narrowest_deg(LowPass::default().guard_deg);
        assert!((d - 16.0).abs() < 1e-12, "{d}");
        assert!(((0.5 - crate::encode::inset::FEATHER) * d - 6.0).abs() < 1e-12);
        // A still inset, centred on the gaze every frame, needs no room for the hold: 13.3°,
        // its core exactly the 5° guard wide.
        let still = crate::encode::inset::narrowest_deg(LowPass::default().guard_deg);
        assert!(((0.5 - crate::encode::inset::FEATHER) * still - 5.0).abs() < 1e-12);
        assert!(still < d);
        // The base's scale allows for the offsets: never coarser than a centred inset's.
        assert!(first.scale <= plan(w, h, [0.5, 0.5], &v, 20.0, &a).scale);
    }

    #[test]
    fn held_blocks_follow_what_the_client_shows_of_each_part() {
        let (w, h) = (1280, 720);
        let v = Viewing::new(Display::default(), w, h);
        let gaze = [0.3, 0.6];
        let plan = follow(None, w, h, gaze, &v, 16.0, &LowPass::default());
        let l = layout(&plan, w, h);
        let t = hold_thresholds(&plan, &l, (w, h), gaze, &v, &Hold::default());
        let (cols, rows) = hold::blocks(l.width as usize, l.height as usize);
        assert_eq!(t.len(), cols * rows);
        let at = |x: u32, y: u32| t[(y / 16) as usize * cols + (x / 16) as usize];
        // The inset's block at the gaze takes every change.
        let [gx, gy] = v.to_pixels(gaze);
        let (ix, iy) = (l.inset_x + gx as u32 - plan.x, gy as u32 - plan.y);
        assert_eq!(at(ix, iy), 0);
        // The base's block under the gaze lies under the inset's core: never shown.
        let s = f64::from(plan.scale);
        assert_eq!(at((gx / s) as u32, (gy / s) as u32), hold::ALWAYS);
        // The base's far corner holds, but not blindly; its padding as the edge it repeats.
        let (bw, bh) = plan.base_size(w, h);
        let corner = at(bw - 1, 0);
        assert!(corner > 0 && corner < hold::ALWAYS, "{corner}");
        if l.inset_x >= bw + 16 {
            assert_eq!(at(l.inset_x - 1, 0), corner);
        }
        assert!(bh < l.height || at(0, bh - 1) > 0);
        // No inset block is blind: the client shows all of the inset.
        for y in (0..l.height).step_by(16) {
            for x in (l.inset_x..l.width).step_by(16) {
                assert!(at(x, y) < hold::ALWAYS, "({x}, {y})");
            }
        }
    }
}
