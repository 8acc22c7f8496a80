//! `fovea bench --sweep codecs`: the encoder comparison along a recorded gaze path.

use anyhow::{bail, Context, Result};

use super::bench::{with_renderer, BenchArgs};
use super::parse::parse_size;

pub fn bench_codecs(a: BenchArgs) -> Result<()> {
    let Some(file) = &a.gaze_file else {
        bail!(
            "--sweep codecs follows a recorded gaze path: add --gaze-file (e.g. \
             --gaze-file assets/gaze/eyelink_1000hz_1920x1080.csv --screen 1920x1080)"
        );
    };
    if a.against.is_some() {
        bail!("--against compares renders; --sweep codecs compares encoders of one render");
    }
    let scene = a.scene.trim();
    if scene.contains(',') || a.size.contains(',') {
        bail!(
            "--sweep codecs measures one scene at one size (got --scene {scene} --size {})",
            a.size
        );
    }
    fovea::scene::Scene::builtin(scene)?;
    let (width, height) = parse_size(&a.size)?;
    if let Some(t) = a.gaze_from_s.iter().find(|t| !t.is_finite() || **t < 0.0) {
        bail!("--gaze-from-s must be times ≥ 0 s, got {t}");
    }
    if a.gaze_from_s.is_empty() {
        bail!("--gaze-from-s needs a time (0 for the recording's start)");
    }
    if !a.orbit_deg_per_s.is_finite() || a.orbit_deg_per_s.abs() > 360.0 {
        bail!(
            "--orbit-deg-per-s must be within ±360 (a turn a second), got {}",
            a.orbit_deg_per_s
        );
    }
    let rec = a.read.load(file, a.screen.as_deref())?;
    let path = fovea::bench::gaze_stretches(&rec, &a.gaze_from_s, a.frames as usize)
        .with_context(|| format!("following {}", file.display()))?;
    let froms: Vec<String> = a.gaze_from_s.iter().map(|t| t.to_string()).collect();
    let opts = fovea::bench::CodecOptions {
        scene: scene.to_string(),
        width,
        height,
        path,
        stretch_frames: a.frames as usize,
        recording: format!(
            "{} from {} s{}",
            file.file_name().map_or(file.display().to_string(), |n| n
                .to_string_lossy()
                .into_owned()),
            froms.join(", "),
            if froms.len() > 1 {
                format!(" ({} frames from each, a stream apiece)", a.frames)
            } else {
                String::new()
            }
        ),
        configs: chosen(a.only.as_deref())?,
        display: fovea::protocol::Display {
            width_cm: a.display_width_cm,
            distance_cm: a.distance_cm,
        },
        pictures: a.pictures.then(|| a.out.join("codecs")),
        orbit_deg_per_s: a.orbit_deg_per_s,
    };
    let report = with_renderer(|renderer, stop, progress| {
        Ok(fovea::bench::run_codecs(renderer, &opts, stop, progress)?)
    })?;
    fovea::bench::write_codec_reports(&report, &a.out)
        .with_context(|| format!("writing reports to {}", a.out.display()))?;
    println!("{}", report.markdown());
    eprintln!(
        "wrote {}/codecs.json, codecs.md, codecs.svg{}{}",
        a.out.display(),
        if a.pictures { " and codecs/*.png" } else { "" },
        if report.interrupted {
            " (interrupted)"
        } else {
            ""
        }
    );
    Ok(())
}

/// The configurations `--only` keeps (all without it), JPEG q85 always among them.
fn chosen(only: Option<&str>) -> Result<Vec<fovea::bench::CodecConfig>> {
    let all = fovea::bench::codec_configs();
    let Some(only) = only else {
        return Ok(all);
    };
    let words: Vec<String> = only
        .split(',')
        .map(|w| w.trim().to_lowercase())
        .filter(|w| !w.is_empty())
        .collect();
    let named = |name: &str| {
        let name = name.to_lowercase();
        words.iter().any(|w| name.contains(w))
    };
    if !all.iter().any(|c| named(&c.name)) {
        let names: Vec<&str> = all.iter().map(|c| c.name.as_str()).collect();
        bail!(
            "--only {only}: no configuration's name contains it; the names are: {}",
            names.join(", ")
        );
    }
    Ok(all
        .into_iter()
        .filter(|c| c.name == fovea::bench::TARGET || named(&c.name))
        .collect())
}

#[cfg(test)]
mod tests {
    use super::chosen;

    #[test]
    fn only_keeps_the_named_configurations_and_the_target() {
        let all = chosen(None).unwrap();
        assert_eq!(all, fovea::bench::codec_configs());
        let names = |only: &str| -> Vec<String> {
            chosen(Some(only))
                .unwrap()
                .into_iter()
                .map(|c| c.name)
                .collect()
        };
        let inset = names("INSET 16");
        assert_eq!(inset.len(), 26, "{inset:?}");
        assert_eq!(inset[0], fovea::bench::TARGET);
        assert!(
            inset[1..].iter().all(|n| n.contains("inset 16°")),
            "{inset:?}"
        );
        assert_eq!(
            names("h.264 500 kbit/s, q95"),
            [
                "JPEG q85",
                "JPEG q95",
                "H.264 500 kbit/s",
                "JPEG q95 + low-pass",
                "H.264 500 kbit/s + low-pass",
                "JPEG q95 + inset 20°",
                "H.264 500 kbit/s + inset 20°",
                "JPEG q95 + inset 16°",
                "H.264 500 kbit/s + inset 16°",
                "H.264 500 kbit/s + inset 16° + low-pass",
                "H.264 500 kbit/s + hold",
                "H.264 500 kbit/s + low-pass + hold",
                "H.264 500 kbit/s + inset 16° + low-pass + hold",
                "JPEG q95 + inset 13.3°"
            ]
        );
        assert!(chosen(Some("vp9")).is_err());
        // Naming only the target is allowed.
        assert_eq!(
            names("q85"),
            [
                "JPEG q85",
                "JPEG q85 + low-pass",
                "JPEG q85 + inset 20°",
                "JPEG q85 + inset 16°",
                "JPEG q85 + inset 13.3°"
            ]
        );
    }
}
