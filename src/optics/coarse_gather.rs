//! CPU twin of the coarse photon gather's interpolation (`shaders/shade.wgsl`, `interpolated`):
//! which lattice points a pixel's gather is blended from, and with what weights, or that the
//! pixel must gather itself.
//!
//! The gather Σ R_d(|x_c − x|) Φ_c depends on the surface point x alone and is smooth over the
//! photons' softening length, so on one smooth patch of one material it can be taken at every
//! other pixel on each axis (the lattice (2i, 2j)) and blended bilinearly between them: a pixel
//! on a lattice point is that point, one between two takes ½ of each, one inside a cell ¼ of
//! four. Where any of those points lies on another material, farther from x than half the
//! softening length, with a normal more than ~25° off, or outside the frame, the blend would
//! mix light from elsewhere and the pixel gathers itself.

/// Normals closer than this cosine (~25°) count as one smooth patch (`COHERENT_COS`).
pub const COHERENT_COS: f32 = 0.9;

/// Lattice points may lie this many softening lengths from the pixel's surface point
/// (`REACH_OF_SOFTENING`): within half of it the gather changes little, and a straight blend
/// missed the per-pixel gather by under 2% on the marble bunny (`tests/coarse_gather.rs`);
/// within a whole one by up to 26%, on its ears at 160×120.
pub const REACH_OF_SOFTENING: f32 = 0.5;

/// What a pixel sees: the surface point, its normal and its material id.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Surface {
    pub point: [f32; 3],
    pub normal: [f32; 3],
    pub material: u32,
}

/// The lattice points (pixel coordinates, both even) and weights pixel `p` is blended from, or
/// `None` where it must gather itself. `at` gives what a pixel sees (None: background);
/// `gathered` whether a lattice point holds a gather (a photon-rung material); `reach` is how
/// far a lattice point may lie, in scene units (`REACH_OF_SOFTENING` × the softening length).
pub fn lattice_weights(
    p: (u32, u32),
    size: (u32, u32),
    at: &dyn Fn(u32, u32) -> Option<Surface>,
    gathered: &dyn Fn(u32, u32) -> bool,
    reach: f32,
) -> Option<Vec<((u32, u32), f32)>> {
    let own = at(p.0, p.1)?;
    let base = (p.0 / 2, p.1 / 2);
    let odd = (p.0 % 2, p.1 % 2);
    let w = if odd.0 == 1 { 0.5 } else { 1.0 } * if odd.1 == 1 { 0.5 } else { 1.0 };
    let mut out = Vec::with_capacity(4);
    for oy in 0..=odd.1 {
        for ox in 0..=odd.0 {
            let q = (2 * (base.0 + ox), 2 * (base.1 + oy));
            if q.0 >= size.0 || q.1 >= size.1 || !gathered(q.0, q.1) {
                return None;
            }
            let s = at(q.0, q.1)?;
            let d = (0..3)
                .map(|i| (s.point[i] - own.point[i]).powi(2))
                .sum::<f32>()
                .sqrt();
            let cos = (0..3).map(|i| s.normal[i] * own.normal[i]).sum::<f32>();
            if s.material != own.material || d > reach.max(1e-12) || cos < COHERENT_COS {
                return None;
            }
            out.push((q, w));
        }
    }
    Some(out)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A plane facing the camera, pixels 0.1 apart, one material; `step` changes one pixel.
    fn plane(step: impl Fn(u32, u32, &mut Surface)) -> impl Fn(u32, u32) -> Option<Surface> {
        move |x, y| {
            let mut s = Surface {
                point: [0.1 * x as f32, 0.1 * y as f32, 5.0],
                normal: [0.0, 0.0, -1.0],
                material: 3,
            };
            step(x, y, &mut s);
            Some(s)
        }
    }

    fn all(_: u32, _: u32) -> bool {
        true
    }

    #[test]
    fn on_a_flat_patch_every_pixel_blends_with_weights_summing_to_one() {
        let at = plane(|_, _, _| {});
        for (y, x) in (0..9).flat_map(|y| (0..9).map(move |x| (y, x))) {
            let w = lattice_weights((x, y), (9, 9), &at, &all, 0.5).expect("coherent");
            let n = 1 << (x % 2 + y % 2);
            assert_eq!(w.len(), n, "({x}, {y})");
            assert!((w.iter().map(|e| e.1).sum::<f32>() - 1.0).abs() < 1e-6);
            assert!(w.iter().all(|((qx, qy), _)| qx % 2 == 0 && qy % 2 == 0));
        }
        // A lattice pixel is its own gather.
        assert_eq!(
            lattice_weights((4, 6), (9, 9), &at, &all, 0.5),
            Some(vec![((4, 6), 1.0)])
        );
    }

    /// The plane with columns from `col` on 1 unit farther, and the columns of row 2 that
    /// gather per pixel there.
    fn per_pixel_at_step(col: u32) -> Vec<u32> {
        let at = plane(move |x, _, s| {
            if x >= col {
                s.point[2] += 1.0;
            }
        });
        (0..9)
            .filter(|&x| lattice_weights((x, 2), (9, 9), &at, &all, 0.5).is_none())
            .collect()
    }

    #[test]
    fn a_depth_step_gathers_per_pixel_at_the_step_only() {
        // A step before column 5: only pixel 5, blended from lattice columns 4 (near) and 6
        // (far), straddles it; 3 blends 2 and 4, both near, 7 blends 6 and 8, both far.
        assert_eq!(
            per_pixel_at_step(5),
            vec![5],
            "the pixels whose lattice neighbours straddle the step"
        );
        // A step before lattice column 4: now pixel 3 straddles it (2 near, 4 far).
        assert_eq!(per_pixel_at_step(4), vec![3]);
        // The same along y.
        let at_y = plane(|_, y, s| {
            if y >= 5 {
                s.point[2] += 1.0;
            }
        });
        assert!(lattice_weights((2, 5), (9, 9), &at_y, &all, 0.5).is_none());
        assert!(lattice_weights((2, 4), (9, 9), &at_y, &all, 0.5).is_some());
    }

    #[test]
    fn a_crease_and_a_material_edge_gather_per_pixel() {
        let crease = plane(|x, _, s| {
            if x >= 4 {
                s.normal = [0.6, 0.0, -0.8];
            }
        });
        assert!(lattice_weights((3, 0), (9, 9), &crease, &all, 0.5).is_none());
        assert!(lattice_weights((1, 0), (9, 9), &crease, &all, 0.5).is_some());
        let materials = plane(|x, _, s| s.material = if x >= 4 { 4 } else { 3 });
        assert!(lattice_weights((3, 0), (9, 9), &materials, &all, 0.5).is_none());
        assert!(lattice_weights((5, 0), (9, 9), &materials, &all, 0.5).is_some());
    }

    #[test]
    fn edges_background_and_ungathered_points_gather_per_pixel() {
        let at = plane(|_, _, _| {});
        // Width 8: column 7 would need lattice column 8, outside the frame.
        assert!(lattice_weights((7, 0), (8, 8), &at, &all, 0.5).is_none());
        assert!(lattice_weights((6, 0), (8, 8), &at, &all, 0.5).is_some());
        // 1×1: the pixel is its own lattice point.
        assert_eq!(
            lattice_weights((0, 0), (1, 1), &at, &all, 0.5),
            Some(vec![((0, 0), 1.0)])
        );
        let hole = |x: u32, y: u32| (x, y) != (2, 2);
        assert!(lattice_weights((3, 3), (9, 9), &at, &hole, 0.5).is_none());
        let background = |x: u32, y: u32| if x >= 4 { None } else { at(x, y) };
        assert!(lattice_weights((3, 0), (9, 9), &background, &all, 0.5).is_none());
        // A reach below the lattice spacing: nothing is close enough to blend.
        assert!(lattice_weights((1, 0), (9, 9), &at, &all, 0.05).is_none());
    }
}
