//! Form factors between a receiving point and a shooting patch (GPU Gems 2 ch. 39, after
//! Wallace et al. 1989): the patch is an oriented disc of its own area, so the factor stays
//! finite as the distance goes to zero, where the differential form cos·cos/(πr²) diverges.

use std::f32::consts::PI;

use glam::Vec3;

/// A flat convex piece of a shooting patch (a wall patch, or one triangle of a mesh cluster).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Facet {
    pub centre: Vec3,
    pub normal: Vec3,
    pub area: f32,
    /// Corners counter-clockwise seen from the front; `corners[3]` repeats `corners[2]` for a
    /// triangle.
    pub corners: [Vec3; 4],
    pub sides: usize,
}

/// Receivers closer than this many facet "radii" (r² < NEAR · A) get the exact polygon factor:
/// there the disc at the centre is badly off (a wall next to the shooter, a receiver almost
/// touching it).
const NEAR: f32 = 16.0;

/// F(dA_r → A_s) for one facet: the fraction of the light leaving a differential receiver at
/// `receiver` with unit normal `normal` that lands on the facet, visibility not included.
///
/// Far away the facet is an oriented disc (GPU Gems 2, after Wallace et al. 1989):
/// cos_r cos_s A / (π r² + A), finite as r → 0. Both cosines are clamped separately: the
/// listing in the seed clamps their product, which lets two elements facing away from each
/// other (both cosines negative) exchange light. Near the facet, Lambert's exact contour
/// integral over the part of the polygon above the receiver's horizon.
pub fn point_to_facet(receiver: Vec3, normal: Vec3, facet: &Facet) -> f32 {
    let w = facet.centre - receiver;
    let r2 = w.length_squared();
    if !(facet.area > 0.0) || facet.normal.dot(receiver - facet.centre) <= 0.0 {
        return 0.0;
    }
    if r2 < NEAR * facet.area {
        return polygon_factor(receiver, normal, &facet.corners[..facet.sides]).min(1.0);
    }
    let dir = w / r2.sqrt();
    let cos_r = normal.dot(dir).max(0.0);
    let cos_s = (-facet.normal.dot(dir)).max(0.0);
    (cos_r * cos_s * facet.area / (PI * r2 + facet.area)).min(1.0)
}

/// F(dA_r → A_s) for a patch: the sum over its facets, at most 1.
pub fn point_to_patch(receiver: Vec3, normal: Vec3, facets: &[Facet]) -> f32 {
    facets
        .iter()
        .map(|f| point_to_facet(receiver, normal, f))
        .sum::<f32>()
        .min(1.0)
}

/// Lambert's formula, F = (1/2π) Σ γ_i n · (R_i × R_i+1)/|R_i × R_i+1|, for a convex polygon
/// clipped to the receiver's upper half-space (Sutherland–Hodgman on the vectors R_i).
fn polygon_factor(receiver: Vec3, normal: Vec3, corners: &[Vec3]) -> f32 {
    let mut clipped = [Vec3::ZERO; 8];
    let mut count = 0;
    for i in 0..corners.len() {
        let a = corners[i] - receiver;
        let b = corners[(i + 1) % corners.len()] - receiver;
        let (da, db) = (normal.dot(a), normal.dot(b));
        if da >= 0.0 {
            clipped[count] = a;
            count += 1;
        }
        if (da >= 0.0) != (db >= 0.0) {
            let t = da / (da - db);
            clipped[count] = a + (b - a) * t;
            count += 1;
        }
    }
    let mut sum = 0.0f32;
    for i in 0..count {
        let (Some(a), Some(b)) = (
            clipped[i].try_normalize(),
            clipped[(i + 1) % count].try_normalize(),
        ) else {
            continue;
        };
        let c = a.cross(b);
        let len = c.length();
        if len > 1e-12 {
            sum += len.atan2(a.dot(b)) * normal.dot(c / len);
        }
    }
    (sum / (2.0 * PI)).abs()
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A square of the given area centred on `centre`, facing `normal` (±Z).
    fn disc(centre: Vec3, normal: Vec3, area: f32) -> Vec<Facet> {
        let h = area.sqrt() / 2.0;
        let mut corners = [
            Vec3::new(-h, -h, 0.0),
            Vec3::new(h, -h, 0.0),
            Vec3::new(h, h, 0.0),
            Vec3::new(-h, h, 0.0),
        ]
        .map(|c| c + centre);
        if normal.z < 0.0 {
            corners.reverse();
        }
        vec![Facet {
            centre,
            normal,
            area,
            corners,
            sides: 4,
        }]
    }

    #[test]
    fn the_exact_near_factor_of_a_square_matches_its_closed_form() {
        // A point under the centre of a 2a × 2a square at height h (unit area normal along
        // the axis): F = (2/π)·(a/√(a²+h²))·atan(a/√(a²+h²)) summed for the four quarters —
        // closed form 4 · (1/2π)(x/√(1+x²) atan(y/√(1+x²)) + y/√(1+y²) atan(x/√(1+y²))) with
        // x = y = a/h for each quarter.
        for (a, h) in [(1.0f32, 0.5f32), (1.0, 0.05), (0.5, 1.0)] {
            let area = 4.0 * a * a;
            let f = point_to_patch(Vec3::ZERO, Vec3::Z, &disc(Vec3::Z * h, Vec3::NEG_Z, area));
            let x = a / h;
            let q = 1.0 / (2.0 * PI)
                * 2.0
                * (x / (1.0 + x * x).sqrt())
                * (x / (1.0 + x * x).sqrt()).atan();
            assert!(
                (f - 4.0 * q).abs() < 1e-4,
                "a {a} h {h}: {f} vs {}",
                4.0 * q
            );
        }
    }

    #[test]
    fn a_point_under_a_distant_coaxial_disc_gets_the_exact_factor() {
        // Exact: F = a²/(a² + h²) for a disc of radius a at height h facing the point.
        for (a, h) in [(0.1f32, 1.0f32), (0.3, 4.0), (0.2, 2.0)] {
            let area = PI * a * a;
            let f = point_to_patch(Vec3::ZERO, Vec3::Z, &disc(Vec3::Z * h, Vec3::NEG_Z, area));
            let exact = a * a / (a * a + h * h);
            assert!((f - exact).abs() < 1e-5, "a {a} h {h}: {f} vs {exact}");
        }
    }

    #[test]
    fn back_to_back_coincident_and_tiny_cases_stay_finite_and_bounded() {
        let area = 0.25;
        // Back to back: both cosines negative (a product clamp would let light through).
        let away = disc(Vec3::Z, Vec3::Z, area);
        assert_eq!(point_to_patch(Vec3::ZERO, Vec3::NEG_Z, &away), 0.0);
        // Receiver facing away from a shooter that faces it, and the other way round.
        let facing = disc(Vec3::Z, Vec3::NEG_Z, area);
        assert_eq!(point_to_patch(Vec3::ZERO, Vec3::NEG_Z, &facing), 0.0);
        assert_eq!(point_to_patch(Vec3::ZERO, Vec3::Z, &away), 0.0);
        // Coincident points.
        assert_eq!(
            point_to_patch(Vec3::ONE, Vec3::Z, &disc(Vec3::ONE, Vec3::NEG_Z, area)),
            0.0
        );
        // r → 0 with both facing: tends to 1, never above.
        for h in [1e-2f32, 1e-4, 1e-6, 1e-9] {
            let f = point_to_patch(Vec3::ZERO, Vec3::Z, &disc(Vec3::Z * h, Vec3::NEG_Z, area));
            assert!(f.is_finite() && f <= 1.0 && f > 0.99, "h {h}: {f}");
        }
        // A zero-area shooter sends nothing.
        assert_eq!(
            point_to_patch(Vec3::ZERO, Vec3::Z, &disc(Vec3::Z, Vec3::NEG_Z, 0.0)),
            0.0
        );
    }
}
