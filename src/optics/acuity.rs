//! Visual acuity across the field: eccentricity from the gaze on a physical display, the minimum
//! angle of resolution (MAR), the sampling probability it implies, and the pupil-driven depth of
//! field. CPU twin of `shaders/sampling.wgsl` and `shaders/dof.wgsl`.
//!
//! Units: angles in degrees unless a name says radians; display sizes in centimetres.

/// Linear MAR model (Strasburger; thesis Fig. 12): w(e) = m·e + w0, in degrees.
pub fn mar_deg(e_deg: f64, slope: f64, w0_deg: f64) -> f64 {
    slope * e_deg + w0_deg
}

pub use crate::settings::ProbabilityForm;

/// Sampling probability before saliency and depth of field, in [0, 1]. Guards: a display
/// coarser than the eye everywhere (`w_far ≤ w_min`) samples fully; a zero or negative MAR
/// (impossible parameters) samples fully rather than dividing by zero.
pub fn acuity_probability(form: ProbabilityForm, w: f64, w_min: f64, w_far: f64) -> f64 {
    let p = match form {
        ProbabilityForm::Linear => {
            let span = w_far - w_min;
            if span <= 1e-12 {
                1.0
            } else {
                1.0 - (w - w_min) / span
            }
        }
        ProbabilityForm::Density => {
            if w <= 1e-12 {
                1.0
            } else {
                (w_min / w) * (w_min / w)
            }
        }
    };
    if p.is_nan() {
        1.0
    } else {
        p.clamp(0.0, 1.0)
    }
}

/// Where the eye may be looking, degrees around the reported gaze: tracker error and the
/// latency between the gaze sample and the frame on the screen (the same disc the foveal error
/// is judged in, and that foveated encoding leaves untouched). Whole degrees, shared with WGSL.
pub const EDGE_MARGIN_DEG: u32 = 5;

/// The eccentricity whose acuity an edge is sampled for with `edges_at_mar`: the nearest the
/// eye may be to it, [`EDGE_MARGIN_DEG`] closer than the reported gaze says. An edge asks for
/// S·√p there (one sample per MAR along it), so within the margin edges are sampled fully.
pub fn edge_eccentricity_deg(e_deg: f64) -> f64 {
    (e_deg - f64::from(EDGE_MARGIN_DEG)).max(0.0)
}

/// Angular diameter (radians) of the eye's blur circle for a point at `distance_m` when focused
/// at `focus_m`, with a pupil of `pupil_mm`: β ≈ A·|1/d_focus − 1/d| (thin lens, small angles).
/// Distances at or below zero are treated as 1 mm, never divided by.
pub fn blur_angle_rad(pupil_mm: f64, focus_m: f64, distance_m: f64) -> f64 {
    let f = focus_m.max(1e-3);
    let d = distance_m.max(1e-3);
    (pupil_mm * 1e-3) * (1.0 / f - 1.0 / d).abs()
}

/// The depth-of-field factor of thesis eq. 3, made physical: where the blur circle spans `b`
/// pixels, a sample every `b` pixels suffices, so density may fall as 1/b². Equal to 1 inside
/// the in-focus band (b ≤ 1 px).
pub fn dof_factor(blur_px: f64) -> f64 {
    if blur_px.is_nan() || blur_px <= 1.0 {
        1.0
    } else {
        1.0 / (blur_px * blur_px)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::viewing::Viewing;

    fn view() -> Viewing {
        Viewing {
            width: 640,
            height: 480,
            width_cm: 53.0,
            distance_cm: 60.0,
        }
    }

    #[test]
    fn edges_are_sampled_for_the_acuity_within_the_margin_nearest_them() {
        // Inside the margin the eye may be on the edge: the fovea's acuity, whatever the gaze.
        for e in [0.0, 1.0, 4.999, f64::from(EDGE_MARGIN_DEG)] {
            assert_eq!(edge_eccentricity_deg(e), 0.0, "{e}°");
        }
        // Beyond it the margin less, never negative, and monotone with the eccentricity.
        assert!((edge_eccentricity_deg(12.5) - 7.5).abs() < 1e-12);
        let mut last = 0.0;
        for k in 0..=900 {
            let e = edge_eccentricity_deg(f64::from(k) * 0.1);
            assert!(e >= last && e <= f64::from(k) * 0.1);
            last = e;
        }
        // An eccentricity that is not a number (no gaze) samples edges fully.
        assert_eq!(edge_eccentricity_deg(f64::NAN), 0.0);
    }

    #[test]
    fn eccentricity_is_zero_at_the_gaze_and_precise_just_beside_it() {
        let v = view();
        assert_eq!(v.eccentricity_deg([320.0, 240.0], [320.0, 240.0]), 0.0);
        // A hundredth of a pixel away: acos would round this to 0 or to ~1e-4 garbage.
        let e = v.eccentricity_deg([100.0, 100.0], [100.01, 100.0]);
        let expected = (0.01 * 53.0 / 640.0 / 60.0f64).atan().to_degrees();
        assert!((e - expected).abs() / expected < 0.2, "{e} vs {expected}");
    }

    #[test]
    fn eccentricity_of_the_frame_edge_matches_trigonometry() {
        let v = view();
        let e = v.eccentricity_deg([320.0, 240.0], [640.0, 240.0]);
        assert!((e - (26.5f64 / 60.0).atan().to_degrees()).abs() < 1e-9);
        // Off-screen gaze is still a direction: finite and larger towards the far side.
        let off = v.eccentricity_deg([-500.0, 240.0], [640.0, 240.0]);
        assert!(off.is_finite() && off > e);
    }

    #[test]
    fn probability_forms_hit_their_ends_and_stay_in_range() {
        for form in [ProbabilityForm::Linear, ProbabilityForm::Density] {
            assert_eq!(
                acuity_probability(form, 0.05, 0.08, 0.9),
                1.0,
                "{form:?}: finer than a pixel"
            );
            assert_eq!(acuity_probability(form, 0.08, 0.08, 0.9), 1.0);
            for w in [0.0, 1e-9, 0.1, 0.5, 0.9, 5.0, f64::INFINITY, f64::NAN] {
                let p = acuity_probability(form, w, 0.08, 0.9);
                assert!((0.0..=1.0).contains(&p), "{form:?} w={w}: {p}");
            }
        }
        assert_eq!(
            acuity_probability(ProbabilityForm::Linear, 0.9, 0.08, 0.9),
            0.0
        );
        assert_eq!(
            acuity_probability(ProbabilityForm::Linear, 0.5, 0.08, 0.08),
            1.0,
            "w_far = w_min"
        );
        assert_eq!(
            acuity_probability(ProbabilityForm::Linear, 0.5, 0.08, 0.0),
            1.0,
            "w_far → 0"
        );
        let d = acuity_probability(ProbabilityForm::Density, 0.16, 0.08, 0.9);
        assert!(
            (d - 0.25).abs() < 1e-12,
            "twice the MAR: a quarter of the samples"
        );
    }

    #[test]
    fn larger_pupils_blur_more_and_focus_is_sharp() {
        assert_eq!(blur_angle_rad(4.0, 0.3, 0.3), 0.0);
        let small = blur_angle_rad(2.0, 0.24, 0.30);
        let large = blur_angle_rad(8.0, 0.24, 0.30);
        assert!((large / small - 4.0).abs() < 1e-9);
        // 4 mm pupil, focus 0.24 m, point at 0.30 m: 4e-3 × (1/0.24 − 1/0.3) = 3.33e-3 rad.
        assert!((blur_angle_rad(4.0, 0.24, 0.30) - 3.333e-3).abs() < 1e-6);
        assert!(blur_angle_rad(4.0, 0.0, -1.0).is_finite());
        assert_eq!(dof_factor(0.5), 1.0);
        assert_eq!(dof_factor(4.0), 1.0 / 16.0);
        assert_eq!(dof_factor(f64::NAN), 1.0);
    }
}
