//! Punctual lights at a point: the direction towards the light and the irradiance it gives a
//! surface facing it. CPU twin of `punctual_light` in `shaders/common.wgsl`.
//!
//! Falloff follows the glTF `KHR_lights_punctual` recommendation: inverse square, windowed to 0
//! at `range` by (1 − (d/range)⁴)², and a spot's cone blended by t² with t linear in cos θ
//! between the outer and inner angles.

use glam::Vec3;

use crate::scene::LightSpec;

/// Distances below this (scene units) count as this, so a point on the light stays finite.
pub const MIN_DISTANCE: f32 = 1e-4;

/// (unit vector towards the light, irradiance on a surface facing it) at `x`.
pub fn punctual(light: &LightSpec, x: Vec3) -> (Vec3, Vec3) {
    match *light {
        LightSpec::Directional {
            to_light,
            color,
            intensity,
        } => (
            Vec3::from(to_light).normalize_or_zero(),
            Vec3::from(color) * intensity,
        ),
        LightSpec::Point {
            position,
            color,
            intensity,
            range,
        } => {
            let (l, falloff) = point(Vec3::from(position), range, x);
            (l, Vec3::from(color) * intensity * falloff)
        }
        LightSpec::Spot {
            position,
            direction,
            color,
            intensity,
            range,
            inner_deg,
            outer_deg,
        } => {
            let (l, falloff) = point(Vec3::from(position), range, x);
            let axis = Vec3::from(direction).normalize_or_zero();
            let (ci, co) = (inner_deg.to_radians().cos(), outer_deg.to_radians().cos());
            let t = ((-l).dot(axis) - co) / (ci - co).max(1e-6);
            let t = t.clamp(0.0, 1.0);
            (l, Vec3::from(color) * intensity * falloff * t * t)
        }
    }
}

fn point(position: Vec3, range: Option<f32>, x: Vec3) -> (Vec3, f32) {
    let d = (position - x).length().max(MIN_DISTANCE);
    let l = (position - x) / d;
    let window = match range {
        Some(r) if r > 0.0 => (1.0 - (d / r).powi(4)).clamp(0.0, 1.0).powi(2),
        _ => 1.0,
    };
    (l.normalize_or_zero(), window / (d * d))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn point_lights_fall_with_the_square_of_distance_and_stop_at_their_range() {
        let p = LightSpec::Point {
            position: [0.0, 2.0, 0.0],
            color: [1.0; 3],
            intensity: 4.0,
            range: None,
        };
        let (l, e) = punctual(&p, Vec3::ZERO);
        assert_eq!(l, Vec3::Y);
        assert!((e.x - 1.0).abs() < 1e-6);
        let ranged = LightSpec::Point {
            position: [0.0, 2.0, 0.0],
            color: [1.0; 3],
            intensity: 4.0,
            range: Some(1.5),
        };
        assert_eq!(punctual(&ranged, Vec3::ZERO).1, Vec3::ZERO);
        let (_, at_light) = punctual(&p, Vec3::new(0.0, 2.0, 0.0));
        assert!(at_light.is_finite());
    }

    #[test]
    fn spots_light_inside_their_cone_only() {
        let s = LightSpec::Spot {
            position: [0.0, 1.0, 0.0],
            direction: [0.0, -1.0, 0.0],
            color: [1.0; 3],
            intensity: 1.0,
            range: None,
            inner_deg: 10.0,
            outer_deg: 20.0,
        };
        assert!((punctual(&s, Vec3::ZERO).1.x - 1.0).abs() < 1e-6);
        let outside = Vec3::new(1.0, 0.0, 0.0); // 45° off the axis
        assert_eq!(punctual(&s, outside).1, Vec3::ZERO);
        let edge = Vec3::new(15f32.to_radians().tan(), 0.0, 0.0);
        let e = punctual(&s, edge).1.x;
        assert!(e > 0.0 && e < 1.0, "{e}");
    }
}
