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
    if !a.gaze_from_s.is_finite() || a.gaze_from_s < 0.0 {
        bail!("--gaze-from-s must be a time ≥ 0 s, got {}", a.gaze_from_s);
    }
    let rec = a.read.load(file, a.screen.as_deref())?;
    let path = fovea::bench::gaze_path(&rec, a.gaze_from_s, a.frames as usize)
        .with_context(|| format!("following {}", file.display()))?;
    let opts = fovea::bench::CodecOptions {
        scene: scene.to_string(),
        width,
        height,
        path,
        recording: format!(
            "{} from {} s",
            file.file_name().map_or(file.display().to_string(), |n| n
                .to_string_lossy()
                .into_owned()),
            a.gaze_from_s
        ),
        configs: fovea::bench::codec_configs(),
        display: fovea::protocol::Display {
            width_cm: a.display_width_cm,
            distance_cm: a.distance_cm,
        },
        pictures: a.pictures.then(|| a.out.join("codecs")),
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
