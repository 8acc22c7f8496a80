//! Peak signal-to-noise ratio on 8-bit sRGB (RGB channels; alpha ignored).

/// Identical images have infinite PSNR; reports cap it here so they stay finite numbers.
pub const PSNR_CAP_DB: f64 = 100.0;

/// PSNR in dB with every pixel weighted equally. `f64::INFINITY` for identical images.
pub fn psnr(reference: &[u8], test: &[u8]) -> f64 {
    let weights = vec![1.0; reference.len() / 4];
    psnr_weighted(reference, test, &weights).min(f64::INFINITY)
}

/// PSNR from the weighted mean squared error (`weights` per pixel, any scale). Returns
/// `f64::INFINITY` when the weighted error is zero (including when every weight is zero).
pub fn psnr_weighted(reference: &[u8], test: &[u8], weights: &[f64]) -> f64 {
    let (mut se, mut wsum) = (0.0f64, 0.0f64);
    for ((r, t), w) in reference
        .chunks_exact(4)
        .zip(test.chunks_exact(4))
        .zip(weights)
    {
        let e: f64 = (0..3)
            .map(|c| (f64::from(r[c]) - f64::from(t[c])).powi(2))
            .sum::<f64>()
            / 3.0;
        se += w * e;
        wsum += w;
    }
    if wsum <= 0.0 || se <= 0.0 {
        return f64::INFINITY;
    }
    let mse = se / wsum;
    10.0 * (255.0 * 255.0 / mse).log10()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn identical_images_have_infinite_psnr() {
        let a = vec![7u8; 16 * 4];
        assert_eq!(psnr(&a, &a), f64::INFINITY);
        assert_eq!(psnr_weighted(&a, &a, &[0.0; 16]), f64::INFINITY);
    }

    #[test]
    fn a_uniform_error_of_one_level_gives_48_13_db() {
        let a = vec![100u8; 64 * 4];
        let b: Vec<u8> = a
            .iter()
            .enumerate()
            .map(|(i, v)| if i % 4 == 3 { *v } else { v + 1 })
            .collect();
        // MSE = 1 → 10·log10(255²) = 48.1308 dB.
        assert!((psnr(&a, &b) - 48.1308).abs() < 1e-3);
    }

    #[test]
    fn weights_select_where_the_error_counts() {
        let a = vec![0u8; 2 * 4];
        let mut b = a.clone();
        b[4] = 255; // second pixel, red channel: MSE 255²/3 there
        assert_eq!(psnr_weighted(&a, &b, &[1.0, 0.0]), f64::INFINITY);
        let expected = 10.0 * 3f64.log10();
        assert!((psnr_weighted(&a, &b, &[0.0, 1.0]) - expected).abs() < 1e-9);
    }
}
