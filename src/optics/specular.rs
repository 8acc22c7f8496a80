//! Microfacet specular reflection in Karis's UE4 form (seed 001 #17): GGX normal distribution,
//! height-correlated Smith visibility, Schlick's Fresnel with F0 from the index of refraction
//! (or the base colour of a metal). CPU twin of `ggx_*` in `shaders/common.wgsl`.
//!
//! Energy: a surface's reflected lobe returns E(μ_o) of the light (its directional albedo, a
//! per-material table of F0·A(μ) + F90·B(μ), `directional_albedo_table`); what enters the
//! diffuse or subsurface part is scaled by (1 − E(μ_i))(1 − E(μ_o)), so diffuse plus specular
//! never reflects more than arrives. For translucent materials this is the rough dielectric
//! interface of Walter et al. 2007 (seed 001 #14) reduced to what the dipole needs: the
//! diffusion approximation forgets the direction light is refracted into, so only the share
//! that crosses the rough boundary, 1 − E(μ_i), matters, and the same roughness sets the
//! reflected lobe and that share.

use std::f64::consts::PI;

/// GGX α below this is clamped: α → 0 is a mirror whose D is a delta, which a point light
/// would show as a single over-bright pixel (and 1/α² overflow in f32).
pub const MIN_ALPHA: f64 = 0.002;
/// μ samples in a material's directional-albedo table (uniform in μ = n·v from 0 to 1).
pub const ALBEDO_TABLE: usize = 16;
/// Strata per axis when integrating a table entry (96² samples: within 0.02 of 512²).
const TABLE_SAMPLES: usize = 96;

/// Schlick's F0 of a dielectric with relative index of refraction `ior`.
pub fn f0_of_ior(ior: f64) -> f64 {
    let r = (ior - 1.0) / (ior + 1.0);
    r * r
}

/// GGX α from perceptual roughness (α = r², clamped to `MIN_ALPHA`).
pub fn alpha(roughness: f64) -> f64 {
    (roughness * roughness).clamp(MIN_ALPHA, 1.0)
}

/// GGX normal distribution D(h) for cos θ_h = `n_h`.
pub fn ggx_d(n_h: f64, alpha: f64) -> f64 {
    let a2 = alpha * alpha;
    let c = n_h.clamp(0.0, 1.0);
    let d = c * c * (a2 - 1.0) + 1.0;
    a2 / (PI * d * d)
}

/// Height-correlated Smith visibility V = G₂ / (4 n·l n·v); finite at grazing angles (both
/// cosines are clamped away from 0, where the product with n·l in the caller vanishes anyway).
pub fn smith_visibility(n_v: f64, n_l: f64, alpha: f64) -> f64 {
    let a2 = alpha * alpha;
    let (v, l) = (n_v.clamp(1e-4, 1.0), n_l.clamp(1e-4, 1.0));
    let gv = l * (v * v * (1.0 - a2) + a2).sqrt();
    let gl = v * (l * l * (1.0 - a2) + a2).sqrt();
    0.5 / (gv + gl)
}

/// Schlick's Fresnel with F90 = min(50 F0, 1): surfaces with F0 → 0 (η → 1) reflect nothing
/// even at grazing angles. `cos` is clamped to [0, 1] (rounding can push v·h past 1).
pub fn schlick(f0: f64, cos: f64) -> f64 {
    let f90 = (50.0 * f0).min(1.0);
    let m = 1.0 - cos.clamp(0.0, 1.0);
    f0 + (f90 - f0) * m.powi(5)
}

/// The specular BRDF × π (our radiance convention: a white Lambertian surface facing a unit
/// light shows 1), for unit vectors given as cosines: n·l, n·v, n·h, v·h.
pub fn specular(f0: f64, alpha: f64, n_l: f64, n_v: f64, n_h: f64, v_h: f64) -> f64 {
    if n_l <= 0.0 || n_v <= 0.0 {
        return 0.0;
    }
    PI * ggx_d(n_h, alpha) * smith_visibility(n_v, n_l, alpha) * schlick(f0, v_h)
}

/// The directional albedo of the specular lobe split as E(μ) = F0·A(μ) + F90·B(μ), at
/// μ = `table_mu(i)`. Integrated by stratified importance sampling of D(h)·(n·h) (n × n strata).
pub fn directional_albedo_table(alpha: f64) -> [[f64; 2]; ALBEDO_TABLE] {
    let mut out = [[0.0; 2]; ALBEDO_TABLE];
    for (i, slot) in out.iter_mut().enumerate() {
        *slot = split_albedo(table_mu(i), alpha, TABLE_SAMPLES);
    }
    out
}

/// The μ the table's entry `i` stands for.
pub fn table_mu(i: usize) -> f64 {
    (i as f64 / (ALBEDO_TABLE - 1) as f64).max(1e-3)
}

/// (A, B) at one μ, `n`² samples.
pub fn split_albedo(mu: f64, alpha: f64, n: usize) -> [f64; 2] {
    let v = [(1.0 - mu * mu).max(0.0).sqrt(), 0.0, mu];
    let a2 = alpha * alpha;
    let (mut a, mut b) = (0.0, 0.0);
    for i in 0..n {
        for j in 0..n {
            let (u1, u2) = ((i as f64 + 0.5) / n as f64, (j as f64 + 0.5) / n as f64);
            // h from D(h)·(n·h): cos²θ = (1 − u)/(1 + (α² − 1)u).
            let cos_t = ((1.0 - u1) / (1.0 + (a2 - 1.0) * u1)).sqrt();
            let sin_t = (1.0 - cos_t * cos_t).max(0.0).sqrt();
            let phi = 2.0 * PI * u2;
            let h = [sin_t * phi.cos(), sin_t * phi.sin(), cos_t];
            let v_h = v[0] * h[0] + v[1] * h[1] + v[2] * h[2];
            let n_l = 2.0 * v_h * h[2] - v[2];
            if n_l <= 0.0 || v_h <= 0.0 {
                continue;
            }
            // f·cos / pdf with pdf = D·(n·h)/(4 v·h): V·4·n_l·v_h/n_h.
            let w = smith_visibility(mu, n_l, alpha) * 4.0 * n_l * v_h / cos_t;
            let fc = (1.0 - v_h).powi(5);
            a += (1.0 - fc) * w;
            b += fc * w;
        }
    }
    let count = (n * n) as f64;
    [a / count, b / count]
}

/// E(μ) for F0 from a table, linearly interpolated (the shader's `lobe_albedo`).
pub fn lobe_albedo(table: &[[f64; 2]; ALBEDO_TABLE], f0: f64, mu: f64) -> f64 {
    let x = mu.clamp(0.0, 1.0) * (ALBEDO_TABLE - 1) as f64;
    let i = (x.floor() as usize).min(ALBEDO_TABLE - 2);
    let t = x - i as f64;
    let ab = |k: usize| f0 * table[k][0] + (50.0 * f0).min(1.0) * table[k][1];
    (ab(i) * (1.0 - t) + ab(i + 1) * t).clamp(0.0, 1.0)
}

/// The table's cosine-weighted hemisphere averages 2∫A(μ)μ dμ and 2∫B(μ)μ dμ (trapezoids on
/// its μ grid): with them F0·A + F90·B is the share of light arriving evenly from every
/// direction that the lobe reflects, so the diffuse part receives 1 − that (`surface`'s
/// diffuse term is not renormalised for it).
pub fn lobe_average_split(table: &[[f64; 2]; ALBEDO_TABLE]) -> [f64; 2] {
    let last = (ALBEDO_TABLE - 1) as f64;
    let mut sum = [0.0; 2];
    for (i, ab) in table.iter().enumerate() {
        let w = if i == 0 || i == ALBEDO_TABLE - 1 {
            0.5
        } else {
            1.0
        };
        let mu = i as f64 / last;
        sum[0] += w * ab[0] * mu;
        sum[1] += w * ab[1] * mu;
    }
    sum.map(|s| 2.0 * s / last)
}

/// F0·A + F90·B with [`lobe_average_split`]'s averages, in [0, 1].
pub fn lobe_average(table: &[[f64; 2]; ALBEDO_TABLE], f0: f64) -> f64 {
    let [a, b] = lobe_average_split(table);
    (f0 * a + (50.0 * f0).min(1.0) * b).clamp(0.0, 1.0)
}

/// Everything a surface reflects towards v from a unit light along l (×π convention): the
/// diffuse part `diffuse` (an albedo, or the dipole's total reflectance) scaled by what crosses
/// the interface both ways, plus the specular lobe. Cosines of unit vectors.
pub fn surface(
    diffuse: f64,
    f0: f64,
    alpha: f64,
    table: &[[f64; 2]; ALBEDO_TABLE],
    n_l: f64,
    n_v: f64,
    n_h: f64,
    v_h: f64,
) -> f64 {
    if n_l <= 0.0 || n_v <= 0.0 {
        return 0.0;
    }
    let cross = (1.0 - lobe_albedo(table, f0, n_l)) * (1.0 - lobe_albedo(table, f0, n_v));
    n_l * (diffuse * cross + specular(f0, alpha, n_l, n_v, n_h, v_h))
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Hemisphere integral of `surface`/π · cos for a fixed view: the fraction of uniform
    /// incident light the surface sends back (white furnace).
    fn furnace(diffuse: f64, f0: f64, roughness: f64, mu_v: f64) -> f64 {
        let alpha = alpha(roughness);
        let table = directional_albedo_table(alpha);
        let v = glam::DVec3::new((1.0 - mu_v * mu_v).sqrt(), 0.0, mu_v);
        let (nt, np) = (400, 200);
        let mut sum = 0.0;
        for i in 0..nt {
            // Uniform in cos θ so each cell has the same solid angle 2π/(nt·np).
            let c = (i as f64 + 0.5) / nt as f64;
            let s = (1.0 - c * c).sqrt();
            for j in 0..np {
                let p = 2.0 * PI * (j as f64 + 0.5) / np as f64;
                let l = glam::DVec3::new(s * p.cos(), s * p.sin(), c);
                let h = (l + v).normalize();
                sum += surface(diffuse, f0, alpha, &table, c, mu_v, h.z, v.dot(h));
            }
        }
        // surface() = π f cos; ∫ f cos dω = Σ surface/π · 2π/(nt np).
        sum * 2.0 / (nt * np) as f64
    }

    #[test]
    fn no_material_reflects_more_than_it_receives() {
        for roughness in [0.0, 0.05, 0.25, 0.5, 0.75, 1.0] {
            for ior in [1.0, 1.3, 1.5, 2.0] {
                for mu in [0.02, 0.3, 0.7, 1.0] {
                    for diffuse in [0.0, 1.0] {
                        let e = furnace(diffuse, f0_of_ior(ior), roughness, mu);
                        assert!(
                            e.is_finite() && e <= 1.02,
                            "r {roughness} η {ior} μ {mu} d {diffuse}: {e}"
                        );
                    }
                }
            }
        }
        // A white metal (F0 = 1) returns most of the light at normal incidence.
        let metal = furnace(0.0, 1.0, 0.5, 1.0);
        assert!(metal > 0.85 && metal <= 1.02, "{metal}");
    }

    #[test]
    fn the_sky_reaches_the_diffuse_part_through_the_lobes_average() {
        // The diffuse part of what the shader gives a uniform sky, ρ(1 − E(μ_o))(1 − E_avg),
        // is the furnace integral of `surface`'s diffuse term (the lobe's E(μ_o) is held to
        // its own integral by the table tests), for any roughness, index and view.
        for roughness in [0.1, 0.5, 1.0] {
            let table = directional_albedo_table(alpha(roughness));
            for ior in [1.0, 1.5, 2.0] {
                let f0 = f0_of_ior(ior);
                let e_avg = lobe_average(&table, f0);
                assert!(
                    (0.0..0.5).contains(&e_avg),
                    "r {roughness} η {ior}: {e_avg}"
                );
                for mu in [0.2, 0.6, 1.0] {
                    let e_o = lobe_albedo(&table, f0, mu);
                    let sky = 0.8 * (1.0 - e_o) * (1.0 - e_avg);
                    let furnace = furnace(0.8, f0, roughness, mu) - furnace(0.0, f0, roughness, mu);
                    assert!(
                        (sky - furnace).abs() < 0.01,
                        "r {roughness} η {ior} μ {mu}: formula {sky}, furnace {furnace}"
                    );
                }
            }
        }
    }

    #[test]
    fn a_white_rough_dielectric_loses_little() {
        // Diffuse 1 + specular: the sum should stay close to 1 (we lose only the
        // multiple-scattering share of the lobe and what (1−E_i) drops).
        let e = furnace(1.0, f0_of_ior(1.5), 0.5, 0.8);
        assert!(e > 0.85, "{e}");
    }

    #[test]
    fn extremes_stay_finite() {
        let t = directional_albedo_table(alpha(0.0));
        for (n_l, n_v, n_h, v_h) in [
            (1e-9, 1.0, 1.0, 1.0),
            (1.0, 1e-9, 1.0, 1.0),
            (1.0, 1.0, 1.0, 1.0 + 1e-6),
            (0.5, 0.5, 1.0, 0.5),
            (0.0, 0.0, 0.0, 0.0),
        ] {
            for alpha in [MIN_ALPHA, 1.0] {
                let s = surface(1.0, 0.04, alpha, &t, n_l, n_v, n_h, v_h);
                assert!(
                    s.is_finite() && s >= 0.0,
                    "{n_l} {n_v} {n_h} {v_h} α {alpha}: {s}"
                );
            }
        }
        assert_eq!(
            schlick(0.0, 0.0),
            0.0,
            "η = 1 reflects nothing, even grazing"
        );
        assert!((schlick(0.04, 1.5) - 0.04).abs() < 1e-12, "cos > 1 clamps");
        assert!(ggx_d(1.0, MIN_ALPHA).is_finite());
    }

    #[test]
    fn the_table_matches_a_finer_integration() {
        for alpha in [MIN_ALPHA, 0.1, 0.5, 1.0] {
            for mu in [0.05, 0.5, 1.0] {
                let [a, b] = split_albedo(mu, alpha, TABLE_SAMPLES);
                let [a2, b2] = split_albedo(mu, alpha, 512);
                assert!(
                    (a - a2).abs() < 0.02 && (b - b2).abs() < 0.02,
                    "α {alpha} μ {mu}: {a} {b} vs {a2} {b2}"
                );
                assert!(a + b <= 1.0 + 1e-3 && a >= 0.0 && b >= 0.0);
            }
        }
    }
}
