//! `fovea bench`: the speed/accuracy sweep's command line, progress bar and Ctrl-C.

use std::path::PathBuf;
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::Arc;

use anyhow::{Context, Result};

use super::parse::{parse_gaze, parse_size};
use fovea::render::Renderer;

#[derive(clap::Args)]
pub struct BenchArgs {
    /// Scenes, comma-separated: built-in ones by name (gallery, bunny-marble, bunny-skin,
    /// materials, opaque, bunny, cornell) or scene and model files by path (.json, .gltf, .glb,
    /// .ply, .obj), named in the report by their file's stem.
    #[arg(long, default_value = fovea::scene::DEFAULT_SCENE)]
    pub scene: String,
    /// Frame sizes WxH, comma-separated.
    #[arg(long, default_value = "640x480")]
    pub size: String,
    /// Gaze points X,Y separated by ';' (default: centre and near a corner).
    #[arg(long, default_value = "0.5,0.5;0.1,0.1")]
    pub gaze: String,
    /// Move the gaze slowly around each point (smooth pursuit), so temporal reuse is exercised.
    #[arg(long)]
    pub moving: bool,
    /// Configurations: presets, rungs, knobs, or a comma-separated list of names from knobs.
    /// `codecs` compares the encoders instead (JPEG q50–95, H.264 125–8000 kbit/s, each plain,
    /// low-passed and with 20° and 16° insets, JPEG with a 13.3° one, H.264 with its periphery
    /// held alone, after the low-pass and with the 16° inset too) on frames rendered along
    /// --gaze-file (and --orbit-deg-per-s): one scene,
    /// one size, --frames frames at 60 fps; writes codecs.json, codecs.md, codecs.svg.
    #[arg(long, default_value = "knobs")]
    pub sweep: String,
    /// Unmeasured frames per configuration and gaze before measuring.
    #[arg(long, default_value_t = 3)]
    pub warmup: u32,
    /// Measured frames per configuration and gaze.
    #[arg(long, default_value_t = 10, value_parser = clap::value_parser!(u32).range(1..=100000))]
    pub frames: u32,
    /// Pupil diameter, mm.
    #[arg(long, default_value_t = fovea::render::DEFAULT_PUPIL_MM)]
    pub pupil_mm: f32,
    /// Physical width of the displayed frame, cm (sets degrees per pixel for the pooled errors).
    #[arg(long, default_value_t = 53.0)]
    pub display_width_cm: f64,
    /// Viewing distance, cm.
    #[arg(long, default_value_t = 60.0)]
    pub distance_cm: f64,
    /// Output directory for bench.json, bench.md and bench.svg.
    #[arg(long)]
    pub out: PathBuf,
    /// Physical ground truth of the same scene, camera and size (tools/mitsuba_reference.py:
    /// .exr linear in Fovea's units, or .png sRGB): every configuration and the reference rung
    /// are also compared with it. Needs one scene and one size, the image's.
    #[arg(long)]
    pub against: Option<PathBuf>,
    /// `--sweep codecs`: the recorded gaze the frames follow (any format `fovea replay` reads,
    /// e.g. assets/gaze/eyelink_1000hz_1920x1080.csv).
    #[arg(long)]
    pub gaze_file: Option<PathBuf>,
    /// `--sweep codecs`: the recording's screen WxH, for formats in pixels.
    #[arg(long)]
    pub screen: Option<String>,
    /// `--sweep codecs`: start this many seconds into the recording. Several, comma-separated
    /// (e.g. 5,10,15,20), measure --frames from each as a stream of its own and pool them in
    /// one report: a short stream's bytes depend on where in the recording it falls.
    #[arg(long, value_delimiter = ',', default_value = "0")]
    pub gaze_from_s: Vec<f64>,
    /// `--sweep codecs`: also write each configuration's last frame as the page would show it
    /// (and the lossless frame) to OUT/codecs/*.png.
    #[arg(long)]
    pub pictures: bool,
    /// `--sweep codecs`: turn the camera about its target at this many degrees per second (as
    /// a viewer dragging the view), so the periphery changes every frame; 0 keeps it still.
    #[arg(long, default_value_t = 0.0, allow_negative_numbers = true)]
    pub orbit_deg_per_s: f64,
    /// `--sweep codecs`: only the configurations whose names contain one of these
    /// comma-separated words (case-insensitive; e.g. "h.264" or "inset 16"). JPEG q85, which
    /// every family is matched to, is always measured.
    #[arg(long)]
    pub only: Option<String>,
    #[command(flatten, next_help_heading = "Reading --gaze-file")]
    pub read: super::gaze::ReadArgs,
}

pub fn bench(a: BenchArgs) -> Result<()> {
    if a.sweep == "codecs" {
        return super::codecs::bench_codecs(a);
    }
    if a.gaze_file.is_some() {
        anyhow::bail!("--gaze-file is for --sweep codecs; the other sweeps use --gaze points");
    }
    let configs = fovea::bench::sweep(&a.sweep).map_err(anyhow::Error::msg)?;
    let sizes = a
        .size
        .split(',')
        .map(parse_size)
        .collect::<Result<Vec<_>>>()?;
    let gazes = a
        .gaze
        .split(';')
        .map(parse_gaze)
        .collect::<Result<Vec<_>, _>>()
        .map_err(anyhow::Error::msg)?;
    let (scenes, own) = bench_scenes(&a.scene)?;
    let against = a
        .against
        .as_deref()
        .map(fovea::bench::GroundTruth::load)
        .transpose()?;
    if let Some(t) = &against {
        if scenes.len() != 1 || sizes != [(t.width, t.height)] {
            anyhow::bail!(
                "--against {}: the image is {}x{}; run one scene at that size (--size {}x{})",
                t.path.display(),
                t.width,
                t.height,
                t.width,
                t.height
            );
        }
    }
    let opts = fovea::bench::BenchOptions {
        scenes,
        sizes,
        gazes,
        moving: a.moving,
        warmup: a.warmup,
        frames: a.frames,
        configs,
        display: fovea::protocol::Display {
            width_cm: a.display_width_cm,
            distance_cm: a.distance_cm,
        },
        pupil_mm: a.pupil_mm,
        against,
    };
    let report = with_renderer(|renderer, stop, progress| {
        for scene in own {
            renderer.add_scene(scene)?;
        }
        Ok(fovea::bench::run(renderer, &opts, stop, progress)?)
    })?;
    fovea::bench::write_reports(&report, &a.out)
        .with_context(|| format!("writing reports to {}", a.out.display()))?;
    println!("{}", report.markdown());
    eprintln!(
        "wrote {}/bench.json, bench.md, bench.svg{}",
        a.out.display(),
        if report.interrupted {
            " (interrupted)"
        } else {
            ""
        }
    );
    Ok(())
}

/// A one-line progress bar with an ETA (`cli::progress` says how often it is shown).
fn progress_bar(line: &mut super::progress::Progress) -> impl FnMut(usize, usize, &str) + '_ {
    let started = std::time::Instant::now();
    move |done: usize, total: usize, what: &str| {
        let frac = done as f64 / total.max(1) as f64;
        let eta = if frac > 0.0 {
            started.elapsed().as_secs_f64() * (1.0 - frac) / frac
        } else {
            0.0
        };
        let bar: String = (0..30)
            .map(|i| if (i as f64) < frac * 30.0 { '#' } else { '-' })
            .collect();
        line.show(
            format_args!(
                "[{bar}] {done}/{total} ({:.0}%) ETA {:.0}s  {what:<28}",
                frac * 100.0,
                eta
            ),
            done >= total,
        );
    }
}

/// Opens the GPU and runs `sweep` with a progress bar; Ctrl-C sets the flag it gets, so it
/// stops after the frame in hand and keeps its results.
pub(super) fn with_renderer<R>(
    sweep: impl FnOnce(&mut Renderer, &AtomicBool, fovea::bench::Progress) -> Result<R>,
) -> Result<R> {
    let stop = Arc::new(AtomicBool::new(false));
    let flag = stop.clone();
    ctrlc::set_handler(move || {
        eprintln!("\nstopping after this frame; writing the results so far");
        flag.store(true, Ordering::Relaxed);
    })
    .context("installing the Ctrl-C handler")?;
    let mut renderer = Renderer::new().context("opening the GPU")?;
    eprintln!("adapter: {}", renderer.adapter());
    let mut line = super::progress::Progress::new();
    let out = sweep(&mut renderer, &stop, &mut progress_bar(&mut line));
    line.finish();
    out
}

/// The scenes `--scene` names: built-in ones as they are; anything else a scene or model file,
/// loaded here (its name is its file's stem, which must not shadow a built-in scene).
fn bench_scenes(list: &str) -> Result<(Vec<String>, Vec<fovea::scene::Scene>)> {
    let builtin = fovea::scene::builtin_names();
    let (mut names, mut own) = (Vec::new(), Vec::new());
    for item in list.split(',').map(str::trim) {
        if builtin.contains(&item) {
            names.push(item.to_string());
            continue;
        }
        let path = std::path::Path::new(item);
        if !path.exists() {
            anyhow::bail!(
                "--scene {item}: neither a built-in scene ({}) nor a scene or model file",
                builtin.join(", ")
            );
        }
        let scene = super::scenes::load_own_scene(path)?;
        let name = scene.name().to_string();
        if builtin.contains(&name.as_str()) || names.contains(&name) {
            anyhow::bail!(
                "{item}: its scene is named {name:?}, which another scene of this run has; rename the file"
            );
        }
        names.push(name);
        own.push(scene);
    }
    Ok((names, own))
}
