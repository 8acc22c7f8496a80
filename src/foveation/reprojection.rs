//! The reprojection cache test (thesis eq. 4, with the digest's fixes): reuse last frame's colour
//! at a pixel only if the surface seen there now is the one seen there then. CPU twin of
//! `shaders/reproject.wgsl`.
//!
//! Fixes over the printed equation: the difference is taken in absolute value (as printed, any
//! disocclusion — the new surface *behind* the old — counted as a hit); the stored depth is the
//! Euclidean distance from the previous eye, which is what it is compared with; the tolerance is
//! relative, so the test does not depend on scene scale; off-screen reprojections are misses.

/// Default relative depth tolerance ε: 1% of the distance.
pub const DEFAULT_EPSILON: f32 = 0.01;

/// Is the history at `prev_uv` (normalised, in [0, 1)²) valid for the current surface point?
/// `prev_distance`: distance stored there last frame (from last frame's eye);
/// `distance_from_prev_eye`: |pos_now − eye_prev|. Non-finite inputs are misses.
pub fn cache_hit(
    prev_uv: [f32; 2],
    prev_distance: f32,
    distance_from_prev_eye: f32,
    epsilon: f32,
) -> bool {
    let on_screen = prev_uv.iter().all(|c| (0.0..1.0).contains(c));
    if !on_screen || !prev_distance.is_finite() || !distance_from_prev_eye.is_finite() {
        return false;
    }
    (prev_distance - distance_from_prev_eye).abs() < epsilon * distance_from_prev_eye.max(1e-6)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn same_surface_hits_and_disocclusion_misses_in_both_directions() {
        assert!(cache_hit([0.5, 0.5], 24.0, 24.1, 0.01));
        assert!(
            !cache_hit([0.5, 0.5], 20.0, 24.0, 0.01),
            "new surface behind the old (x < 0)"
        );
        assert!(
            !cache_hit([0.5, 0.5], 28.0, 24.0, 0.01),
            "new surface in front"
        );
    }

    #[test]
    fn off_screen_and_non_finite_reprojections_miss() {
        for uv in [[-0.01, 0.5], [0.5, 1.0], [1.2, 0.3], [f32::NAN, 0.5]] {
            assert!(!cache_hit(uv, 24.0, 24.0, 0.01), "{uv:?}");
        }
        assert!(
            !cache_hit([0.5, 0.5], f32::INFINITY, 24.0, 0.01),
            "no history there"
        );
        assert!(!cache_hit([0.5, 0.5], 24.0, f32::NAN, 0.01));
    }
}
