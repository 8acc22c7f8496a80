//! Quality knobs, travelling as one struct from a preset, the protocol's `settings` message or
//! `fovea render` flags into the frame's uniforms.

use serde::{Deserialize, Serialize};

use crate::optics::acuity::ProbabilityForm;

/// How a pixel's sampling probability becomes a yes/no.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Noise {
    /// Against the WSE blue-noise rank map: every density is a well-spread subset.
    Blue,
    /// Against a per-pixel hash: clumps and holes, kept for comparison.
    White,
}

/// How unshaded pixels are filled.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Reconstruction {
    /// The nearest shaded sample's colour (Voronoi cells from jump flooding).
    Nearest,
    /// Windowed approximate Sibson natural-neighbour interpolation over the JFA result.
    Sibson,
}

/// Foveated sampling knobs (thesis eqs. 2–4). With `enabled: false` every pixel is shaded.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Foveation {
    pub enabled: bool,
    /// MAR slope m, degrees of MAR per degree of eccentricity.
    pub mar_slope: f32,
    /// MAR at the fovea w0, degrees.
    pub mar_w0_deg: f32,
    /// Minimum sampling probability ξ: bounds the largest hole reconstruction must fill.
    pub min_probability: f32,
    pub probability: ProbabilityForm,
    /// Raise the probability at albedo and normal edges (3×3 Sobel, albedo in CIE-Lab).
    pub saliency: bool,
    /// Raise the probability where the image moves.
    pub motion: bool,
    pub noise: Noise,
    /// Reuse last frame's colour where the eq. 4 depth test passes.
    pub reprojection: bool,
    /// Frames a reused colour may age before the pixel counts as a miss.
    pub max_history_age: u32,
    pub reconstruction: Reconstruction,
    /// Largest Sibson window half-size in pixels; 0 derives it from ξ as ⌈1/√ξ⌉ (one
    /// guaranteed sample per window), capped at 16.
    pub sibson_window: u32,
    /// Shade a dense list of the sampled pixels (stream compaction) instead of masking a
    /// full-frame dispatch.
    pub compaction: bool,
}

impl Foveation {
    pub const OFF: Foveation = Foveation {
        enabled: false,
        mar_slope: 0.022,
        mar_w0_deg: 1.0 / 48.0,
        min_probability: 0.05,
        probability: ProbabilityForm::Density,
        saliency: true,
        motion: true,
        noise: Noise::Blue,
        reprojection: true,
        max_history_age: 8,
        reconstruction: Reconstruction::Sibson,
        sibson_window: 0,
        compaction: true,
    };

    /// Jump sizes of the JFA passes for a frame (fewer when ξ bounds the holes). The count
    /// keeps the parity of the full list so the result lands in the same texture.
    pub fn jfa_steps(&self, width: u32, height: u32, min_xi: f32) -> Vec<u32> {
        use super::reconstruct::{jfa_steps, jfa_steps_within, max_gap_for};
        let full = jfa_steps(width, height);
        let mut steps =
            jfa_steps_within(width, height, max_gap_for(self.min_probability.max(min_xi)));
        if steps.len() % 2 != full.len() % 2 {
            steps.push(1);
        }
        steps
    }

    /// The Sibson window bound actually used.
    pub fn sibson_max_window(&self) -> u32 {
        if self.sibson_window > 0 {
            return self.sibson_window.min(32);
        }
        let xi = self.min_probability.max(1.0 / 256.0);
        ((1.0 / xi.sqrt()).ceil() as u32).clamp(1, 16)
    }
}

/// The translucency ladder, cheapest first; every rung takes the same physical inputs.
#[derive(Debug, Clone, Copy, PartialEq, Eq, PartialOrd, Ord, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Rung {
    /// The dipole's total diffuse reflectance as an opaque BRDF albedo.
    Opaque,
    /// The same with normals blurred over the subsurface reach (seed 001 #6).
    NormalBlur,
    /// Irradiance blurred in screen space by the dipole profile.
    Screen,
    /// The dipole over a cut through the light-space photon pyramid (seed 000).
    Hierarchical,
    /// The dipole over every photon: the model's reference.
    BruteForce,
}

impl Rung {
    pub const ALL: [Rung; 5] = [
        Rung::Opaque,
        Rung::NormalBlur,
        Rung::Screen,
        Rung::Hierarchical,
        Rung::BruteForce,
    ];
}

#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Translucency {
    pub rung: Rung,
    /// The finest pyramid level a cluster may come from (0: single photons).
    pub cut_level: u32,
    /// A cluster is used whole when its extent is below ε × its distance.
    pub cut_epsilon: f32,
}

impl Translucency {
    pub const DEFAULT: Translucency = Translucency {
        rung: Rung::Hierarchical,
        cut_level: 0,
        cut_epsilon: 0.5,
    };
}

/// Overlays drawn over the frame for people looking at how it was made.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Overlay {
    #[default]
    None,
    /// Shaded pixels green, reused (reprojected) pixels blue, reconstructed ones as they are.
    Samples,
    /// The sampling probability as a heat map.
    Probability,
}

/// Everything a session can tune.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Settings {
    pub preset: String,
    pub foveation: Foveation,
    pub translucency: Translucency,
    /// Blur the frame by the eye's depth of field for the current pupil and gaze depth.
    pub dof: bool,
    pub overlay: Overlay,
    /// Gaze prediction (a session knob; the renderer ignores it).
    pub prediction: bool,
    /// Prediction horizon in ms; 0 uses the session's measured gaze-to-frame latency.
    pub prediction_horizon_ms: f32,
    /// In scenes with radiosity, add its interreflected light to the direct light (off: area
    /// lights' direct light only, for comparison).
    #[serde(default = "yes")]
    pub indirect: bool,
}

fn yes() -> bool {
    true
}

/// Named presets, cheapest last. `full` shades every pixel with the frame's shading; `reference`
/// shades every pixel with the most accurate shading (the ground truth errors are measured
/// against).
pub const PRESETS: &[&str] = &["reference", "full", "quality", "balanced", "fast"];

impl Settings {
    pub fn preset(name: &str) -> Option<Settings> {
        let on = Foveation {
            enabled: true,
            ..Foveation::OFF
        };
        let foveation = match name {
            "reference" | "full" => Foveation::OFF,
            "quality" => Foveation {
                probability: ProbabilityForm::Linear,
                min_probability: 0.1,
                ..on
            },
            "balanced" => Foveation {
                min_probability: 0.05,
                ..on
            },
            "fast" => Foveation {
                mar_slope: 0.034,
                min_probability: 0.02,
                reconstruction: Reconstruction::Nearest,
                ..on
            },
            _ => return None,
        };
        let translucency = match name {
            "reference" => Translucency {
                rung: Rung::BruteForce,
                ..Translucency::DEFAULT
            },
            "fast" => Translucency {
                cut_level: 1,
                cut_epsilon: 1.0,
                ..Translucency::DEFAULT
            },
            _ => Translucency::DEFAULT,
        };
        Some(Settings {
            preset: name.to_string(),
            foveation,
            translucency,
            dof: false,
            overlay: Overlay::None,
            prediction: false,
            prediction_horizon_ms: 0.0,
            indirect: true,
        })
    }
}

impl Settings {
    /// Applies a protocol `settings` message: the preset first (if any), then single knobs.
    /// Returns the preset name back as an error if it does not exist.
    pub fn apply(&mut self, patch: &crate::protocol::SettingsPatch) -> Result<(), String> {
        if let Some(name) = &patch.preset {
            let (prediction, horizon) = (self.prediction, self.prediction_horizon_ms);
            *self = Settings::preset(name).ok_or_else(|| name.clone())?;
            // Prediction is about the viewer's eye, not image quality: presets keep it.
            self.prediction = prediction;
            self.prediction_horizon_ms = horizon;
        }
        let before = (self.foveation, self.translucency);
        let t = &mut self.translucency;
        if let Some(v) = patch.translucency {
            t.rung = v;
        }
        if let Some(v) = patch.cut_level {
            t.cut_level = v;
        }
        if let Some(v) = patch.cut_epsilon {
            t.cut_epsilon = v as f32;
        }
        let f = &mut self.foveation;
        if let Some(v) = patch.foveation {
            f.enabled = v;
        }
        if let Some(v) = patch.mar_slope {
            f.mar_slope = v as f32;
        }
        if let Some(v) = patch.mar_w0_deg {
            f.mar_w0_deg = v as f32;
        }
        if let Some(v) = patch.min_probability {
            f.min_probability = v as f32;
        }
        if let Some(v) = patch.probability {
            f.probability = v;
        }
        if let Some(v) = patch.saliency {
            f.saliency = v;
        }
        if let Some(v) = patch.motion {
            f.motion = v;
        }
        if let Some(v) = patch.noise {
            f.noise = v;
        }
        if let Some(v) = patch.reprojection {
            f.reprojection = v;
        }
        if let Some(v) = patch.max_history_age {
            f.max_history_age = v;
        }
        if let Some(v) = patch.reconstruction {
            f.reconstruction = v;
        }
        if let Some(v) = patch.sibson_window {
            f.sibson_window = v;
        }
        if let Some(v) = patch.compaction {
            f.compaction = v;
        }
        if let Some(v) = patch.dof {
            self.dof = v;
        }
        if let Some(v) = patch.overlay {
            self.overlay = v;
        }
        if let Some(v) = patch.indirect {
            self.indirect = v;
        }
        if let Some(v) = patch.prediction {
            self.prediction = v;
        }
        if let Some(v) = patch.prediction_horizon_ms {
            self.prediction_horizon_ms = v as f32;
        }
        // Hand-tuned knobs make this a custom point near the named preset: say so.
        if (self.foveation, self.translucency) != before && !self.preset.ends_with('*') {
            self.preset.push('*');
        }
        Ok(())
    }
}

impl Default for Settings {
    fn default() -> Self {
        Settings::preset("full").expect("full is a preset")
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn every_listed_preset_exists_and_only_those() {
        for p in PRESETS {
            assert_eq!(Settings::preset(p).unwrap().preset, *p);
        }
        assert!(Settings::preset("ultra").is_none());
        assert!(!Settings::preset("full").unwrap().foveation.enabled);
        assert!(Settings::preset("fast").unwrap().foveation.enabled);
    }

    #[test]
    fn sibson_window_follows_xi_and_stays_bounded() {
        let w = |xi: f32| {
            Foveation {
                min_probability: xi,
                ..Foveation::OFF
            }
            .sibson_max_window()
        };
        assert_eq!(w(1.0), 1);
        assert_eq!(w(0.25), 2);
        assert_eq!(w(0.05), 5);
        assert_eq!(w(0.0), 16, "ξ = 0 does not make the window unbounded");
    }
}
