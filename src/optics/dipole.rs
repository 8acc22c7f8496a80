//! Jensen et al. 2001's dipole diffusion model of multiple scattering (seed 000 eqs. 3–10, with
//! the digest's corrected eq. 4), one colour channel at a time. CPU twin of `dipole_rd` in
//! `shaders/shade.wgsl`.
//!
//! Units: lengths in millimetres, coefficients per millimetre.

/// Why a pair of coefficients cannot be used with the diffusion approximation.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum DipoleError {
    #[error("σ's = {0} and σa = {1} must be finite and non-negative")]
    NotFinite(f64, f64),
    #[error("σ's and σa are both 0: the medium neither scatters nor absorbs (not translucent)")]
    Vacuum,
    #[error("σ's = 0 with σa = {sigma_a}: the medium absorbs without scattering, so nothing diffuses back out; use an opaque material")]
    NoScattering { sigma_a: f64 },
    #[error("η = {0} must be finite and > 0")]
    Eta(f64),
}

/// Diffuse Fresnel reflectance F_dr of a boundary with relative index η: Egan & Hilgeman's fit
/// for η ≥ 1 (the form seed 000 prints), and its companion polynomial in 1/η for η < 1.
pub fn fresnel_diffuse_reflectance(eta: f64) -> f64 {
    if eta >= 1.0 {
        -1.440 / (eta * eta) + 0.710 / eta + 0.668 + 0.0636 * eta
    } else {
        -0.4399 + 0.7099 / eta - 0.3319 / (eta * eta) + 0.0636 / (eta * eta * eta)
    }
}

/// The reduced albedo α' whose dipole reflects `rd` in total at index `eta` (the total
/// depends on α' and η only), by bisection; `rd` is clamped to what α' ∈ [0, 0.9999] can give.
/// Used to turn a colour (a glTF base colour) into scattering coefficients.
pub fn albedo_for_total_reflectance(rd: f64, eta: f64) -> f64 {
    let total = |a: f64| {
        Dipole::new(a, 1.0 - a, eta)
            .map(|d| d.total_reflectance())
            .unwrap_or(0.0)
    };
    let (mut lo, mut hi) = (1e-4, 0.9999);
    for _ in 0..60 {
        let mid = 0.5 * (lo + hi);
        if total(mid) < rd {
            lo = mid;
        } else {
            hi = mid;
        }
    }
    0.5 * (lo + hi)
}

/// The dipole's derived constants for one channel.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Dipole {
    /// Reduced albedo α' = σ's/σ't.
    pub albedo: f64,
    /// Effective transport coefficient σtr = √(3 σa σ't), per mm.
    pub sigma_tr: f64,
    /// Depth of the real source z_r = 1/σ't and height of the virtual one z_v = z_r(1 + 4A/3), mm.
    pub z_r: f64,
    pub z_v: f64,
    /// Boundary term A = (1 + F_dr)/(1 − F_dr).
    pub a: f64,
    pub eta: f64,
}

impl Dipole {
    /// Validates and derives. A medium must scatter (σ's > 0). Where absorption dominates
    /// (σa ≥ σ's, as in Jensen's ketchup at green and blue) diffusion is a poor model but stays
    /// finite and dark (α' < ½), so it is allowed.
    pub fn new(sigma_s_prime: f64, sigma_a: f64, eta: f64) -> Result<Dipole, DipoleError> {
        if !(sigma_s_prime.is_finite() && sigma_a.is_finite())
            || sigma_s_prime < 0.0
            || sigma_a < 0.0
        {
            return Err(DipoleError::NotFinite(sigma_s_prime, sigma_a));
        }
        if sigma_s_prime == 0.0 && sigma_a == 0.0 {
            return Err(DipoleError::Vacuum);
        }
        if sigma_s_prime == 0.0 {
            return Err(DipoleError::NoScattering { sigma_a });
        }
        if !(eta.is_finite() && eta > 0.0) {
            return Err(DipoleError::Eta(eta));
        }
        let sigma_t = sigma_s_prime + sigma_a;
        let fdr = fresnel_diffuse_reflectance(eta);
        // F_dr < 1 for every η > 0 the fits cover; the clamp keeps A finite if a fit overshoots.
        let a = (1.0 + fdr) / (1.0 - fdr).max(1e-6);
        let z_r = 1.0 / sigma_t;
        Ok(Dipole {
            albedo: sigma_s_prime / sigma_t,
            sigma_tr: (3.0 * sigma_a * sigma_t).sqrt(),
            z_r,
            z_v: z_r * (1.0 + 4.0 * a / 3.0),
            a,
            eta,
        })
    }

    /// Diffuse reflectance profile R_d(r) (per mm²), corrected eq. 4:
    /// α'/(4π) [ z_r (σtr d_r + 1) e^{−σtr d_r}/d_r³ + z_v (σtr d_v + 1) e^{−σtr d_v}/d_v³ ].
    /// Finite at r = 0 because d_r ≥ z_r > 0; negative or NaN r counts as 0.
    pub fn rd(&self, r: f64) -> f64 {
        let r = if r.is_nan() { 0.0 } else { r.abs() };
        let term = |z: f64| {
            let d = (r * r + z * z).sqrt();
            z * (self.sigma_tr * d + 1.0) * (-self.sigma_tr * d).exp() / (d * d * d)
        };
        self.albedo / (4.0 * std::f64::consts::PI) * (term(self.z_r) + term(self.z_v))
    }

    /// Total diffuse reflectance ∫ R_d 2πr dr in closed form (Jensen 2001):
    /// (α'/2)(1 + e^{−(4/3)A√(3(1−α'))}) e^{−√(3(1−α'))}.
    pub fn total_reflectance(&self) -> f64 {
        let s = (3.0 * (1.0 - self.albedo)).max(0.0).sqrt();
        0.5 * self.albedo * (1.0 + (-(4.0 / 3.0) * self.a * s).exp()) * (-s).exp()
    }

    /// The light that diffuses back out beyond radius `s` (mm) of the entry point,
    /// ∫_s^∞ R_d 2πr dr, in closed form: (α'/2)[z_r e^{−σtr d_r}/d_r + z_v e^{−σtr d_v}/d_v] with
    /// d = √(s² + z²) (the antiderivative of R_d 2πr is −(α'/2) z e^{−σtr d}/d per source).
    /// At s = 0 this is `total_reflectance`.
    pub fn reflectance_beyond(&self, s: f64) -> f64 {
        let s = if s.is_nan() { 0.0 } else { s.abs() };
        let term = |z: f64| {
            let d = (s * s + z * z).sqrt();
            z * (-self.sigma_tr * d).exp() / d
        };
        0.5 * self.albedo * (term(self.z_r) + term(self.z_v))
    }

    /// What a photon's softened R_d is scaled by so it keeps its energy: evaluating R_d at
    /// √(r² + s²) instead of r returns only the light beyond radius s (`reflectance_beyond`),
    /// so the gain is total / beyond. ≥ 1, finite (beyond(s) > 0 for finite s and σtr).
    /// CPU twin of `softening_gain` in `shaders/shade.wgsl`.
    pub fn softening_gain(&self, s: f64) -> f64 {
        let beyond = self.reflectance_beyond(s);
        if beyond > 0.0 && beyond.is_finite() {
            (self.reflectance_beyond(0.0) / beyond).max(1.0)
        } else {
            1.0
        }
    }

    /// Radius (mm) of the disc around an entry point through which `fraction` of the light
    /// that diffuses back out leaves: how far light spreads under the surface. Integrates
    /// R_d 2πr dr on a logarithmic grid from 1 µm to 10 m.
    pub fn reach(&self, fraction: f64) -> f64 {
        const STEPS: usize = 4000;
        let (lo, hi) = (1e-3f64.ln(), 1e4f64.ln());
        let r_at = |i: usize| (lo + (hi - lo) * i as f64 / STEPS as f64).exp();
        let f = |r: f64| self.rd(r) * 2.0 * std::f64::consts::PI * r;
        let mut cumulative = Vec::with_capacity(STEPS + 1);
        let mut sum = 0.0;
        cumulative.push(0.0);
        for i in 1..=STEPS {
            let (a, b) = (r_at(i - 1), r_at(i));
            sum += 0.5 * (f(a) + f(b)) * (b - a);
            cumulative.push(sum);
        }
        let target = fraction.clamp(0.0, 1.0) * sum;
        let i = cumulative
            .iter()
            .position(|c| *c >= target)
            .unwrap_or(STEPS);
        r_at(i)
    }
}

/// The distance (mm) at which a photon's R_d is evaluated: a photon stands for the light
/// entering a disc of `radius_mm` (its texel footprint), so its distance to a shading point is
/// softened by that radius instead of letting R_d's 1/r³ peak through. CPU twin of
/// `cluster_distance_mm` in `shaders/shade.wgsl`.
pub fn softened_distance(r_mm: f64, radius_mm: f64) -> f64 {
    (r_mm * r_mm + radius_mm * radius_mm).sqrt()
}

/// The softening radius (mm) of one photon (a pyramid leaf): `PHOTON_SOFTENING` times its
/// footprint's. Its texel lands on a surface slanted under the light as an ellipse stretched
/// by 1/cos; the disc of the same area has radius `radius_mm`/√cos. The leaf's extent,
/// 0.7071·texel/cos (mm), carries the stretch, and texel = √π·`radius_mm`, so that radius is
/// √(`radius_mm` · extent / (0.7071·√π)). Without the stretch,
/// light arriving from all around (radiosity) shows the photon rows on slanted surfaces.
/// CPU twin of `leaf_softening` in `shaders/shade.wgsl`.
pub fn leaf_softening(radius_mm: f64, extent_mm: f64) -> f64 {
    PHOTON_SOFTENING
        * (radius_mm * extent_mm / (std::f64::consts::FRAC_1_SQRT_2 * std::f64::consts::PI.sqrt()))
            .sqrt()
            .max(radius_mm)
}

/// R_d is softened over this many photon radii (√π: one texel, the photons' spacing). The sum
/// of a kernel over a lattice ripples at the lattice's frequency by about exp(−2π s/h) for a
/// width s and spacing h: at one radius (s = h/√π) ~3%, which showed as a grid of dots and
/// moiré bands on the default scene's marble; at s = h ~0.2%. The softening gain keeps the
/// energy. CPU twin of `PHOTON_SOFTENING` in `shaders/shade.wgsl`.
pub const PHOTON_SOFTENING: f64 = 1.772_453_850_905_516;

#[cfg(test)]
mod tests {
    use super::*;

    /// ∫_0^∞ R_d(r) 2πr dr by substitution r = t/(1−t) and composite Simpson on [0, 1).
    fn integrate(d: &Dipole) -> f64 {
        let n = 200_000;
        let f = |t: f64| {
            if t >= 1.0 {
                return 0.0;
            }
            let r = t / (1.0 - t);
            d.rd(r) * 2.0 * std::f64::consts::PI * r / ((1.0 - t) * (1.0 - t))
        };
        let h = 1.0 / n as f64;
        let mut s = f(0.0) + f(1.0 - 1e-12);
        for i in 1..n {
            s += f(i as f64 * h) * if i % 2 == 1 { 4.0 } else { 2.0 };
        }
        s * h / 3.0
    }

    #[test]
    fn profile_integrates_to_the_closed_form_total_reflectance() {
        // Marble, skin and whole milk (red channels, Jensen 2001) and extremes of albedo.
        for (s, a) in [
            (2.19, 0.0021),
            (0.74, 0.032),
            (2.55, 0.0011),
            (1.0, 1e-6),
            (1.0, 0.5),
            (50.0, 10.0),
        ] {
            for eta in [1.0, 1.3, 1.5, 0.8] {
                let d = Dipole::new(s, a, eta).unwrap();
                let (num, closed) = (integrate(&d), d.total_reflectance());
                assert!(
                    (num - closed).abs() <= 2e-3 * closed.max(1e-3),
                    "σ's {s} σa {a} η {eta}: ∫ {num} vs {closed}"
                );
            }
        }
    }

    #[test]
    fn profile_is_finite_positive_and_decreasing_at_the_extremes() {
        let cases = [
            (2.19, 0.0021, 1.3),
            (1.0, 0.0, 1.3),
            (1e4, 1.0, 1.3),
            (1.0, 0.999, 1.0),
            (0.01, 1e-9, 0.7),
            (3.0, 0.1, 2.5),
        ];
        for (s, a, eta) in cases {
            let d = Dipole::new(s, a, eta).unwrap();
            let mut prev = f64::INFINITY;
            for i in 0..200 {
                let r = if i == 0 { 0.0 } else { 1e-4 * 1.1f64.powi(i) };
                let v = d.rd(r);
                assert!(v.is_finite() && v >= 0.0, "σ's {s} σa {a}: R_d({r}) = {v}");
                assert!(
                    v <= prev * (1.0 + 1e-12),
                    "σ's {s} σa {a}: R_d rises at r = {r}"
                );
                prev = v;
            }
            assert!(d.rd(f64::NAN).is_finite() && d.rd(-1.0) == d.rd(1.0));
        }
    }

    #[test]
    fn dense_absorbing_media_return_light_closer_to_where_it_entered() {
        let marble = Dipole::new(2.19, 0.0021, 1.3).unwrap().reach(0.9);
        let skin = Dipole::new(0.74, 0.032, 1.3).unwrap().reach(0.9);
        let dense = Dipole::new(100.0, 10.0, 1.3).unwrap().reach(0.9);
        // Nine-tenths of marble's and skin's red light re-emerges within ~6.5 mm (measured
        // 6.38 and 6.61 mm); a dense, absorbing medium returns it within a tenth of a mm.
        assert!(
            marble > 10.0 * dense && skin > 10.0 * dense,
            "marble {marble} skin {skin} dense {dense}"
        );
        assert!(dense < 0.1 && (5.0..8.0).contains(&marble) && (5.0..8.0).contains(&skin));
    }

    #[test]
    fn without_absorption_nothing_is_lost_except_at_the_boundary() {
        let d = Dipole::new(1.0, 0.0, 1.0).unwrap();
        assert_eq!(d.sigma_tr, 0.0);
        assert!(
            (d.total_reflectance() - 1.0).abs() < 1e-12,
            "α' = 1, η = 1: all light comes back"
        );
        // Energy never exceeds the incident light for any albedo and boundary.
        for a in [0.0, 1e-6, 0.01, 0.3] {
            for eta in [0.6, 1.0, 1.3, 2.0] {
                let t = Dipole::new(1.0, a, eta).unwrap().total_reflectance();
                assert!((0.0..=1.0 + 1e-12).contains(&t), "σa {a} η {eta}: {t}");
            }
        }
    }

    #[test]
    fn unusable_media_are_rejected_with_the_reason() {
        assert_eq!(Dipole::new(0.0, 0.0, 1.3), Err(DipoleError::Vacuum));
        assert!(matches!(
            Dipole::new(0.0, 1.0, 1.3),
            Err(DipoleError::NoScattering { .. })
        ));
        assert!(
            Dipole::new(0.07, 0.97, 1.3).unwrap().total_reflectance() < 0.05,
            "ketchup green: dark, finite"
        );
        assert!(matches!(
            Dipole::new(f64::NAN, 1.0, 1.3),
            Err(DipoleError::NotFinite(..))
        ));
        assert!(matches!(
            Dipole::new(1.0, -0.1, 1.3),
            Err(DipoleError::NotFinite(..))
        ));
        assert!(matches!(
            Dipole::new(1.0, 0.1, 0.0),
            Err(DipoleError::Eta(_))
        ));
    }

    #[test]
    fn a_colour_inverts_to_the_albedo_that_reflects_it() {
        for rd in [0.05, 0.3, 0.6, 0.85] {
            for eta in [1.0, 1.3, 1.5] {
                let a = albedo_for_total_reflectance(rd, eta);
                let back = Dipole::new(a, 1.0 - a, eta).unwrap().total_reflectance();
                assert!(
                    (back - rd).abs() < 1e-6,
                    "rd {rd} η {eta}: α' {a} gives {back}"
                );
            }
        }
    }

    #[test]
    fn a_softened_profile_keeps_the_energy_of_the_sharp_one() {
        for (sp, sa) in [(2.19, 0.0021), (0.74, 0.032), (0.18, 0.061), (7.38, 0.0002)] {
            let d = Dipole::new(sp, sa, 1.3).unwrap();
            assert!(
                (d.reflectance_beyond(0.0) - d.total_reflectance()).abs()
                    < 1e-9 * d.total_reflectance().max(1e-12) + 1e-12
            );
            for s in [0.1, 1.0, 3.0] {
                // ∫ R_d(√(r² + s²)) 2πr dr × gain, numerically, against the total.
                let (mut sum, n, top) = (0.0, 200_000, 400.0);
                for i in 0..n {
                    let r = (i as f64 + 0.5) * top / n as f64;
                    sum += d.rd(softened_distance(r, s)) * 2.0 * std::f64::consts::PI * r * top
                        / n as f64;
                }
                let kept = sum * d.softening_gain(s) / d.total_reflectance();
                assert!((kept - 1.0).abs() < 2e-3, "σ's {sp} s {s}: {kept}");
            }
            assert!(d.softening_gain(1e6).is_finite() && d.softening_gain(f64::NAN) == 1.0);
        }
    }

    #[test]
    fn diffuse_fresnel_reflectance_vanishes_at_a_matched_boundary() {
        assert!(
            (fresnel_diffuse_reflectance(1.0) - 0.0016).abs() < 1e-4,
            "η = 1: almost no reflection"
        );
    }

    #[test]
    fn f16_photon_positions_cost_little_accuracy_at_millimetre_scales() {
        // Positions in scene centimetres up to 10 cm, stored as f16: spacing 2⁻⁷ cm at 8–16 cm.
        let d = Dipole::new(2.19, 0.0021, 1.3).unwrap();
        let q = |x: f64| (x * 128.0).round() / 128.0; // worst-case f16 grid at [8, 16)
        for r_cm in [0.1, 0.5, 1.0, 3.0] {
            let exact = d.rd(r_cm * 10.0);
            let rounded = d.rd((q(9.0 + r_cm) - q(9.0)) * 10.0);
            assert!(
                (rounded - exact).abs() <= 0.1 * exact,
                "r = {r_cm} cm: {rounded} vs {exact}"
            );
        }
    }
}
