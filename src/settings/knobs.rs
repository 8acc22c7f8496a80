//! The knob list, declared once. From the one `knobs!` list below come: the protocol's
//! `settings` message ([`SettingsPatch`], serde), the `fovea render`/`bench` flags (the same
//! struct through `clap::Args`), the range checks both apply, how each knob sets [`Settings`],
//! and [`KNOBS`], the table `docs/protocol.md` shows (a test keeps the docs in step).
//! A new knob is one entry here plus the field it sets.

use serde::{Deserialize, Serialize};

use super::{Noise, Overlay, ProbabilityForm, Reconstruction, Rung, Settings};

#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum KnobError {
    #[error("{name} must be finite, got {value}")]
    NotFinite { name: &'static str, value: f64 },
    #[error("{name} = {value} is outside [{min}, {max}]")]
    OutOfRange {
        name: &'static str,
        value: f64,
        min: f64,
        max: f64,
    },
    #[error("unknown preset {0:?}; available: {presets}", presets = super::Preset::names())]
    UnknownPreset(String),
}

/// Who a knob is for.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Scope {
    /// Changes the frame's pixels; reaches the renderer.
    Render,
    /// About the viewer's eye; stays with the session.
    Session,
}

/// One knob as the docs and the command line describe it.
#[derive(Debug, Clone, Copy)]
pub struct Knob {
    pub name: &'static str,
    pub doc: &'static str,
    /// The value's type as the wire spells it.
    pub kind: &'static str,
    /// Inclusive bounds of numeric knobs.
    pub range: Option<(f64, f64)>,
    pub scope: Scope,
}

/// A knob value as a number, for range checks (enums and flags have none).
trait Numeric {
    fn number(&self) -> Option<f64>;
}
impl Numeric for f64 {
    fn number(&self) -> Option<f64> {
        Some(*self)
    }
}
impl Numeric for u32 {
    fn number(&self) -> Option<f64> {
        Some(f64::from(*self))
    }
}
macro_rules! not_numeric {
    ($($t:ty),*) => { $(impl Numeric for $t { fn number(&self) -> Option<f64> { None } })* };
}
not_numeric!(bool, ProbabilityForm, Noise, Reconstruction, Rung, Overlay);

macro_rules! knobs {
    ($(
        $(#[doc = $doc:literal])+
        $name:ident: $ty:ty, $kind:literal, $scope:ident $(, [$lo:expr, $hi:expr])?
            => |$s:ident, $v:ident| $set:expr;
    )*) => {
        /// Changes a session's knobs live. `preset` (if given) resets the render knobs to that
        /// preset first; the other fields then override single knobs; omitted fields keep
        /// their value. On the command line, each knob is a `--flag`.
        #[derive(Debug, Clone, Default, PartialEq, Serialize, Deserialize, clap::Args)]
        #[serde(deny_unknown_fields)]
        pub struct SettingsPatch {
            #[serde(default, skip_serializing_if = "Option::is_none")]
            #[arg(skip)]
            pub preset: Option<String>,
            $(
                $(#[doc = $doc])+
                #[serde(default, skip_serializing_if = "Option::is_none")]
                #[arg(long, hide = knobs!(@hidden $scope))]
                pub $name: Option<$ty>,
            )*
        }

        /// Every knob, in the order of the protocol docs.
        pub const KNOBS: &[Knob] = &[$(
            Knob {
                name: stringify!($name),
                doc: concat!($($doc),+),
                kind: $kind,
                range: knobs!(@range $($lo, $hi)?),
                scope: Scope::$scope,
            },
        )*];

        impl SettingsPatch {
            /// Checks every numeric knob against its range (NaN included).
            pub fn validate(&self) -> Result<(), KnobError> {
                $(
                    if let (Some(v), Some((min, max))) = (
                        self.$name.as_ref().and_then(Numeric::number),
                        knobs!(@range $($lo, $hi)?),
                    ) {
                        if !v.is_finite() {
                            return Err(KnobError::NotFinite { name: stringify!($name), value: v });
                        }
                        if !(min..=max).contains(&v) {
                            return Err(KnobError::OutOfRange {
                                name: stringify!($name), value: v, min, max,
                            });
                        }
                    }
                )*
                Ok(())
            }

            pub(super) fn set_knobs(&self, settings: &mut Settings) {
                $(
                    if let Some($v) = self.$name {
                        let $s = &mut *settings;
                        $set;
                    }
                )*
            }
        }
    };
    (@range $lo:expr, $hi:expr) => { Some(($lo as f64, $hi as f64)) };
    (@range) => { None };
    (@hidden Render) => { false };
    (@hidden Session) => { true };
}

knobs! {
    /// Radiosity's interreflected light on (default) or off (area lights' direct light only).
    indirect: bool, "bool", Render => |s, v| s.render.indirect = v;
    /// Shadows from the key light on (default) or off.
    shadows: bool, "bool", Render => |s, v| s.render.shadows = v;
    /// Specular reflection on (default) or off (Lambert, and no interface on translucent media).
    specular: bool, "bool", Render => |s, v| s.render.specular = v;
    /// Foveated sampling on or off (off: every pixel shaded).
    foveation: bool, "bool", Render => |s, v| s.render.foveation.enabled = v;
    /// MAR slope m, degrees of MAR per degree of eccentricity.
    mar_slope: f64, "number", Render, [0.0, 1.0] => |s, v| s.render.foveation.mar_slope = v as f32;
    /// MAR at the fovea w0, degrees.
    mar_w0_deg: f64, "number", Render, [0.001, 1.0]
        => |s, v| s.render.foveation.mar_w0_deg = v as f32;
    /// Minimum sampling probability ξ: bounds the largest hole reconstruction must fill.
    min_probability: f64, "number", Render, [0.0, 1.0]
        => |s, v| s.render.foveation.min_probability = v as f32;
    /// Probability form: linear (thesis eq. 2) or density ((w_min/w)²).
    probability: ProbabilityForm, "linear|density", Render
        => |s, v| s.render.foveation.probability = v;
    /// Raise the probability at albedo and normal edges.
    saliency: bool, "bool", Render => |s, v| s.render.foveation.saliency = v;
    /// Edges ask for S·√p, not S (one sample per MAR along them; p the acuity 5° nearer the gaze).
    edges_at_mar: bool, "bool", Render => |s, v| s.render.foveation.edges_at_mar = v;
    /// Raise the probability where the image moves.
    motion: bool, "bool", Render => |s, v| s.render.foveation.motion = v;
    /// Blue noise (WSE rank map) or white noise for the sampling decision.
    noise: Noise, "blue|white", Render => |s, v| s.render.foveation.noise = v;
    /// Reuse last frame's colour where the depth test passes.
    reprojection: bool, "bool", Render => |s, v| s.render.foveation.reprojection = v;
    /// Frames a reused colour may age.
    max_history_age: u32, "integer", Render, [0, 1000]
        => |s, v| s.render.foveation.max_history_age = v;
    /// Reconstruction of unshaded pixels: nearest, sibson or pull_push.
    reconstruction: Reconstruction, "nearest|sibson|pull_push", Render
        => |s, v| s.render.foveation.reconstruction = v;
    /// Sibson window bound in pixels (0: from ξ).
    sibson_window: u32, "integer", Render, [0, 32]
        => |s, v| s.render.foveation.sibson_window = v;
    /// Shade a compacted list of the sampled pixels instead of a masked full-frame dispatch.
    compaction: bool, "bool", Render => |s, v| s.render.foveation.compaction = v;
    /// Translucency rung: opaque, normal_blur, screen, hierarchical, brute_force.
    translucency: Rung, "rung", Render => |s, v| s.render.translucency.rung = v;
    /// Finest photon-pyramid level a cluster may come from (0: single photons).
    cut_level: u32, "integer", Render, [0, 6] => |s, v| s.render.translucency.cut_level = v;
    /// Use a cluster whole when its extent < ε × its distance.
    cut_epsilon: f64, "number", Render, [0.0, 10.0]
        => |s, v| s.render.translucency.cut_epsilon = v as f32;
    /// Photon rungs, frames shaded whole: gather at every other pixel, interpolate where coherent.
    coarse_gather: bool, "bool", Render => |s, v| s.render.translucency.coarse_gather = v;
    /// Blur by the eye's depth of field.
    dof: bool, "bool", Render => |s, v| s.render.dof = v;
    /// Overlay: none, samples or probability.
    overlay: Overlay, "none|samples|probability", Render => |s, v| s.render.overlay = v;
    /// Predict the gaze at the expected display time.
    prediction: bool, "bool", Session => |s, v| s.session.prediction = v;
    /// How far ahead to predict, ms; 0: the session's measured gaze-to-frame latency.
    prediction_horizon_ms: f64, "number", Session, [0.0, 500.0]
        => |s, v| s.session.prediction_horizon_ms = v as f32;
}

/// The knob table as Markdown, as `docs/protocol.md` carries it.
pub fn markdown_table() -> String {
    let mut s =
        String::from("| knob | value | range | scope | what it does |\n|---|---|---|---|---|\n");
    for k in KNOBS {
        let range = k
            .range
            .map(|(a, b)| format!("{a} – {b}"))
            .unwrap_or_default();
        let scope = match k.scope {
            Scope::Render => "render",
            Scope::Session => "session",
        };
        s.push_str(&format!(
            "| `{}` | {} | {range} | {scope} | {} |\n",
            k.name,
            k.kind,
            k.doc.trim()
        ));
    }
    s
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn every_knob_round_trips_through_the_wire_form() {
        // A patch with every knob set serialises to exactly the names KNOBS lists.
        let json = serde_json::json!({
            "indirect": false, "shadows": false, "specular": false, "foveation": true, "mar_slope": 0.03, "mar_w0_deg": 0.02,
            "min_probability": 0.2, "probability": "linear", "saliency": false, "edges_at_mar": true, "motion": false,
            "noise": "white", "reprojection": false, "max_history_age": 4,
            "reconstruction": "nearest", "sibson_window": 3, "compaction": false,
            "translucency": "screen", "cut_level": 2, "cut_epsilon": 0.7, "coarse_gather": true, "dof": true,
            "overlay": "samples", "prediction": true, "prediction_horizon_ms": 20.0
        });
        let patch: SettingsPatch = serde_json::from_value(json.clone()).unwrap();
        let back = serde_json::to_value(&patch).unwrap();
        assert_eq!(back, json);
        let names: Vec<&str> = back
            .as_object()
            .unwrap()
            .keys()
            .map(String::as_str)
            .collect();
        let mut listed: Vec<&str> = KNOBS.iter().map(|k| k.name).collect();
        listed.sort();
        assert_eq!(names, listed);
    }

    #[test]
    fn out_of_range_and_nan_are_refused_with_the_knob_named() {
        for v in [f64::NAN, f64::INFINITY, -0.1, 1.5] {
            let p = SettingsPatch {
                min_probability: Some(v),
                ..Default::default()
            };
            let e = p.validate().unwrap_err();
            assert!(e.to_string().starts_with("min_probability"), "{e}");
        }
        let ok = SettingsPatch {
            min_probability: Some(1.0),
            cut_level: Some(6),
            ..Default::default()
        };
        assert_eq!(ok.validate(), Ok(()));
    }

    #[test]
    fn each_knob_sets_what_it_names() {
        let mut s = Settings::default();
        let p = SettingsPatch {
            cut_level: Some(3),
            prediction: Some(true),
            overlay: Some(Overlay::Probability),
            ..Default::default()
        };
        s.apply(&p).unwrap();
        assert_eq!(s.render.translucency.cut_level, 3);
        assert!(s.session.prediction);
        assert_eq!(s.render.overlay, Overlay::Probability);
    }
}
