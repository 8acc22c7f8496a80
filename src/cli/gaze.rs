//! `fovea replay` and `fovea gaze`: recordings in, frames or prediction errors out.

use std::path::{Path, PathBuf};

use anyhow::{bail, Context, Result};

use super::parse::parse_size;
use super::target::url_is_allowed;

#[derive(clap::Args)]
pub struct RecordingArgs {
    /// The recording.
    pub file: PathBuf,
    /// Screen size WxH in pixels, for formats in pixels (EyeLink, Neon, generic --pixels).
    #[arg(long)]
    pub screen: Option<String>,
    #[command(flatten)]
    pub read: ReadArgs,
}

/// How to read a recording's file, whichever command reads it.
#[derive(clap::Args, Clone)]
pub struct ReadArgs {
    /// Recording format (default: detected from the header).
    #[arg(long, value_enum)]
    pub format: Option<fovea::gaze::formats::Format>,
    /// EyeLink pupil areas are scaled so the recording's median pupil is this diameter, mm.
    #[arg(long, default_value_t = 4.0)]
    pub pupil_median_mm: f64,
    /// Generic CSV: the time column.
    #[arg(long, default_value = "t_ms")]
    pub time_col: String,
    /// Generic CSV: the horizontal gaze column (0–1 of the screen, or pixels with --pixels).
    #[arg(long, default_value = "x")]
    pub x_col: String,
    /// Generic CSV: the vertical gaze column (0–1 from the top, or pixels with --pixels).
    #[arg(long, default_value = "y")]
    pub y_col: String,
    /// Generic CSV: the pupil column (optional in the file; its unit is --pupil-unit).
    #[arg(long, default_value = "pupil_mm")]
    pub pupil_col: String,
    /// What the pupil column holds: mm (diameter in millimetres), diameter or area (arbitrary
    /// units, scaled so the recording's median is --pupil-median-mm; diameter ∝ √area).
    /// Default: the format's own (EyeLink: area, or what the ASC file says; Tobii: mm;
    /// generic: mm).
    #[arg(long, value_enum)]
    pub pupil_unit: Option<fovea::gaze::formats::PupilUnit>,
    /// Binocular recordings: which eye (default: the average, which uses the other eye where
    /// one is lost).
    #[arg(long, value_enum)]
    pub eye: Option<fovea::gaze::formats::Eye>,
    /// Generic CSV: the time column's unit: s, ms, us or ns.
    #[arg(long, default_value = "ms")]
    pub time_unit: String,
    /// Generic CSV: gaze columns are pixels on --screen rather than fractions.
    #[arg(long)]
    pub pixels: bool,
}

impl Default for ReadArgs {
    fn default() -> Self {
        ReadArgs {
            format: None,
            pupil_median_mm: 4.0,
            pupil_unit: None,
            eye: None,
            time_col: "t_ms".into(),
            x_col: "x".into(),
            y_col: "y".into(),
            pupil_col: "pupil_mm".into(),
            time_unit: "ms".into(),
            pixels: false,
        }
    }
}

impl RecordingArgs {
    pub fn load(&self) -> Result<fovea::gaze::formats::Recording> {
        self.read.load(&self.file, self.screen.as_deref())
    }
}

impl ReadArgs {
    pub fn load(
        &self,
        file: &Path,
        screen: Option<&str>,
    ) -> Result<fovea::gaze::formats::Recording> {
        // An hour at 2000 Hz is ~300 MB of CSV; more is not a recording (or is /dev/zero).
        let bytes = fovea::scene::limits::read_capped(file, 1 << 30)
            .with_context(|| format!("reading {}", file.display()))?;
        let text = String::from_utf8(bytes)
            .with_context(|| format!("{} is not UTF-8 text", file.display()))?;
        let screen = screen.map(parse_size).transpose()?;
        let opts = fovea::gaze::formats::ParseOptions {
            format: self.format,
            screen,
            columns: fovea::gaze::formats::Columns {
                time: self.time_col.clone(),
                x: self.x_col.clone(),
                y: self.y_col.clone(),
                pupil: Some(self.pupil_col.clone()),
                time_unit: self.time_unit.clone(),
                pixels: self.pixels,
            },
            pupil_median_mm: self.pupil_median_mm,
            pupil_unit: self.pupil_unit,
            eye: self.eye,
            ..Default::default()
        };
        let rec = fovea::gaze::formats::parse(&text, &opts)
            .with_context(|| format!("parsing {}", file.display()))?;
        let lost = rec.samples.iter().filter(|s| s.xy.is_none()).count();
        let span = rec.samples.last().map(|s| s.t_ms / 1e3).unwrap_or(0.0);
        eprintln!(
            "{}: {:?}, {} samples over {span:.1} s, {lost} without gaze (track loss or blink)",
            file.display(),
            rec.format,
            rec.samples.len()
        );
        if let Some(eye) = rec.eye {
            eprintln!("eye: {eye:?} (binocular recording; --eye left|right|average)");
        }
        if let Some((w, h)) = rec.screen {
            eprintln!("screen: {w}x{h} (from the file)");
        }
        if let Some(s) = &rec.saccades {
            eprintln!("{} saccades labelled by the file", s.len());
        }
        if let Some(rule) = &rec.pupil_rule {
            eprintln!("pupil: {rule}");
        }
        Ok(rec)
    }
}

#[derive(clap::Args)]
pub struct ReplayArgs {
    #[command(flatten)]
    pub recording: RecordingArgs,
    /// Server WebSocket URL.
    #[arg(long, default_value = "ws://127.0.0.1:8080/ws")]
    pub url: String,
    /// Output directory for frames.csv and summary.json.
    #[arg(long)]
    pub out: PathBuf,
    /// A non-loopback host this replay may target (repeatable).
    #[arg(long)]
    pub allow_host: Vec<String>,
    /// The server's session token, sent as `Authorization: Bearer …` (or FOVEA_TOKEN).
    #[arg(long, env = "FOVEA_TOKEN", hide_env_values = true)]
    pub token: Option<String>,
    /// Playback speed factor (2 = twice as fast), 0.01 to 100.
    #[arg(long, default_value_t = 1.0, value_parser = speed)]
    pub speed: f64,
    /// Start this many seconds into the recording (0 to a week).
    #[arg(long, default_value_t = 0.0, alias = "start-s", value_parser = recording_seconds)]
    pub start: f64,
    /// Play only this many seconds of it (up to a week).
    #[arg(long, alias = "duration-s", value_parser = recording_seconds)]
    pub duration: Option<f64>,
    /// Play the selection this many times (1 to 1000).
    #[arg(long = "loop", default_value_t = 1, value_parser = clap::value_parser!(u32).range(1..=1000))]
    pub loops: u32,
    /// Scene the session asks for.
    #[arg(long, default_value = fovea::scene::DEFAULT_SCENE, value_parser = super::parse::scene_names())]
    pub scene: String,
    /// Quality preset the session asks for.
    #[arg(long, value_enum, default_value_t = fovea::settings::Preset::DEFAULT)]
    pub preset: fovea::settings::Preset,
    /// Frame size WxH the session asks for.
    #[arg(long, value_parser = parse_size, default_value = "640x480")]
    pub size: (u32, u32),
    #[command(flatten)]
    pub encoding: super::parse::EncodingArgs,
    /// Save every received frame in DIR/frames: NNNNNN.jpg or .png (an inset frame as
    /// NNNNNN-base and NNNNNN-inset), H.264 as one raw stream per connection, stream-C.h264.
    #[arg(long)]
    pub save_frames: bool,
}

#[derive(clap::Args)]
pub struct GazeArgs {
    /// The recordings: each is scored alone, then all pooled.
    #[arg(required = true)]
    pub files: Vec<PathBuf>,
    /// Screen size WxH in pixels for formats in pixels: once for every file, or once per file
    /// in the files' order (default: what the file says, as ASC and Pro Lab files do).
    #[arg(long = "screen")]
    pub screens: Vec<String>,
    #[command(flatten)]
    pub read: ReadArgs,
    /// Prediction horizons, ms.
    #[arg(long, default_value = "10,20,30,50")]
    pub horizons: String,
    /// Physical width of the screen the recording was made on, cm.
    #[arg(long, default_value_t = 53.0)]
    pub display_width_cm: f64,
    /// Viewing distance the recording was made at, cm.
    #[arg(long, default_value_t = 60.0)]
    pub distance_cm: f64,
    /// Also write the tables (gaze.md, gaze.json) and the error-vs-horizon plots
    /// (gaze-<recording>.svg/png and gaze-pooled.svg/png) here.
    #[arg(long)]
    pub out: Option<PathBuf>,
}

pub fn replay(a: ReplayArgs) -> Result<()> {
    let rec = a.recording.load()?;
    let url = url_is_allowed(&a.url, &a.allow_host)?;
    let opts = fovea::client::replay::ReplayOptions {
        url,
        token: a.token.clone(),
        hello: fovea::protocol::Hello {
            scene: a.scene.clone(),
            preset: a.preset.to_string(),
            width: a.size.0,
            height: a.size.1,
            ..a.encoding.hello()
        },
        speed: a.speed,
        start_ms: a.start * 1e3,
        duration_ms: a.duration.map(|d| d * 1e3),
        loops: a.loops,
        keep_images: a.save_frames,
        stop: tokio_util::sync::CancellationToken::new(),
    };
    let runtime = tokio::runtime::Runtime::new()?;
    // Ctrl-C ends the replay early with its outputs written: the frames so far are data.
    let stop = opts.stop.clone();
    runtime.spawn(async move {
        if tokio::signal::ctrl_c().await.is_ok() {
            eprintln!("\ninterrupted: collecting the frames in flight and writing what came");
            stop.cancel();
        }
    });
    let started = std::time::Instant::now();
    let mut line = super::progress::Progress::new();
    let (frames, summary) = runtime.block_on(fovea::client::replay::replay(
        &rec.samples,
        &opts,
        |done, total| {
            line.show(
                format_args!(
                    "sent {done}/{total} samples ({:.0}%), {:.1} s",
                    100.0 * done as f64 / total.max(1) as f64,
                    started.elapsed().as_secs_f64()
                ),
                done >= total,
            );
        },
    ))?;
    line.finish();
    // Provenance: what was replayed, how, and against what, beside the figures.
    let mut summary = serde_json::to_value(&summary)?;
    summary["recording"] = serde_json::json!({
        "file": a.recording.file.display().to_string(),
        "format": rec.format,
        "eye": rec.eye,
        "screen": a.recording.screen.clone().or(rec.screen.map(|(w, h)| format!("{w}x{h}"))),
        "pupil": rec.pupil_rule,
        "samples": rec.samples.len(),
    });
    summary["asked"] = serde_json::json!({
        "url": a.url,
        "scene": a.scene,
        "preset": a.preset.to_string(),
        "size": format!("{}x{}", a.size.0, a.size.1),
        "speed": a.speed,
        "start_s": a.start,
        "duration_s": a.duration,
        "loops": a.loops,
        "codec": a.encoding.codec.name(),
        "bitrate_kbps": a.encoding.bitrate_kbps,
        "keyframe_s": a.encoding.keyframe_s,
        "foveated_encoding": a.encoding.foveated_encoding,
        "inset_deg": a.encoding.inset_deg,
    });
    summary["client_version"] = env!("CARGO_PKG_VERSION").into();
    std::fs::create_dir_all(&a.out).with_context(|| format!("creating {}", a.out.display()))?;
    std::fs::write(
        a.out.join("frames.csv"),
        fovea::client::replay::frames_csv(&frames),
    )?;
    std::fs::write(
        a.out.join("summary.json"),
        serde_json::to_string_pretty(&summary)?,
    )?;
    if a.save_frames {
        let dir = a.out.join("frames");
        fovea::client::saved_frames::save_frames(&dir, &frames)
            .with_context(|| format!("saving frames in {}", dir.display()))?;
    }
    println!("{}", serde_json::to_string_pretty(&summary)?);
    // The JSON above is for pipes; people get the gist on one line.
    eprintln!("{}", gist(&summary));
    eprintln!("wrote {}/frames.csv and summary.json", a.out.display());
    Ok(())
}

/// A replay's summary on one line for people.
fn gist(summary: &serde_json::Value) -> String {
    let f = |k: &str| summary[k].as_f64().unwrap_or(f64::NAN);
    format!(
        "{} frames in {:.1} s ({:.1} fps), {} at {:.0} kbit/s (keyframes: {}), gaze→frame p50 {:.1} p95 {:.1} p99 {:.1} ms",
        summary["frames"],
        f("seconds"),
        f("frames") / f("seconds"),
        summary["server"]["codec"].as_str().unwrap_or("?"),
        f("kbit_s"),
        summary["keyframes"],
        f("latency_p50_ms"),
        f("latency_p95_ms"),
        f("latency_p99_ms"),
    )
}

pub fn gaze(a: GazeArgs) -> Result<()> {
    if a.screens.len() > 1 && a.screens.len() != a.files.len() {
        bail!(
            "--screen: give one for every file or one per file ({} files, {} screens)",
            a.files.len(),
            a.screens.len()
        );
    }
    let horizons: Vec<f64> = a
        .horizons
        .split(',')
        .map(|s| super::parse::number_in(s.trim(), 0.0, 1000.0).map_err(anyhow::Error::msg))
        .collect::<Result<_>>()
        .context("--horizons: numbers of ms from 0 to 1000, like 10,20,30,50")?;
    let mut pooled = fovea::gaze::evaluate::Errors::default();
    let mut report = String::new();
    let mut tables = serde_json::Map::new();
    let mut plots = Vec::new();
    for (i, file) in a.files.iter().enumerate() {
        let screen = a.screens.get(i).or(a.screens.first()).map(String::as_str);
        let rec = a.read.load(file, screen)?;
        let (w, h) = match screen.map(parse_size).transpose()? {
            Some(size) => size,
            None => rec.screen.unwrap_or((1920, 1080)),
        };
        let display = fovea::viewing::Display {
            width_cm: a.display_width_cm,
            distance_cm: a.distance_cm,
        };
        let viewing = fovea::viewing::Viewing::new(display, w, h);
        let errors = fovea::gaze::evaluate::errors(
            &rec.samples,
            rec.saccades.as_deref(),
            &viewing,
            &horizons,
            fovea::gaze::prediction::Tuning::default(),
        );
        pooled.pool(&errors);
        let name = file
            .file_stem()
            .map(|n| n.to_string_lossy().into_owned())
            .unwrap_or_else(|| format!("recording-{i}"));
        plots.push((name, errors.summary()));
    }
    if a.files.len() > 1 {
        plots.push(("pooled".to_string(), pooled.summary()));
    }
    for (name, rows) in &plots {
        report.push_str(&format!(
            "## {name}\n\n{}\n",
            fovea::gaze::evaluate::markdown(rows)
        ));
        tables.insert(name.clone(), serde_json::to_value(rows)?);
    }
    println!("{report}");
    if let Some(dir) = &a.out {
        std::fs::create_dir_all(dir).with_context(|| format!("creating {}", dir.display()))?;
        std::fs::write(dir.join("gaze.md"), &report)?;
        std::fs::write(
            dir.join("gaze.json"),
            serde_json::to_string_pretty(&tables)?,
        )?;
        for (name, rows) in plots {
            let title = format!("Gaze prediction error: {name}");
            fovea::plot::write(
                &fovea::plot::gaze::GazePlot { title, rows },
                &dir.join(format!("gaze-{name}")),
            )?;
        }
        eprintln!(
            "wrote {0}/gaze.md, gaze.json and gaze-*.svg/png",
            dir.display()
        );
    }
    Ok(())
}

/// A replay speed: finite, 0.01× to 100× (a 1e-300 speed would stretch a schedule past any
/// timer; faster than 100× floods rather than replays).
fn speed(s: &str) -> Result<f64, String> {
    super::parse::number_in(s, 0.01, 100.0)
}

/// A time within a recording, seconds: finite, 0 to a week (the longest recording taken).
fn recording_seconds(s: &str) -> Result<f64, String> {
    super::parse::number_in(s, 0.0, fovea::gaze::formats::MAX_SPAN_DAYS * 86_400.0)
}
