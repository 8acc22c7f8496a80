//! Saliency for the sampling map (thesis eq. 3): the largest 3×3 Sobel gradient of the albedo,
//! measured in CIE-Lab, and of the normal, each normalised to [0, 1]. CPU twin of `saliency`
//! in `shaders/sampling.wgsl`.

/// ΔE per pixel that counts as fully salient.
pub const ALBEDO_FULL: f32 = 10.0;
/// Normal change (radians, roughly) per pixel that counts as fully salient.
pub const NORMAL_FULL: f32 = 0.25;

fn lab_f(t: f32) -> f32 {
    if t > 0.008856 {
        t.powf(1.0 / 3.0)
    } else {
        7.787 * t + 16.0 / 116.0
    }
}

/// CIE-Lab (D65 white) of a linear sRGB colour.
pub fn to_lab(rgb: [f32; 3]) -> [f32; 3] {
    let dot = |m: [f32; 3]| m[0] * rgb[0] + m[1] * rgb[1] + m[2] * rgb[2];
    let x = dot([0.4124, 0.3576, 0.1805]) / 0.95047;
    let y = dot([0.2126, 0.7152, 0.0722]);
    let z = dot([0.0193, 0.1192, 0.9505]) / 1.08883;
    let (fx, fy, fz) = (lab_f(x), lab_f(y), lab_f(z));
    [116.0 * fy - 16.0, 500.0 * (fx - fy), 200.0 * (fy - fz)]
}

/// Saliency at the centre of a 3×3 neighbourhood (row-major, clamped at the frame edge by the
/// caller). `albedo` is the premultiplied albedo (zero for background), `normal` the unit
/// normal (zero for background), so silhouettes are fully salient.
pub fn saliency(albedo: &[[f32; 3]; 9], normal: &[[f32; 3]; 9]) -> f32 {
    const KX: [f32; 9] = [-1.0, 0.0, 1.0, -2.0, 0.0, 2.0, -1.0, 0.0, 1.0];
    const KY: [f32; 9] = [-1.0, -2.0, -1.0, 0.0, 0.0, 0.0, 1.0, 2.0, 1.0];
    let grad = |values: [[f32; 3]; 9]| -> f32 {
        let mut g = [[0.0f32; 3]; 2];
        for k in 0..9 {
            for c in 0..3 {
                g[0][c] += KX[k] * values[k][c];
                g[1][c] += KY[k] * values[k][c];
            }
        }
        // The Sobel weights sum to 8 across the kernel: /8 is a per-pixel derivative.
        (0..3)
            .map(|c| (g[0][c] * g[0][c] + g[1][c] * g[1][c]).sqrt() / 8.0)
            .fold(0.0, f32::max)
    };
    let lab = albedo.map(to_lab);
    let d_albedo = grad(lab) / ALBEDO_FULL;
    let d_normal = grad(*normal) / NORMAL_FULL;
    d_albedo.max(d_normal).clamp(0.0, 1.0)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn white_is_l100_and_black_is_l0() {
        let w = to_lab([1.0; 3]);
        assert!(
            (w[0] - 100.0).abs() < 0.1 && w[1].abs() < 0.5 && w[2].abs() < 0.5,
            "{w:?}"
        );
        assert_eq!(to_lab([0.0; 3])[0], 0.0);
    }

    #[test]
    fn flat_regions_are_not_salient_and_silhouettes_fully_are() {
        let grey = [[0.5; 3]; 9];
        let up = [[0.0, 1.0, 0.0]; 9];
        assert_eq!(saliency(&grey, &up), 0.0);
        let mut edge_a = grey;
        let mut edge_n = up;
        for k in [2, 5, 8] {
            edge_a[k] = [0.0; 3];
            edge_n[k] = [0.0; 3];
        }
        assert_eq!(saliency(&edge_a, &edge_n), 1.0);
    }
}
