//! Direct lighting of an opaque diffuse surface: the forward pass's fragment shader.

use glam::Vec3;

/// Outgoing linear radiance (times π, i.e. in units where a white surface facing a unit light
/// reflects 1) of a Lambertian surface under one directional light plus a constant ambient term.
/// `normal` need not be normalised (interpolated normals are not); a zero normal gives ambient only.
pub fn lambert(normal: Vec3, to_light: Vec3, albedo: Vec3, light: Vec3, ambient: f32) -> Vec3 {
    let n = normal.try_normalize().unwrap_or(Vec3::ZERO);
    let cos = n.dot(to_light).max(0.0);
    albedo * light * (cos + ambient)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn surface_facing_away_from_the_light_gets_only_ambient() {
        let c = lambert(-Vec3::Y, Vec3::Y, Vec3::ONE, Vec3::ONE, 0.1);
        assert_eq!(c, Vec3::splat(0.1));
    }

    #[test]
    fn zero_normal_is_finite() {
        let c = lambert(Vec3::ZERO, Vec3::Y, Vec3::ONE, Vec3::ONE, 0.05);
        assert!(c.is_finite());
        assert_eq!(c, Vec3::splat(0.05));
    }

    #[test]
    fn head_on_white_light_reflects_albedo_plus_ambient() {
        let c = lambert(
            Vec3::Z * 3.0,
            Vec3::Z,
            Vec3::new(0.5, 0.25, 1.0),
            Vec3::ONE,
            0.0,
        );
        assert!((c - Vec3::new(0.5, 0.25, 1.0)).abs().max_element() < 1e-6);
    }
}
