//! What a session can tune, typed: a [`Preset`], the [`RenderSettings`] that reach the renderer
//! and the [`SessionSettings`] that stay with the session (gaze prediction). The knobs that
//! patch them are declared once, in [`knobs`], for the protocol, the command line and the docs.
//! A leaf module: it imports nothing from the rest of the crate.

pub mod knobs;

use serde::{Deserialize, Serialize};

pub use knobs::{Knob, KnobError, SettingsPatch, KNOBS};

/// How the MAR becomes a sampling probability.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize, clap::ValueEnum)]
#[serde(rename_all = "snake_case")]
#[value(rename_all = "snake_case")]
pub enum ProbabilityForm {
    /// Thesis eq. 2 with the digest's normalisation: 1 − (w − w_min)/(w_far − w_min), falling
    /// linearly from 1 where the eye resolves a pixel to 0 at the frame's farthest point.
    Linear,
    /// Sample density matched to acuity: (w_min / w)², one sample per resolvable cell.
    Density,
}

/// How a pixel's sampling probability becomes a yes/no.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize, clap::ValueEnum)]
#[serde(rename_all = "snake_case")]
#[value(rename_all = "snake_case")]
pub enum Noise {
    /// Against the WSE blue-noise rank map: every density is a well-spread subset.
    Blue,
    /// Against a per-pixel hash: clumps and holes, kept for comparison.
    White,
}

/// How unshaded pixels are filled.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize, clap::ValueEnum)]
#[serde(rename_all = "snake_case")]
#[value(rename_all = "snake_case")]
pub enum Reconstruction {
    /// The nearest shaded sample's colour (Voronoi cells from jump flooding).
    Nearest,
    /// Windowed approximate Sibson natural-neighbour interpolation over the JFA result.
    Sibson,
    /// Pull-push over a pyramid of first-order moments (seed 000's hierarchical
    /// interpolation), on colour divided by the G-buffer's Lambert prediction; no jump flooding.
    PullPush,
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
    /// An edge asks for S·√p instead of S: samples a pixel apart across it but only one per
    /// resolvable cell (the MAR) along it, since an edge is one-dimensional; p is the acuity
    /// 5° nearer the gaze (`optics::acuity::EDGE_MARGIN_DEG`: where the eye may be), so edges
    /// within 5° are sampled fully. Off: the thesis's eq. 3, where an edge pixel is shaded at
    /// any eccentricity.
    #[serde(default)]
    pub edges_at_mar: bool,
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
        edges_at_mar: false,
        motion: true,
        noise: Noise::Blue,
        reprojection: true,
        max_history_age: 8,
        reconstruction: Reconstruction::Sibson,
        sibson_window: 0,
        compaction: true,
    };

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
#[derive(
    Debug, Clone, Copy, PartialEq, Eq, PartialOrd, Ord, Serialize, Deserialize, clap::ValueEnum,
)]
#[serde(rename_all = "snake_case")]
#[value(rename_all = "snake_case")]
pub enum Rung {
    /// The dipole's total diffuse reflectance as an opaque BRDF albedo.
    Opaque = 0,
    /// The same with normals blurred over the subsurface reach (seed 001 #6).
    NormalBlur = 1,
    /// Irradiance blurred in screen space by the dipole profile.
    Screen = 2,
    /// The dipole over a cut through the light-space photon pyramid (seed 000).
    Hierarchical = 3,
    /// The dipole over every photon: the model's reference.
    BruteForce = 4,
}

impl Rung {
    /// The id the shaders know it by (`RUNG_*`).
    pub fn id(self) -> u32 {
        self as u32
    }

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
    /// On the photon rungs of a frame shaded whole: gather at every other pixel on each axis
    /// and interpolate where the surface is coherent (seed 000's screen-space hierarchy),
    /// gathering per pixel elsewhere.
    #[serde(default)]
    pub coarse_gather: bool,
}

impl Translucency {
    pub const DEFAULT: Translucency = Translucency {
        rung: Rung::Hierarchical,
        cut_level: 0,
        cut_epsilon: 0.5,
        coarse_gather: false,
    };
}

/// Overlays drawn over the frame for people looking at how it was made.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq, Serialize, Deserialize, clap::ValueEnum)]
#[serde(rename_all = "snake_case")]
#[value(rename_all = "snake_case")]
pub enum Overlay {
    #[default]
    None = 0,
    /// Shaded pixels green, reused (reprojected) pixels blue, reconstructed ones as they are.
    Samples = 1,
    /// The sampling probability as a heat map.
    Probability = 2,
}

impl Overlay {
    /// The id the shaders know it by (`OVERLAY_*`).
    pub fn id(self) -> u32 {
        self as u32
    }
}

/// Named starting points, most accurate first.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Serialize, Deserialize, clap::ValueEnum)]
#[serde(rename_all = "snake_case")]
#[value(rename_all = "snake_case")]
pub enum Preset {
    /// Every pixel shaded with the most accurate shading: the ground truth errors are measured
    /// against.
    Reference,
    /// Every pixel shaded with the frame's shading.
    Full,
    /// Foveated, linear probability, ξ = 0.1, pull-push reconstruction.
    Quality,
    /// Foveated, density probability, ξ = 0.05, pull-push reconstruction: the default.
    Balanced,
    /// Foveated, steeper MAR, ξ = 0.02, pull-push reconstruction, a coarser cut.
    Fast,
}

impl Preset {
    pub const ALL: [Preset; 5] = [
        Preset::Reference,
        Preset::Full,
        Preset::Quality,
        Preset::Balanced,
        Preset::Fast,
    ];
    /// What `serve` and `render` start from.
    pub const DEFAULT: Preset = Preset::Balanced;

    pub fn name(self) -> &'static str {
        match self {
            Preset::Reference => "reference",
            Preset::Full => "full",
            Preset::Quality => "quality",
            Preset::Balanced => "balanced",
            Preset::Fast => "fast",
        }
    }

    pub fn from_name(name: &str) -> Option<Preset> {
        Preset::ALL.into_iter().find(|p| p.name() == name)
    }

    /// The names, comma-separated, for messages.
    pub fn names() -> String {
        Preset::ALL.map(Preset::name).join(", ")
    }
}

impl std::fmt::Display for Preset {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(self.name())
    }
}

/// Everything that changes a frame's pixels: what the renderer receives.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct RenderSettings {
    pub foveation: Foveation,
    pub translucency: Translucency,
    /// Blur the frame by the eye's depth of field for the current pupil and gaze depth.
    pub dof: bool,
    pub overlay: Overlay,
    /// In scenes with radiosity, add its interreflected light to the direct light (off: area
    /// lights' direct light only, for comparison). Reports written before the knob existed
    /// read as on.
    #[serde(default = "yes")]
    pub indirect: bool,
    /// The key light casts shadows (shadow map); off for comparison and cost.
    #[serde(default = "yes")]
    pub shadows: bool,
    /// Surfaces reflect specularly (GGX) and translucent ones lose what their interface
    /// reflects; off: Lambert and a boundary that lets all light through.
    #[serde(default = "yes")]
    pub specular: bool,
}

fn yes() -> bool {
    true
}

/// Knobs about the viewer's eye rather than the image; they never reach the renderer.
#[derive(Debug, Clone, Copy, Default, PartialEq, Serialize, Deserialize)]
pub struct SessionSettings {
    /// Gaze prediction.
    pub prediction: bool,
    /// Prediction horizon in ms; 0 uses the session's measured gaze-to-frame latency.
    pub prediction_horizon_ms: f32,
}

/// A preset, and whether single knobs have moved the render settings away from it.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Settings {
    pub preset: Preset,
    /// Hand-tuned knobs made this a custom point near `preset`.
    pub customised: bool,
    pub render: RenderSettings,
    pub session: SessionSettings,
}

impl RenderSettings {
    pub fn of(preset: Preset) -> RenderSettings {
        let on = Foveation {
            enabled: true,
            ..Foveation::OFF
        };
        let foveation = match preset {
            Preset::Reference | Preset::Full => Foveation::OFF,
            // Every foveated preset reconstructs with pull-push (docs/foveation.md, one run of
            // the 14 scene/size groups): against JFA + Sibson, `balanced` was faster on 12 and
            // closer to `full` within 5° of the gaze on 12, `quality` closer to `full` on all 14
            // (FLIP) and faster on 8; against JFA + nearest, `fast` was faster on 13.
            Preset::Quality => Foveation {
                probability: ProbabilityForm::Linear,
                min_probability: 0.1,
                reconstruction: Reconstruction::PullPush,
                ..on
            },
            Preset::Balanced => Foveation {
                min_probability: 0.05,
                reconstruction: Reconstruction::PullPush,
                ..on
            },
            Preset::Fast => Foveation {
                mar_slope: 0.034,
                min_probability: 0.02,
                reconstruction: Reconstruction::PullPush,
                ..on
            },
        };
        let translucency = match preset {
            Preset::Reference => Translucency {
                rung: Rung::BruteForce,
                ..Translucency::DEFAULT
            },
            Preset::Fast => Translucency {
                cut_level: 1,
                cut_epsilon: 1.0,
                ..Translucency::DEFAULT
            },
            _ => Translucency::DEFAULT,
        };
        RenderSettings {
            foveation,
            translucency,
            dof: false,
            overlay: Overlay::None,
            indirect: true,
            shadows: true,
            specular: true,
        }
    }
}

/// A plain frame request shades every pixel: tests and tools opt into foveation.
impl Default for RenderSettings {
    fn default() -> Self {
        RenderSettings::of(Preset::Full)
    }
}

impl Settings {
    pub fn of(preset: Preset) -> Settings {
        Settings {
            preset,
            customised: false,
            render: RenderSettings::of(preset),
            session: SessionSettings::default(),
        }
    }

    /// The preset's name, with `*` when knobs have moved away from it.
    pub fn label(&self) -> String {
        let star = if self.customised { "*" } else { "" };
        format!("{}{star}", self.preset)
    }

    /// Applies a `settings` patch: the preset first (if any), then single knobs. A preset
    /// resets the render settings; session settings (the viewer's eye) are kept.
    pub fn apply(&mut self, patch: &SettingsPatch) -> Result<(), KnobError> {
        patch.validate()?;
        if let Some(name) = &patch.preset {
            let preset =
                Preset::from_name(name).ok_or_else(|| KnobError::UnknownPreset(name.clone()))?;
            *self = Settings {
                session: self.session,
                ..Settings::of(preset)
            };
        }
        let before = self.render.clone();
        patch.set_knobs(self);
        if self.render != before {
            self.customised = true;
        }
        Ok(())
    }
}

impl Default for Settings {
    fn default() -> Self {
        Settings::of(Preset::Full)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn every_preset_round_trips_its_name_and_only_those() {
        for p in Preset::ALL {
            assert_eq!(Preset::from_name(p.name()), Some(p));
            assert_eq!(serde_json::to_value(p).unwrap(), p.name());
        }
        assert!(Preset::from_name("ultra").is_none());
        assert!(!RenderSettings::of(Preset::Full).foveation.enabled);
        assert!(RenderSettings::of(Preset::Fast).foveation.enabled);
    }

    #[test]
    fn a_preset_keeps_session_knobs_and_a_knob_marks_the_settings_customised() {
        let mut s = Settings::of(Preset::Balanced);
        s.session.prediction = true;
        let patch = SettingsPatch {
            preset: Some("fast".into()),
            ..Default::default()
        };
        s.apply(&patch).unwrap();
        assert_eq!(
            (s.preset, s.customised, s.session.prediction),
            (Preset::Fast, false, true)
        );
        let patch = SettingsPatch {
            min_probability: Some(0.3),
            ..Default::default()
        };
        s.apply(&patch).unwrap();
        assert_eq!(s.render.foveation.min_probability, 0.3);
        assert_eq!(s.label(), "fast*");
        let bad = SettingsPatch {
            preset: Some("ultra".into()),
            ..Default::default()
        };
        assert!(matches!(s.apply(&bad), Err(KnobError::UnknownPreset(_))));
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
