//! The configurations a sweep measures: the presets, then one knob at a time around `balanced`.

use serde::{Deserialize, Serialize};

use crate::optics::acuity::ProbabilityForm;
use crate::protocol::Codec;
use crate::settings::{Noise, Preset, Reconstruction, RenderSettings, Rung};

#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct BenchConfig {
    pub name: String,
    pub settings: RenderSettings,
    pub codec: Codec,
    pub quality: u8,
}

impl BenchConfig {
    fn preset(name: &str) -> Option<BenchConfig> {
        Some(BenchConfig {
            name: name.to_string(),
            settings: RenderSettings::of(Preset::from_name(name)?),
            codec: Codec::Jpeg,
            quality: 85,
        })
    }

    fn variant(name: String, tweak: impl FnOnce(&mut RenderSettings)) -> BenchConfig {
        BenchConfig::variant_of("balanced", name, tweak)
    }

    fn variant_of(
        preset: &str,
        name: String,
        tweak: impl FnOnce(&mut RenderSettings),
    ) -> BenchConfig {
        let mut c = BenchConfig::preset(preset).expect("a preset");
        tweak(&mut c.settings);
        c.name = name;
        c
    }
}

/// `presets`: the named presets. `rungs`: every translucency rung and cut, unfoveated.
/// `knobs`: presets, rungs, shadows and specular off and depth of field on (of `full` and
/// `balanced`), and single-knob variations of `balanced` (MAR slope, ξ, probability form,
/// saliency, reprojection, reconstruction, noise, compaction) and the encoder. Any other value
/// is a comma-separated list of names from `knobs`.
pub fn sweep(which: &str) -> Result<Vec<BenchConfig>, String> {
    let presets: Vec<BenchConfig> = Preset::ALL
        .iter()
        .filter_map(|p| BenchConfig::preset(p.name()))
        .collect();
    let mut rungs = Vec::new();
    for rung in [Rung::Opaque, Rung::NormalBlur, Rung::Screen] {
        let name = serde_json::to_value(rung)
            .ok()
            .and_then(|v| v.as_str().map(str::to_string))
            .unwrap_or_default();
        rungs.push(BenchConfig::variant_of(
            "full",
            format!("full {name}"),
            |s| s.translucency.rung = rung,
        ));
    }
    for level in 1..=4u32 {
        rungs.push(BenchConfig::variant_of(
            "full",
            format!("full cut-level {level}"),
            |s| s.translucency.cut_level = level,
        ));
    }
    for eps in [0.25f32, 1.0, 2.0] {
        rungs.push(BenchConfig::variant_of(
            "full",
            format!("full cut-ε {eps}"),
            |s| s.translucency.cut_epsilon = eps,
        ));
    }
    rungs.push(BenchConfig::variant_of(
        "full",
        "full coarse-gather".into(),
        |s| s.translucency.coarse_gather = true,
    ));
    let mut knobs = presets.clone();
    knobs.extend(rungs.iter().cloned());
    // What the surface model costs: the key light's shadows and the specular lobe, each off;
    // and what the depth of field's gather adds, on.
    for preset in ["full", "balanced"] {
        knobs.push(BenchConfig::variant_of(
            preset,
            format!("{preset} dof"),
            |s| s.dof = true,
        ));
        knobs.push(BenchConfig::variant_of(
            preset,
            format!("{preset} no-shadows"),
            |s| s.shadows = false,
        ));
        knobs.push(BenchConfig::variant_of(
            preset,
            format!("{preset} no-specular"),
            |s| s.specular = false,
        ));
    }
    for m in [0.015f32, 0.034, 0.05] {
        knobs.push(BenchConfig::variant(format!("balanced m={m}"), |s| {
            s.foveation.mar_slope = m
        }));
    }
    for xi in [0.01f32, 0.02, 0.1, 0.2] {
        knobs.push(BenchConfig::variant(format!("balanced ξ={xi}"), |s| {
            s.foveation.min_probability = xi
        }));
    }
    knobs.push(BenchConfig::variant("balanced linear-p".into(), |s| {
        s.foveation.probability = ProbabilityForm::Linear
    }));
    knobs.push(BenchConfig::variant("balanced no-saliency".into(), |s| {
        s.foveation.saliency = false
    }));
    knobs.push(BenchConfig::variant(
        "balanced no-reprojection".into(),
        |s| s.foveation.reprojection = false,
    ));
    knobs.push(BenchConfig::variant("balanced nearest".into(), |s| {
        s.foveation.reconstruction = Reconstruction::Nearest
    }));
    knobs.push(BenchConfig::variant("balanced sibson".into(), |s| {
        s.foveation.reconstruction = Reconstruction::Sibson
    }));
    // The other foveated presets with the reconstructions they had before pull-push.
    knobs.push(BenchConfig::variant_of(
        "quality",
        "quality sibson".into(),
        |s| s.foveation.reconstruction = Reconstruction::Sibson,
    ));
    knobs.push(BenchConfig::variant_of(
        "fast",
        "fast nearest".into(),
        |s| s.foveation.reconstruction = Reconstruction::Nearest,
    ));
    knobs.push(BenchConfig::variant("balanced edges-at-mar".into(), |s| {
        s.foveation.edges_at_mar = true
    }));
    knobs.push(BenchConfig::variant("balanced white-noise".into(), |s| {
        s.foveation.noise = Noise::White
    }));
    knobs.push(BenchConfig::variant("balanced no-compaction".into(), |s| {
        s.foveation.compaction = false
    }));
    for q in [50u8, 95] {
        let mut c = BenchConfig::preset("balanced").expect("balanced is a preset");
        c.quality = q;
        c.name = format!("balanced jpeg q{q}");
        knobs.push(c);
    }
    let mut png = BenchConfig::preset("balanced").expect("balanced is a preset");
    png.codec = Codec::Png;
    png.name = "balanced png".into();
    knobs.push(png);
    match which {
        "presets" => Ok(presets),
        "rungs" => Ok(presets
            .into_iter()
            .filter(|c| c.name == "full" || c.name == "reference")
            .chain(rungs)
            .collect()),
        "knobs" => Ok(knobs),
        list => list
            .split(',')
            .map(|n| {
                let n = n.trim();
                knobs.iter().find(|c| c.name == n).cloned().ok_or_else(|| {
                    let names: Vec<&str> = knobs.iter().map(|c| c.name.as_str()).collect();
                    format!("unknown configuration {n:?}; known: {}", names.join(", "))
                })
            })
            .collect(),
    }
}

#[cfg(test)]
mod tests {
    #[test]
    fn sweeps_contain_the_baselines_and_names_are_unique() {
        let k = super::sweep("knobs").unwrap();
        assert!(k.iter().any(|c| c.name == "full") && k.iter().any(|c| c.name == "reference"));
        let mut names: Vec<&str> = k.iter().map(|c| c.name.as_str()).collect();
        names.sort();
        names.dedup();
        assert_eq!(names.len(), k.len());
        assert_eq!(super::sweep("full,fast").unwrap().len(), 2);
        assert!(super::sweep("full,nonsense")
            .unwrap_err()
            .contains("nonsense"));
    }
}
