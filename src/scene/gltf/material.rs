//! glTF materials as Fovea materials (the reasoning is in `docs/scenes.md`, "glTF materials"):
//! metallic-roughness → opaque GGX + Lambert; transmission, diffuse transmission or volume →
//! a translucent medium whose dipole reflects the base colour, with σa from the volume's
//! attenuation (Beer's law) and η from `KHR_materials_ior`; emissive → an area light.

use crate::optics::dipole::albedo_for_total_reflectance;
use crate::scene::material::SurfaceSpec;
use crate::scene::MaterialSpec;

use crate::scene::TextureImage;

/// glTF lengths are metres; dipole coefficients are per millimetre.
const MM_PER_METRE: f64 = 1000.0;
/// Mean free path given to a translucent material without a finite attenuation distance: a
/// tenth of its stated thickness (optically thick, as the dipole assumes), else 1 mm.
const DEFAULT_MEAN_FREE_PATH_MM: f64 = 1.0;

/// The parts of a glTF material that matter to Fovea, with texture means already folded in.
pub struct GltfMaterial<'a> {
    pub material: gltf::Material<'a>,
    /// Mean of the metallic-roughness texture (G roughness, B metallic), if any.
    pub metallic_roughness_mean: Option<[f32; 4]>,
    /// Mean of the emissive texture, if any.
    pub emissive_mean: Option<[f32; 4]>,
}

pub fn spec_of(g: &GltfMaterial) -> MaterialSpec {
    let m = &g.material;
    let pbr = m.pbr_metallic_roughness();
    let base = pbr.base_color_factor();
    let mr = g.metallic_roughness_mean.unwrap_or([1.0; 4]);
    let roughness = f64::from((pbr.roughness_factor() * mr[1]).clamp(0.0, 1.0));
    let metallic = f64::from((pbr.metallic_factor() * mr[2]).clamp(0.0, 1.0));
    let strength = m.emissive_strength().unwrap_or(1.0);
    let em_tex = g.emissive_mean.unwrap_or([1.0; 4]);
    let emissive: [f64; 3] = std::array::from_fn(|c| {
        f64::from((m.emissive_factor()[c] * strength * em_tex[c]).max(0.0))
    });
    if emissive.iter().any(|e| *e > 0.0) && emissive.iter().all(|e| e.is_finite()) {
        return MaterialSpec::Emitter { emission: emissive };
    }
    let ior = f64::from(m.ior().unwrap_or(1.5)).clamp(1.0, 3.0);
    let albedo = base.map(|b| f64::from(b.clamp(0.0, 1.0)));
    let albedo = [albedo[0], albedo[1], albedo[2]];
    let transmission = m.transmission().map_or(0.0, |t| t.transmission_factor());
    let diffuse_transmission = m
        .extension_value("KHR_materials_diffuse_transmission")
        .and_then(|v| v.get("diffuseTransmissionFactor"))
        .and_then(|v| v.as_f64())
        .unwrap_or(0.0);
    let surface = SurfaceSpec {
        roughness: Some(roughness),
        metallic: None,
        ior: Some(ior),
        double_sided: m.double_sided(),
    };
    let translucent = (transmission > 0.0 || diffuse_transmission > 0.0 || m.volume().is_some())
        && metallic < 0.5;
    if !translucent {
        return MaterialSpec::Opaque {
            albedo,
            surface: SurfaceSpec {
                metallic: Some(metallic),
                ..surface
            },
        };
    }
    let (sigma_s_prime, sigma_a) = medium(albedo, m.volume(), ior);
    MaterialSpec::Translucent {
        preset: None,
        sigma_s_prime: Some(sigma_s_prime),
        sigma_a: Some(sigma_a),
        eta: Some(ior),
        surface: SurfaceSpec {
            ior: None,
            ..surface
        },
    }
}

/// σ's and σa (per mm) for a medium that shows `colour` as its total diffuse reflectance.
fn medium(
    colour: [f64; 3],
    volume: Option<gltf::material::Volume>,
    eta: f64,
) -> ([f64; 3], [f64; 3]) {
    let reduced: [f64; 3] = colour.map(|c| albedo_for_total_reflectance(c.clamp(0.01, 0.95), eta));
    let attenuation = volume.as_ref().and_then(|v| {
        let d = f64::from(v.attenuation_distance()) * MM_PER_METRE;
        let c = v.attenuation_color();
        // Beer's law: after d, a fraction c is left, so σa = −ln c / d.
        let sa: [f64; 3] = std::array::from_fn(|k| -(f64::from(c[k]).clamp(1e-4, 1.0)).ln() / d);
        (d.is_finite() && d > 0.0 && sa.iter().all(|s| *s > 0.0)).then_some(sa)
    });
    match attenuation {
        Some(sa) => {
            let ss = std::array::from_fn(|k| sa[k] * reduced[k] / (1.0 - reduced[k]));
            (ss, sa)
        }
        None => {
            let thickness = volume.map_or(0.0, |v| f64::from(v.thickness_factor()) * MM_PER_METRE);
            let mfp = if thickness > 0.0 {
                thickness / 10.0
            } else {
                DEFAULT_MEAN_FREE_PATH_MM
            };
            let st = 1.0 / mfp;
            (reduced.map(|a| a * st), reduced.map(|a| (1.0 - a) * st))
        }
    }
}

/// The mean of a texture if it decoded (a material whose texture fails keeps its factors).
pub fn mean(t: Option<&TextureImage>, srgb: bool) -> Option<[f32; 4]> {
    t.map(|t| super::texture::mean(t, srgb))
}
