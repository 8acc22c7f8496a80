//! FLIP (Andersson et al. 2020) through the `nv-flip` crate (NVIDIA's reference implementation).

use crate::viewing::Viewing;

/// Pixels per degree of visual angle at the frame centre for this display geometry: FLIP's
/// observer model depends on it.
pub fn pixels_per_degree(v: &Viewing) -> f32 {
    (1.0 / v.pixel_angle_deg()) as f32
}

/// Per-pixel FLIP error in [0, 1] of `test` against `reference` (sRGB RGBA8, same size).
pub fn flip_map(reference: &[u8], test: &[u8], width: u32, height: u32, ppd: f32) -> Vec<f64> {
    let rgb = |img: &[u8]| -> Vec<u8> {
        img.chunks_exact(4)
            .flat_map(|p| [p[0], p[1], p[2]])
            .collect()
    };
    let r = nv_flip::FlipImageRgb8::with_data(width, height, &rgb(reference));
    let t = nv_flip::FlipImageRgb8::with_data(width, height, &rgb(test));
    nv_flip::flip(r, t, ppd)
        .to_vec()
        .into_iter()
        .map(f64::from)
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A 48×32 ramp and the same ramp with +40 red on a 4-pixel checkerboard.
    fn pair() -> (Vec<u8>, Vec<u8>) {
        let (w, h) = (48u32, 32u32);
        let mut r = Vec::new();
        let mut t = Vec::new();
        for y in 0..h {
            for x in 0..w {
                let px = [((x * 5) % 256) as u8, ((y * 7) % 256) as u8, 128, 255];
                r.extend_from_slice(&px);
                let mut q = px;
                if (x / 4 + y / 4) % 2 == 0 {
                    q[0] = q[0].saturating_add(40);
                }
                t.extend_from_slice(&q);
            }
        }
        (r, t)
    }

    #[test]
    fn identical_images_have_zero_flip() {
        let (r, _) = pair();
        assert!(flip_map(&r, &r, 48, 32, 67.0).iter().all(|v| *v == 0.0));
    }

    #[test]
    fn flip_agrees_with_nvidias_python_implementation() {
        // Expected means computed independently with NVIDIA's `flip-evaluator` 1.7 (PyPI):
        // flip.evaluate(ref/255, test/255, "LDR", parameters={"ppd": p}) on the same pair:
        // 0.20989619 at 67 ppd, 0.19390942 at 12.6 ppd.
        let (r, t) = pair();
        for (ppd, expected) in [(67.0f32, 0.209_896_19), (12.6, 0.193_909_42)] {
            let m = flip_map(&r, &t, 48, 32, ppd);
            let mean = m.iter().sum::<f64>() / m.len() as f64;
            assert!(
                (mean - expected).abs() < 1e-4,
                "ppd {ppd}: {mean} vs {expected}"
            );
        }
    }
}
