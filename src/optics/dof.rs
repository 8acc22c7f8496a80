//! The depth-of-field blur (CPU twin of `shaders/dof.wgsl`): each pixel averages `TAPS` pixels
//! on a Vogel spiral over its blur circle, whose radius is half the angle of
//! [`blur_angle_rad`](super::acuity::blur_angle_rad) in pixels, at most `MAX_RADIUS_PX`. The
//! shader turns each tap by the golden angle with a fixed rotation; here the angles are exact,
//! so a tap whose offset lies within a rounding error of half a pixel may land one pixel over.

/// Taps per pixel.
pub const TAPS: usize = 24;
/// Largest blur radius, pixels.
pub const MAX_RADIUS_PX: f32 = 24.0;
/// The golden angle, π(3 − √5) radians: consecutive taps turn by it.
pub const GOLDEN_ANGLE: f64 = 2.399_963_229_728_653;

/// What the blur needs to know of the frame.
#[derive(Debug, Clone, Copy)]
pub struct Focus {
    /// Pupil diameter, mm.
    pub pupil_mm: f32,
    /// Scene units → metres.
    pub metres_per_unit: f32,
    /// Vertical field of view over the frame's height.
    pub radians_per_pixel: f32,
    /// Distance (scene units) the eye focuses at: the depth under the gaze, or the camera's
    /// target distance where the gaze is off every surface.
    pub focus_distance: f32,
}

/// Blur radius (pixels) of a point `distance` scene units away; 0 for the background (≤ 0).
pub fn blur_radius_px(distance: f32, f: &Focus) -> f32 {
    if distance.is_nan() || distance <= 0.0 {
        return 0.0;
    }
    let focus = (f.focus_distance * f.metres_per_unit).max(1e-3);
    let d = (distance * f.metres_per_unit).max(1e-3);
    let beta = f.pupil_mm * 1e-3 * (1.0 / focus - 1.0 / d).abs();
    (0.5 * beta / f.radians_per_pixel).min(MAX_RADIUS_PX)
}

/// The blurred linear colour of every pixel of a `width`×`height` frame, from its colour and
/// its distances (row-major). Pixels whose radius is under half a pixel keep their colour.
pub fn depth_of_field(
    color: &[[f32; 3]],
    distance: &[f32],
    width: usize,
    height: usize,
    f: &Focus,
) -> Vec<[f32; 3]> {
    let clamp = |v: i64, n: usize| v.clamp(0, n as i64 - 1) as usize;
    (0..width * height)
        .map(|k| {
            let r = blur_radius_px(distance[k], f);
            if r < 0.5 {
                return color[k];
            }
            let (x, y) = ((k % width) as i64, (k / width) as i64);
            let mut sum = [0.0f32; 3];
            for i in 0..TAPS {
                let t = (i as f64 + 0.5) / TAPS as f64;
                let a = i as f64 * GOLDEN_ANGLE;
                let s = t.sqrt() * f64::from(r);
                // WGSL's round() is half-to-even, as f64::round_ties_even.
                let dx = (a.cos() * s).round_ties_even() as i64;
                let dy = (a.sin() * s).round_ties_even() as i64;
                let q = clamp(y + dy, height) * width + clamp(x + dx, width);
                for (acc, c) in sum.iter_mut().zip(color[q]) {
                    *acc += c;
                }
            }
            sum.map(|c| c / TAPS as f32)
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    fn focus() -> Focus {
        Focus {
            pupil_mm: 4.0,
            metres_per_unit: 0.1,
            radians_per_pixel: 0.001,
            focus_distance: 10.0,
        }
    }

    #[test]
    fn in_focus_and_background_pixels_are_untouched_and_the_radius_is_bounded() {
        let f = focus();
        assert_eq!(blur_radius_px(10.0, &f), 0.0);
        assert_eq!(blur_radius_px(0.0, &f), 0.0);
        assert_eq!(blur_radius_px(f32::NAN, &f), 0.0);
        // Extremes: a point at the eye, and one at infinity.
        assert_eq!(blur_radius_px(1e-9, &f), MAX_RADIUS_PX);
        let far = blur_radius_px(f32::MAX, &f);
        // 4 mm · |1/1 m − 0| / 2 / 1 mrad = 2 px.
        assert!((far - 2.0).abs() < 1e-4, "{far}");
        let color = vec![[0.25, 0.5, 1.0]; 9];
        let out = depth_of_field(&color, &[10.0; 9], 3, 3, &f);
        assert_eq!(out, color);
    }

    #[test]
    fn a_flat_colour_stays_flat_and_a_point_spreads_over_its_circle() {
        let f = Focus {
            focus_distance: 1.0,
            ..focus()
        };
        let (w, h) = (41, 41);
        let r = blur_radius_px(100.0, &f);
        assert!(r > 5.0 && r < 20.0, "{r}");
        let flat = depth_of_field(&vec![[0.3; 3]; w * h], &vec![100.0; w * h], w, h, &f);
        assert!(flat
            .iter()
            .all(|c| c.iter().all(|v| (v - 0.3).abs() < 1e-6)));
        // One lit pixel in the middle: it reaches pixels within r of it, none beyond.
        let mut point = vec![[0.0f32; 3]; w * h];
        point[20 * w + 20] = [1.0; 3];
        let out = depth_of_field(&point, &vec![100.0; w * h], w, h, &f);
        // Each tap carries 1/TAPS of it to the one pixel it is read from: none is lost.
        let total: f32 = out.iter().map(|c| c[0]).sum();
        assert!((total - 1.0).abs() < 1e-4, "{total}");
        for (k, c) in out.iter().enumerate() {
            let (dx, dy) = ((k % w) as f32 - 20.0, (k / w) as f32 - 20.0);
            if c[0] > 0.0 {
                assert!(
                    (dx * dx + dy * dy).sqrt() <= r + 1.0,
                    "({dx}, {dy}) past {r}"
                );
            }
        }
    }
}
