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

/// A punctual light as the shaders see it (`PunctualLight` in `shaders/common.wgsl`): every
/// kind in one shape, angles already cosines, colour already times intensity.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Punctual {
    /// 0 directional, 1 point, 2 spot.
    pub kind: u32,
    /// The position, or the unit vector towards a directional light.
    pub at: Vec3,
    pub radiance: Vec3,
    /// 0: no range.
    pub range: f32,
    /// A spot's axis (away from the light) and its cone's cosines.
    pub axis: Vec3,
    pub cos_inner: f32,
    pub cos_outer: f32,
}

impl Punctual {
    pub fn of(light: &LightSpec) -> Punctual {
        let mut p = Punctual {
            kind: 0,
            at: Vec3::ZERO,
            radiance: Vec3::ZERO,
            range: 0.0,
            axis: Vec3::ZERO,
            cos_inner: 1.0,
            cos_outer: 1.0,
        };
        match *light {
            LightSpec::Directional {
                to_light,
                color,
                intensity,
            } => {
                p.at = Vec3::from(to_light).normalize_or_zero();
                p.radiance = Vec3::from(color) * intensity;
            }
            LightSpec::Point {
                position,
                color,
                intensity,
                range,
            } => {
                (p.kind, p.at, p.range) = (1, position.into(), range.unwrap_or(0.0));
                p.radiance = Vec3::from(color) * intensity;
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
                (p.kind, p.at, p.range) = (2, position.into(), range.unwrap_or(0.0));
                p.radiance = Vec3::from(color) * intensity;
                p.axis = Vec3::from(direction).normalize_or_zero();
                (p.cos_inner, p.cos_outer) =
                    (inner_deg.to_radians().cos(), outer_deg.to_radians().cos());
            }
        }
        p
    }
}

/// (unit vector towards the light, irradiance on a surface facing it) at `x`.
pub fn punctual(light: &LightSpec, x: Vec3) -> (Vec3, Vec3) {
    let p = Punctual::of(light);
    if p.kind == 0 {
        return (p.at, p.radiance);
    }
    let range = (p.range > 0.0).then_some(p.range);
    let (l, mut falloff) = point(p.at, range, x);
    if p.kind == 2 {
        let t = ((-l).dot(p.axis) - p.cos_outer) / (p.cos_inner - p.cos_outer).max(1e-6);
        falloff *= t.clamp(0.0, 1.0).powi(2);
    }
    (l, p.radiance * falloff)
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
