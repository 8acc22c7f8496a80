//! Materials: opaque (Lambertian albedo) or translucent (the dipole's physical inputs, per
//! millimetre), with Jensen et al. 2001's measured media as presets.

use serde::{Deserialize, Serialize};

use crate::optics::dipole::{Dipole, DipoleError};

/// Jensen, Marschner, Levoy & Hanrahan, "A Practical Model for Subsurface Light Transport",
/// SIGGRAPH 2001, Figure 5: reduced scattering σ's and absorption σa in mm⁻¹ (R, G, B),
/// measured with η = 1.3.
pub const JENSEN_2001: &[(&str, [f64; 3], [f64; 3])] = &[
    ("apple", [2.29, 2.39, 1.97], [0.0030, 0.0034, 0.046]),
    ("chicken1", [0.15, 0.21, 0.38], [0.015, 0.077, 0.19]),
    ("chicken2", [0.19, 0.25, 0.32], [0.018, 0.088, 0.20]),
    ("cream", [7.38, 5.47, 3.15], [0.0002, 0.0028, 0.0163]),
    ("ketchup", [0.18, 0.07, 0.03], [0.061, 0.97, 1.45]),
    ("marble", [2.19, 2.62, 3.00], [0.0021, 0.0041, 0.0071]),
    ("potato", [0.68, 0.70, 0.55], [0.0024, 0.0090, 0.12]),
    ("skimmilk", [0.70, 1.22, 1.90], [0.0014, 0.0025, 0.0142]),
    ("skin1", [0.74, 0.88, 1.01], [0.032, 0.17, 0.48]),
    ("skin2", [1.09, 1.59, 1.79], [0.013, 0.070, 0.145]),
    ("wholemilk", [2.55, 3.21, 3.77], [0.0011, 0.0024, 0.014]),
];

/// The share of re-emitted light that defines a material's reach (see `Material::reach_mm`).
pub const REACH_FRACTION: f64 = 0.9;

/// The index of refraction Jensen et al. measured with.
pub const JENSEN_ETA: f64 = 1.3;

/// A material as written in a scene file.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(tag = "kind", rename_all = "snake_case", deny_unknown_fields)]
pub enum MaterialSpec {
    Opaque {
        /// Linear base colour, each channel in [0, 1]: the diffuse reflectance of a
        /// dielectric, the specular colour of a metal.
        albedo: [f64; 3],
        #[serde(flatten)]
        surface: SurfaceSpec,
    },
    Translucent {
        /// A name from `JENSEN_2001`; explicit coefficients below override it.
        #[serde(default, skip_serializing_if = "Option::is_none")]
        preset: Option<String>,
        /// Reduced scattering coefficient σ's, mm⁻¹, RGB.
        #[serde(default, skip_serializing_if = "Option::is_none")]
        sigma_s_prime: Option<[f64; 3]>,
        /// Absorption coefficient σa, mm⁻¹, RGB.
        #[serde(default, skip_serializing_if = "Option::is_none")]
        sigma_a: Option<[f64; 3]>,
        /// Relative index of refraction η (default 1.3).
        #[serde(default, skip_serializing_if = "Option::is_none")]
        eta: Option<f64>,
        #[serde(flatten)]
        surface: SurfaceSpec,
    },
    /// An area light: a surface that emits diffusely and reflects nothing.
    Emitter {
        /// Exitance in the light's units (1 is as bright as a white surface facing a unit
        /// light), linear RGB, each ≥ 0.
        emission: [f64; 3],
    },
}

/// The interface of a surface: its microfacet roughness, how metallic it is, whether both
/// faces show. Omitted fields take the defaults below.
#[derive(Debug, Clone, Copy, PartialEq, Default, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct SurfaceSpec {
    /// Perceptual roughness r in [0, 1] (GGX α = r²); default 0.5 (0.3 for translucent).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub roughness: Option<f64>,
    /// 0 dielectric … 1 metal; default 0. Translucent materials are dielectric.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub metallic: Option<f64>,
    /// Index of refraction of an opaque dielectric's coating, for its F0 (default 1.5).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub ior: Option<f64>,
    /// Shade back faces too (open meshes, leaves); default false (back faces are culled).
    #[serde(default, skip_serializing_if = "std::ops::Not::not")]
    pub double_sided: bool,
}

/// A validated surface (see `SurfaceSpec`).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Surface {
    pub roughness: f64,
    pub metallic: f64,
    /// Normal-incidence specular reflectance per channel (Schlick's F0).
    pub f0: [f64; 3],
    /// F0 of the dielectric part (from the index of refraction), before metal mixes in.
    pub dielectric_f0: f64,
    /// The lobe's directional-albedo table for this roughness (`optics::specular`), made once
    /// at load: the GPU upload and the CPU reference both read it.
    pub lobe: [[f64; 2]; crate::optics::specular::ALBEDO_TABLE],
    pub double_sided: bool,
}

impl SurfaceSpec {
    fn validate(
        &self,
        default_roughness: f64,
        base: [f64; 3],
        eta: Option<f64>,
    ) -> Result<Surface, String> {
        let roughness = self.roughness.unwrap_or(default_roughness);
        let metallic = self.metallic.unwrap_or(0.0);
        if !(0.0..=1.0).contains(&roughness) || !(0.0..=1.0).contains(&metallic) {
            return Err(format!(
                "roughness {roughness} and metallic {metallic} must lie in [0, 1]"
            ));
        }
        let ior = eta.or(self.ior).unwrap_or(1.5);
        if !(1.0..=3.0).contains(&ior) {
            return Err(format!("ior {ior} must lie in [1, 3]"));
        }
        let dielectric = crate::optics::specular::f0_of_ior(ior);
        let f0 = [0, 1, 2].map(|c| dielectric + (base[c] - dielectric) * metallic);
        Ok(Surface {
            roughness,
            metallic,
            f0,
            dielectric_f0: dielectric,
            lobe: crate::optics::specular::directional_albedo_table(
                crate::optics::specular::alpha(roughness),
            ),
            double_sided: self.double_sided,
        })
    }
}

/// A validated material, ready for shading.
#[derive(Debug, Clone, PartialEq)]
pub enum Material {
    Opaque {
        albedo: [f64; 3],
        surface: Surface,
    },
    Translucent {
        sigma_s_prime: [f64; 3],
        sigma_a: [f64; 3],
        eta: f64,
        dipole: [Dipole; 3],
        surface: Surface,
    },
    Emitter {
        emission: [f64; 3],
    },
}

impl Material {
    pub fn from_spec(spec: &MaterialSpec) -> Result<Material, String> {
        match spec {
            MaterialSpec::Opaque { albedo, surface } => {
                if albedo.iter().any(|a| !(0.0..=1.0).contains(a)) {
                    return Err(format!("albedo {albedo:?} must lie in [0, 1]"));
                }
                Ok(Material::Opaque {
                    albedo: *albedo,
                    surface: surface.validate(0.5, *albedo, None)?,
                })
            }
            MaterialSpec::Emitter { emission } => {
                if emission.iter().any(|e| !(e.is_finite() && *e >= 0.0)) {
                    return Err(format!("emission {emission:?} must be finite and ≥ 0"));
                }
                Ok(Material::Emitter {
                    emission: *emission,
                })
            }
            MaterialSpec::Translucent {
                preset,
                sigma_s_prime,
                sigma_a,
                eta,
                surface,
            } => {
                if surface.metallic.is_some_and(|m| m != 0.0) {
                    return Err("a translucent material cannot be metallic".into());
                }
                let base = match preset {
                    Some(name) => {
                        let (_, s, a) =
                            JENSEN_2001
                                .iter()
                                .find(|(n, _, _)| n == name)
                                .ok_or_else(|| {
                                    let names: Vec<&str> =
                                        JENSEN_2001.iter().map(|(n, _, _)| *n).collect();
                                    format!(
                                        "unknown medium {name:?}; measured presets: {}",
                                        names.join(", ")
                                    )
                                })?;
                        Some((*s, *a))
                    }
                    None => None,
                };
                let s = sigma_s_prime
                    .or(base.map(|b| b.0))
                    .ok_or("a translucent material needs a preset or sigma_s_prime")?;
                let a = sigma_a
                    .or(base.map(|b| b.1))
                    .ok_or("a translucent material needs a preset or sigma_a")?;
                let eta = eta.unwrap_or(JENSEN_ETA);
                let surface = surface.validate(0.3, [0.0; 3], Some(eta))?;
                let mut dipole = Vec::with_capacity(3);
                for c in 0..3 {
                    dipole.push(Dipole::new(s[c], a[c], eta).map_err(|e: DipoleError| {
                        format!("channel {}: {e}", ["R", "G", "B"][c])
                    })?);
                }
                Ok(Material::Translucent {
                    sigma_s_prime: s,
                    sigma_a: a,
                    eta,
                    dipole: [dipole[0], dipole[1], dipole[2]],
                    surface,
                })
            }
        }
    }

    pub fn is_translucent(&self) -> bool {
        matches!(self, Material::Translucent { .. })
    }

    /// The colour the material shows under even light: its albedo, or for a translucent medium
    /// the dipole's total diffuse reflectance (what every cheaper rung shades with).
    pub fn albedo(&self) -> [f64; 3] {
        match self {
            Material::Opaque { albedo, .. } => *albedo,
            Material::Translucent { dipole, .. } => dipole.map(|d| d.total_reflectance()),
            Material::Emitter { .. } => [0.0; 3],
        }
    }

    /// The surface's interface; `None` for emitters, which reflect nothing.
    pub fn surface(&self) -> Option<&Surface> {
        match self {
            Material::Opaque { surface, .. } | Material::Translucent { surface, .. } => {
                Some(surface)
            }
            Material::Emitter { .. } => None,
        }
    }

    /// Emitted exitance (zero but for emitters).
    pub fn emission(&self) -> [f64; 3] {
        match self {
            Material::Emitter { emission } => *emission,
            _ => [0.0; 3],
        }
    }

    /// How far (mm) light spreads under the surface: the radius through which 90% of the light
    /// that comes back out leaves, the largest over the channels; 0 for opaque materials.
    pub fn reach_mm(&self) -> f64 {
        match self {
            Material::Opaque { .. } | Material::Emitter { .. } => 0.0,
            Material::Translucent { dipole, .. } => dipole
                .iter()
                .map(|d| d.reach(REACH_FRACTION))
                .fold(0.0, f64::max),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn every_measured_medium_is_a_valid_dipole_with_a_plausible_colour() {
        for (name, _, _) in JENSEN_2001 {
            let spec = MaterialSpec::Translucent {
                preset: Some(name.to_string()),
                sigma_s_prime: None,
                sigma_a: None,
                eta: None,
                surface: Default::default(),
            };
            let m = Material::from_spec(&spec).unwrap();
            for rd in m.albedo() {
                assert!((0.0..1.0).contains(&rd), "{name}: {rd}");
            }
            assert!(m.reach_mm() > 0.1, "{name}: reach {}", m.reach_mm());
        }
    }

    #[test]
    fn marble_is_white_ketchup_is_red_and_cream_spreads_less_than_marble() {
        let get = |n: &str| {
            Material::from_spec(&MaterialSpec::Translucent {
                preset: Some(n.into()),
                sigma_s_prime: None,
                sigma_a: None,
                eta: None,
                surface: Default::default(),
            })
            .unwrap()
        };
        let marble = get("marble").albedo();
        assert!(marble.iter().all(|c| *c > 0.8), "{marble:?}");
        let ketchup = get("ketchup").albedo();
        assert!(
            ketchup[0] > 3.0 * ketchup[1] && ketchup[0] > 3.0 * ketchup[2],
            "{ketchup:?}"
        );
        assert!(
            get("marble").reach_mm() > 1.0 && get("cream").reach_mm() < get("marble").reach_mm()
        );
    }

    #[test]
    fn bad_media_are_rejected_at_load_with_the_reason() {
        let t = |s: [f64; 3], a: [f64; 3]| {
            Material::from_spec(&MaterialSpec::Translucent {
                preset: None,
                sigma_s_prime: Some(s),
                sigma_a: Some(a),
                eta: None,
                surface: Default::default(),
            })
        };
        assert!(t([0.0; 3], [0.0; 3])
            .unwrap_err()
            .contains("neither scatters nor absorbs"));
        assert!(t([1.0, 1.0, 0.0], [0.01, 0.01, 0.5])
            .unwrap_err()
            .contains("channel B"));
        let unknown = MaterialSpec::Translucent {
            preset: Some("jade".into()),
            sigma_s_prime: None,
            sigma_a: None,
            eta: None,
            surface: Default::default(),
        };
        assert!(Material::from_spec(&unknown)
            .unwrap_err()
            .contains("marble"));
    }
}
