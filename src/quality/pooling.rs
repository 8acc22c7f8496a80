//! Pooling per-pixel errors with a weight that falls with eccentricity: errors far from the gaze
//! matter less because the eye resolves less there.

use crate::optics::acuity::mar_deg;
use crate::viewing::Viewing;

/// The acuity weighting: weight(e) = min(1, w_px / (m·e + w0)), the display's pixel angle over
/// the MAR at eccentricity e. It is 1 wherever the eye resolves single pixels and falls as
/// 1/MAR beyond, so a pixel's error counts in proportion to how much of it the eye can see.
/// Defaults: m = 0.022, w0 = 1/48° (Guenter et al. 2012's band).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Weighting {
    pub mar_slope: f64,
    pub mar_w0_deg: f64,
}

impl Default for Weighting {
    fn default() -> Self {
        Weighting {
            mar_slope: 0.022,
            mar_w0_deg: 1.0 / 48.0,
        }
    }
}

pub fn acuity_weights(v: &Viewing, gaze_px: [f64; 2], w: &Weighting) -> Vec<f64> {
    per_pixel(v, |px| {
        let e = v.eccentricity_deg(gaze_px, px);
        (v.pixel_angle_deg() / mar_deg(e, w.mar_slope, w.mar_w0_deg)).min(1.0)
    })
}

/// 1 within `radius_deg` of the gaze, 0 elsewhere.
pub fn foveal_mask(v: &Viewing, gaze_px: [f64; 2], radius_deg: f64) -> Vec<f64> {
    per_pixel(v, |px| {
        if v.eccentricity_deg(gaze_px, px) <= radius_deg {
            1.0
        } else {
            0.0
        }
    })
}

fn per_pixel(v: &Viewing, f: impl Fn([f64; 2]) -> f64) -> Vec<f64> {
    (0..v.width * v.height)
        .map(|k| f([(k % v.width) as f64 + 0.5, (k / v.width) as f64 + 0.5]))
        .collect()
}

/// Weighted mean; NaN if every weight is zero (the gaze region lies off the frame).
pub fn pooled_mean(values: &[f64], weights: &[f64]) -> f64 {
    let (s, w) = values
        .iter()
        .zip(weights)
        .fold((0.0, 0.0), |(s, ws), (v, w)| (s + v * w, ws + w));
    if w > 0.0 {
        s / w
    } else {
        f64::NAN
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn weight_is_one_at_the_gaze_and_falls_outward() {
        let v = Viewing {
            width: 640,
            height: 480,
            width_cm: 53.0,
            distance_cm: 60.0,
        };
        let w = acuity_weights(&v, [320.0, 240.0], &Weighting::default());
        assert_eq!(w[240 * 640 + 320], 1.0);
        // A pixel is 0.079°: the eye resolves it out to e = (0.079 − 0.0208)/0.022 ≈ 2.6°.
        let corner = w[0];
        let e = v.eccentricity_deg([320.0, 240.0], [0.5, 0.5]);
        let expected = v.pixel_angle_deg() / (0.022 * e + 1.0 / 48.0);
        assert!(
            (corner - expected).abs() < 1e-12 && corner < 0.15,
            "{corner}"
        );
        let mask = foveal_mask(&v, [320.0, 240.0], 5.0);
        assert_eq!(mask[240 * 640 + 320], 1.0);
        assert_eq!(mask[0], 0.0);
    }
}
