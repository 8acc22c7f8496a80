//! Structural similarity (Wang, Bovik, Sheikh & Simoncelli 2004) on luma, with the paper's
//! 11×11 Gaussian window (σ = 1.5) and constants K1 = 0.01, K2 = 0.03, L = 255. Windows are
//! clipped at the frame edge (renormalised), so every pixel has a value.

const RADIUS: i32 = 5;
const SIGMA: f64 = 1.5;
const C1: f64 = (0.01 * 255.0) * (0.01 * 255.0);
const C2: f64 = (0.03 * 255.0) * (0.03 * 255.0);

fn luma(px: &[u8]) -> f64 {
    0.299 * f64::from(px[0]) + 0.587 * f64::from(px[1]) + 0.114 * f64::from(px[2])
}

/// Per-pixel SSIM of two RGBA8 images; 1 where they are locally identical.
pub fn ssim_map(reference: &[u8], test: &[u8], width: u32, height: u32) -> Vec<f64> {
    let (w, h) = (width as i32, height as i32);
    let x: Vec<f64> = reference.chunks_exact(4).map(luma).collect();
    let y: Vec<f64> = test.chunks_exact(4).map(luma).collect();
    let kernel: Vec<f64> = (-RADIUS..=RADIUS)
        .map(|i| (-(f64::from(i * i)) / (2.0 * SIGMA * SIGMA)).exp())
        .collect();
    // Separable Gaussian moments: blur x, y, x², y², xy horizontally then vertically.
    let fields: [Vec<f64>; 5] = [
        x.clone(),
        y.clone(),
        x.iter().map(|v| v * v).collect(),
        y.iter().map(|v| v * v).collect(),
        x.iter().zip(&y).map(|(a, b)| a * b).collect(),
    ];
    let blur = |f: &[f64]| -> Vec<f64> {
        let pass = |f: &[f64], dx: i32, dy: i32| -> Vec<f64> {
            (0..w * h)
                .map(|k| {
                    let (px, py) = (k % w, k / w);
                    let (mut s, mut ws) = (0.0, 0.0);
                    for (i, kw) in (-RADIUS..=RADIUS).zip(&kernel) {
                        let (qx, qy) = (px + i * dx, py + i * dy);
                        if qx >= 0 && qy >= 0 && qx < w && qy < h {
                            s += kw * f[(qy * w + qx) as usize];
                            ws += kw;
                        }
                    }
                    s / ws
                })
                .collect()
        };
        pass(&pass(f, 1, 0), 0, 1)
    };
    let [mx, my, mxx, myy, mxy] = fields.map(|f| blur(&f));
    (0..(w * h) as usize)
        .map(|k| {
            let (ux, uy) = (mx[k], my[k]);
            let vx = (mxx[k] - ux * ux).max(0.0);
            let vy = (myy[k] - uy * uy).max(0.0);
            let cov = mxy[k] - ux * uy;
            ((2.0 * ux * uy + C1) * (2.0 * cov + C2)) / ((ux * ux + uy * uy + C1) * (vx + vy + C2))
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    fn grey(w: u32, h: u32, v: u8) -> Vec<u8> {
        (0..w * h).flat_map(|_| [v, v, v, 255]).collect()
    }

    #[test]
    fn identical_images_have_ssim_one() {
        let img: Vec<u8> = (0..32 * 24)
            .flat_map(|k| [(k * 7 % 256) as u8, (k % 200) as u8, 9, 255])
            .collect();
        assert!(ssim_map(&img, &img, 32, 24)
            .iter()
            .all(|s| (s - 1.0).abs() < 1e-12));
    }

    #[test]
    fn a_brightness_offset_on_flat_images_matches_the_luminance_term() {
        // Flat images: variances and covariance vanish, so SSIM = (2μxμy + C1)/(μx² + μy² + C1).
        let (a, b) = (grey(16, 16, 100), grey(16, 16, 120));
        let expected = (2.0 * 100.0 * 120.0 + C1) / (100.0f64.powi(2) + 120.0f64.powi(2) + C1);
        for s in ssim_map(&a, &b, 16, 16) {
            assert!((s - expected).abs() < 1e-9, "{s} vs {expected}");
        }
    }

    #[test]
    fn noise_lowers_ssim_more_than_a_small_offset() {
        let base: Vec<u8> = (0..40 * 40)
            .flat_map(|k| {
                let v = (k % 40 * 5) as u8;
                [v, v, v, 255]
            })
            .collect();
        let offset: Vec<u8> = base
            .iter()
            .enumerate()
            .map(|(i, v)| if i % 4 == 3 { *v } else { v.saturating_add(3) })
            .collect();
        let noisy: Vec<u8> = base
            .iter()
            .enumerate()
            .map(|(i, v)| {
                if i % 4 == 3 {
                    *v
                } else if (i / 4 * 2654435761usize) % 7 < 3 {
                    v.saturating_add(25)
                } else {
                    *v
                }
            })
            .collect();
        let mean = |m: Vec<f64>| m.iter().sum::<f64>() / m.len() as f64;
        let (so, sn) = (
            mean(ssim_map(&base, &offset, 40, 40)),
            mean(ssim_map(&base, &noisy, 40, 40)),
        );
        assert!(so > 0.99 && sn < so - 0.1, "offset {so}, noise {sn}");
    }
}
