//! Inset encoding (the split Valve's Steam Link streams): a downscaled whole frame plus a
//! full-resolution square around the gaze, encoded as two images. The client scales the base
//! up and draws the inset over it, its edges feathered into the base.
//!
//! How far the base may be downscaled follows from the eye's minimum angle of resolution
//! (seed 003, §2b; the same w(e) = m·e + w0 as the foveated low-pass): outside the inset's
//! solid core the eccentricity is at least e_core = (½ − FEATHER)·inset_deg, where the eye
//! resolves nothing finer than w(e_core), so the base's pixels may be that wide:
//! scale = ⌊w(e_core) / p⌋ frame pixels per base pixel (p: a pixel's angle), 1 ≤ scale ≤ 8.
//! Within the core the client shows the inset alone, so the fovea is exactly what the codec
//! made of the full-resolution frame.

use super::foveated::LowPass;
use crate::viewing::Viewing;

/// The feathered band on each side of the inset, as a share of its side: the inset's weight
/// rises linearly from 0 at its edge to 1 this far in.
pub const FEATHER: f64 = 0.125;
/// Largest base downscale (frame pixels per base pixel, per axis).
pub const MAX_SCALE: u32 = 8;
/// The inset's angular size the protocol accepts, degrees.
pub const INSET_DEG_RANGE: (f64, f64) = (4.0, 90.0);

/// Where the inset lies in the frame and how the base is downscaled.
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
pub struct InsetPlan {
    /// The inset's top-left pixel and size in the frame (the size even where the frame's is).
    pub x: u32,
    pub y: u32,
    pub width: u32,
    pub height: u32,
    /// Frame pixels per base pixel, per axis; the base is ⌈w/scale⌉ × ⌈h/scale⌉.
    pub scale: u32,
}

impl InsetPlan {
    /// The base image's size for a `width`×`height` frame.
    pub fn base_size(&self, width: u32, height: u32) -> (u32, u32) {
        (width.div_ceil(self.scale), height.div_ceil(self.scale))
    }
}

/// The narrowest inset, degrees, whose unfeathered core holds everything within `guard_deg`
/// of the gaze when the inset is centred on it (a still image's inset, placed on the gaze
/// every frame): 2·guard/(1 − 2·FEATHER). For the 5° judged fovea, 13.3°.
pub fn narrowest_deg(guard_deg: f64) -> f64 {
    2.0 * guard_deg / (1.0 - 2.0 * FEATHER)
}

/// The inset for a frame of `width`×`height` seen as `viewing`, `gaze` normalised: a square
/// `inset_deg` wide (at most the frame) centred on the gaze, moved inside the frame.
pub fn plan(
    width: u32,
    height: u32,
    gaze: [f64; 2],
    viewing: &Viewing,
    inset_deg: f64,
    acuity: &LowPass,
) -> InsetPlan {
    let p = viewing.pixel_angle_deg();
    let side_px = if p > 0.0 { inset_deg / p } else { 0.0 };
    let even = |v: f64, max: u32| ((v.round() as u32 / 2) * 2).clamp(2.min(max), max);
    let (w, h) = (even(side_px, width), even(side_px, height));
    let [cx, cy] = viewing.to_pixels(gaze);
    let place = |c: f64, side: u32, max: u32| {
        let start = (c - f64::from(side) / 2.0).round().max(0.0) as u32;
        start.min(max - side)
    };
    InsetPlan {
        x: place(cx, w, width),
        y: place(cy, h, height),
        width: w,
        height: h,
        scale: base_scale(viewing, inset_deg, acuity, 0.0),
    }
}

/// The base's downscale when the gaze may lie up to `drift_deg` from the inset's centre: the
/// core's edge is then at least e_core − drift from it.
pub fn base_scale(viewing: &Viewing, inset_deg: f64, acuity: &LowPass, drift_deg: f64) -> u32 {
    let p = viewing.pixel_angle_deg();
    let e_core = ((0.5 - FEATHER) * inset_deg - drift_deg).max(0.0);
    let mar = acuity.mar_slope * e_core + acuity.mar_w0_deg;
    let scale = if p > 0.0 { (mar / p).floor() } else { 1.0 };
    (scale.max(1.0) as u32).min(MAX_SCALE)
}

/// The base (box-filtered by `plan.scale`) and the inset (cropped), both RGBA8.
pub fn split(rgba: &[u8], width: u32, height: u32, plan: &InsetPlan) -> (Vec<u8>, Vec<u8>) {
    let (bw, bh) = plan.base_size(width, height);
    let s = plan.scale;
    let mut base = Vec::with_capacity((bw * bh * 4) as usize);
    for by in 0..bh {
        for bx in 0..bw {
            let mut sum = [0u32; 4];
            let mut n = 0;
            for y in by * s..((by + 1) * s).min(height) {
                for x in bx * s..((bx + 1) * s).min(width) {
                    let i = ((y * width + x) * 4) as usize;
                    for k in 0..4 {
                        sum[k] += u32::from(rgba[i + k]);
                    }
                    n += 1;
                }
            }
            base.extend(sum.map(|v| ((v + n / 2) / n.max(1)) as u8));
        }
    }
    let mut inset = Vec::with_capacity((plan.width * plan.height * 4) as usize);
    for y in plan.y..plan.y + plan.height {
        let row = ((y * width + plan.x) * 4) as usize;
        inset.extend_from_slice(&rgba[row..row + (plan.width * 4) as usize]);
    }
    (base, inset)
}

/// The inset's weight at frame pixel (x, y): a linear ramp over `FEATHER` of its side on each
/// side that does not lie on the frame's edge, the two axes multiplied (what the page's two
/// `destination-in` gradients make); 0 outside.
pub fn weight(plan: &InsetPlan, width: u32, height: u32, x: u32, y: u32) -> f64 {
    let axis = |p: u32, start: u32, side: u32, frame: u32| -> f64 {
        if p < start || p >= start + side {
            return 0.0;
        }
        let band = FEATHER * f64::from(side);
        let from_start = f64::from(p - start) + 0.5;
        let from_end = f64::from(start + side - p) - 0.5;
        let a = if start == 0 {
            1.0
        } else {
            (from_start / band).min(1.0)
        };
        let b = if start + side == frame {
            1.0
        } else {
            (from_end / band).min(1.0)
        };
        a.min(b)
    };
    axis(x, plan.x, plan.width, width) * axis(y, plan.y, plan.height, height)
}

/// What the client shows (CPU twin of `web/inset.js`): the base scaled up bilinearly (pixel
/// centres aligned), the inset blended over it by `weight`; RGBA8, `width`×`height`.
pub fn compose(base: &[u8], inset: &[u8], plan: &InsetPlan, width: u32, height: u32) -> Vec<u8> {
    let (bw, bh) = plan.base_size(width, height);
    let s = f64::from(plan.scale);
    let texel = |x: i64, y: i64, k: usize| -> f64 {
        let (x, y) = (x.clamp(0, i64::from(bw) - 1), y.clamp(0, i64::from(bh) - 1));
        f64::from(base[((y * i64::from(bw) + x) * 4) as usize + k])
    };
    let mut out = Vec::with_capacity((width * height * 4) as usize);
    for y in 0..height {
        let v = (f64::from(y) + 0.5) / s - 0.5;
        let (y0, fy) = (v.floor() as i64, v - v.floor());
        for x in 0..width {
            let u = (f64::from(x) + 0.5) / s - 0.5;
            let (x0, fx) = (u.floor() as i64, u - u.floor());
            let a = weight(plan, width, height, x, y);
            for k in 0..4 {
                let top = texel(x0, y0, k) * (1.0 - fx) + texel(x0 + 1, y0, k) * fx;
                let bottom = texel(x0, y0 + 1, k) * (1.0 - fx) + texel(x0 + 1, y0 + 1, k) * fx;
                let mut c = top * (1.0 - fy) + bottom * fy;
                if a > 0.0 {
                    let i = (((y - plan.y) * plan.width + (x - plan.x)) * 4) as usize + k;
                    c = c * (1.0 - a) + f64::from(inset[i]) * a;
                }
                out.push(c.round().clamp(0.0, 255.0) as u8);
            }
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::viewing::Display;

    fn viewing(w: u32, h: u32) -> Viewing {
        Viewing::new(Display::default(), w, h)
    }

    /// A frame whose every pixel differs from its neighbours.
    fn pattern(w: u32, h: u32) -> Vec<u8> {
        (0..w * h)
            .flat_map(|i| {
                let (x, y) = (i % w, i / w);
                [
                    (x * 7 + y * 3) as u8,
                    ((x * 13) ^ (y * 5)) as u8,
                    (x + y * 11) as u8,
                    255,
                ]
            })
            .collect()
    }

    #[test]
    fn the_inset_sits_on_the_gaze_and_the_core_is_the_frame_itself() {
        let (w, h) = (1280, 720);
        let v = viewing(w, h);
        let rgba = pattern(w, h);
        // Gazes far enough from the edges that the inset is not moved inside the frame.
        for gaze in [[0.5, 0.5], [0.35, 0.55], [0.62, 0.45]] {
            let plan = plan(w, h, gaze, &v, 20.0, &LowPass::default());
            assert!(
                plan.scale >= 2,
                "a 20° inset lets the base shrink: {plan:?}"
            );
            let [gx, gy] = v.to_pixels(gaze);
            let centre = [
                f64::from(plan.x) + f64::from(plan.width) / 2.0,
                f64::from(plan.y) + f64::from(plan.height) / 2.0,
            ];
            assert!((centre[0] - gx).abs() <= 2.0 && (centre[1] - gy).abs() <= 2.0);
            let (base, inset) = split(&rgba, w, h, &plan);
            let shown = compose(&base, &inset, &plan, w, h);
            // Within 5° of the gaze every pixel is the frame's own, bit for bit.
            let mut checked = 0;
            for y in 0..h {
                for x in 0..w {
                    if v.eccentricity_deg([gx, gy], [f64::from(x) + 0.5, f64::from(y) + 0.5]) < 5.0
                    {
                        let i = ((y * w + x) * 4) as usize;
                        assert_eq!(shown[i..i + 4], rgba[i..i + 4], "pixel ({x}, {y})");
                        checked += 1;
                    }
                }
            }
            assert!(checked > 10_000, "{checked} foveal pixels");
        }
    }

    #[test]
    fn near_an_edge_the_inset_stays_inside_and_unfeathered_there() {
        let (w, h) = (640, 480);
        let v = viewing(w, h);
        let plan = plan(w, h, [0.0, 1.0], &v, 30.0, &LowPass::default());
        assert_eq!((plan.x, plan.y + plan.height), (0, h));
        assert_eq!(weight(&plan, w, h, 0, h - 1), 1.0);
        assert!(weight(&plan, w, h, plan.width - 1, h - 1) < 0.1);
        // An inset wider than the frame is the whole frame.
        let all = super::plan(w, h, [0.5, 0.5], &v, 90.0, &LowPass::default());
        assert_eq!((all.x, all.y, all.width, all.height), (0, 0, w, h));
    }

    #[test]
    fn the_weight_falls_monotonically_from_the_core_to_the_edge() {
        let plan = InsetPlan {
            x: 100,
            y: 100,
            width: 200,
            height: 200,
            scale: 4,
        };
        let mut last = 1.0;
        for x in 200..=310 {
            let a = weight(&plan, 640, 480, x, 200);
            assert!(a <= last && (0.0..=1.0).contains(&a), "x {x}: {a}");
            last = a;
        }
        assert_eq!(last, 0.0);
        assert_eq!(weight(&plan, 640, 480, 200, 200), 1.0);
    }

    #[test]
    fn the_base_is_the_block_mean() {
        let (w, h) = (6, 4);
        let rgba: Vec<u8> = (0..w * h).flat_map(|i| [i as u8 * 10, 0, 0, 255]).collect();
        let plan = InsetPlan {
            x: 0,
            y: 0,
            width: 2,
            height: 2,
            scale: 4,
        };
        let (base, _) = split(&rgba, w, h, &plan);
        assert_eq!(plan.base_size(w, h), (2, 1));
        // Block 0: x 0..4, y 0..4 → mean of i = x + 6y = (1.5 + 6·1.5)·10 = 105.
        assert_eq!(base[0], 105);
        // Block 1: x 4..6 → mean (4.5 + 9)·10 = 135.
        assert_eq!(base[4], 135);
    }
}
