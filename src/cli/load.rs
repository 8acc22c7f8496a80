//! `fovea load`: the load generator's command line.

use std::path::PathBuf;

use anyhow::{bail, Context, Result};

use super::gaze::ReadArgs;
use super::target::url_is_allowed;

#[derive(clap::Args)]
pub struct LoadArgs {
    /// The server's WebSocket URL (loopback unless --allow-host names the host).
    #[arg(long, default_value = "ws://127.0.0.1:8080/ws")]
    pub url: String,
    /// Concurrent sessions.
    #[arg(long, default_value_t = 4)]
    pub sessions: usize,
    /// Run several session counts in turn (e.g. 1,2,4,8) and report where the budget breaks.
    #[arg(long)]
    pub sweep: Option<String>,
    /// Seconds per run (bounded: at most 600).
    #[arg(long, default_value_t = 30.0)]
    pub duration: f64,
    /// Milliseconds between session starts.
    #[arg(long, default_value_t = 100.0)]
    pub ramp_up_ms: f64,
    /// Gaze samples per second per session.
    #[arg(long, default_value_t = 120.0)]
    pub rate_hz: f64,
    /// Scene every session asks for.
    #[arg(long, default_value = fovea::scene::DEFAULT_SCENE, value_parser = super::parse::scene_names())]
    pub scene: String,
    /// Quality preset every session asks for.
    #[arg(long, value_enum, default_value_t = fovea::settings::Preset::DEFAULT)]
    pub preset: fovea::settings::Preset,
    /// Frame size WxH every session asks for.
    #[arg(long, value_parser = super::parse::parse_size, default_value = "640x480")]
    pub size: (u32, u32),
    #[command(flatten)]
    pub encoding: super::parse::EncodingArgs,
    /// Compare codecs in one run: session i asks for the i-th codec of this list (cycling),
    /// e.g. jpeg,h264; the report gains a line per codec. Overrides --codec.
    #[arg(long, value_delimiter = ',', value_parser = super::parse::codec)]
    pub mix_codecs: Vec<fovea::protocol::Codec>,
    /// Sweep budget: p95 gaze-to-frame latency, ms.
    #[arg(long, default_value_t = 500.0)]
    pub budget_ms: f64,
    /// Sweep budget: slowest session's frames per second.
    #[arg(long, default_value_t = 2.0)]
    pub min_fps: f64,
    /// Synthetic-eye seed.
    #[arg(long, default_value_t = 1)]
    pub seed: u32,
    /// Drive sessions with a gaze recording instead of the synthetic eye (each session starts
    /// at a different offset; the recording loops). Samples are sent at their recorded timing.
    #[arg(long)]
    pub recording: Option<PathBuf>,
    /// Screen size WxH of the recording, for formats in pixels.
    #[arg(long)]
    pub screen: Option<String>,
    /// A non-loopback host this load may target (repeatable).
    #[arg(long)]
    pub allow_host: Vec<String>,
    /// The server's session token, sent as `Authorization: Bearer …` (or FOVEA_TOKEN).
    #[arg(long, env = "FOVEA_TOKEN", hide_env_values = true)]
    pub token: Option<String>,
    /// Folder for load.json and the plots.
    #[arg(long)]
    pub out: PathBuf,
}

/// One run of the load, its progress on stderr (`cli::progress`).
fn run_with_progress(
    runtime: &tokio::runtime::Runtime,
    opts: &fovea::client::load::LoadOptions,
) -> fovea::client::load::LoadReport {
    let total = opts.duration.as_secs_f64();
    // `run` wants a shareable callback; the line is touched once a second.
    let line = std::sync::Arc::new(std::sync::Mutex::new(super::progress::Progress::new()));
    let shown = line.clone();
    let report = runtime.block_on(fovea::client::load::run(opts, move |n, t| {
        if let Ok(mut line) = shown.lock() {
            line.show(
                format_args!("{}: {t:.0}/{total:.0} s", sessions(n)),
                t >= total,
            );
        }
    }));
    if let Ok(mut line) = line.lock() {
        line.finish();
    }
    report
}

/// "1 session", "4 sessions".
fn sessions(n: usize) -> String {
    format!("{n} session{}", if n == 1 { "" } else { "s" })
}

/// One run's summary lines on stdout.
fn print_run(n: usize, report: &fovea::client::load::LoadReport) {
    println!(
        "{}: {} frames, {:.2} fps total, {:.2}–{:.2} fps per session (fairness {:.2}), gaze→frame p50 {:.1} p95 {:.1} p99 {:.1} max {:.1} ms; render p50 {:.1} ms; samples coalesced {}; errors {}, refused {}, failed {}",
        sessions(n),
        report.frames,
        report.fps_total,
        report.fps_min,
        report.fps_max,
        report.fairness,
        report.latency_ms.p50,
        report.latency_ms.p95,
        report.latency_ms.p99,
        report.latency_ms.max,
        report.stages_ms.get("render").map(|p| p.p50).unwrap_or(f64::NAN),
        report.samples_coalesced,
        report.errors,
        report.refused,
        report.connection_failures
    );
    if report.by_codec.len() > 1 {
        for (codec, c) in &report.by_codec {
            println!(
                "  {codec}: {}, {} frames, gaze→frame p50 {:.1} p95 {:.1} ms; render p50 {:.1} ms; encode p50 {:.2} ms; {:.0} kbit/s per session",
                sessions(c.sessions), c.frames, c.latency_ms.p50, c.latency_ms.p95, c.render_ms.p50, c.encode_ms.p50, c.kbit_s_per_session
            );
        }
    }
    if report.reconnects > 0 || report.sessions_ended_early > 0 {
        let gap = report.reconnect_gap_ms.map_or(String::new(), |g| {
            format!(", gap between frames p50 {:.0} max {:.0} ms", g.p50, g.max)
        });
        println!(
            "  {} reconnects (a server drained or a connection dropped){gap}; {} ended early{}",
            report.reconnects,
            sessions(report.sessions_ended_early as usize),
            report
                .ended_early_reason
                .as_ref()
                .map_or(String::new(), |r| format!(" ({r})"))
        );
    }
}

pub fn load(a: LoadArgs) -> Result<()> {
    let url = url_is_allowed(&a.url, &a.allow_host)?;
    let recording = match &a.recording {
        Some(file) => {
            let read = ReadArgs::default();
            Some(std::sync::Arc::new(
                read.load(file, a.screen.as_deref())?.samples,
            ))
        }
        None => None,
    };
    let counts = session_counts(&a)?;
    let duration = std::time::Duration::from_secs_f64(a.duration.clamp(1.0, 600.0));
    let runtime = tokio::runtime::Runtime::new()?;
    let mut reports = Vec::new();
    std::fs::create_dir_all(&a.out).with_context(|| format!("creating {}", a.out.display()))?;
    for n in counts {
        let opts = fovea::client::load::LoadOptions {
            url: url.clone(),
            token: a.token.clone(),
            sessions: n,
            duration,
            ramp_up: std::time::Duration::from_secs_f64(a.ramp_up_ms.max(0.0) / 1000.0),
            rate_hz: a.rate_hz,
            hello: fovea::protocol::Hello {
                scene: a.scene.clone(),
                preset: a.preset.to_string(),
                width: a.size.0,
                height: a.size.1,
                ..a.encoding.hello()
            },
            seed: a.seed,
            recording: recording.clone(),
            codecs: a.mix_codecs.clone(),
        };
        let report = run_with_progress(&runtime, &opts);
        // Nothing answered: no later count can do better, and plots of zeros would only
        // bury the reason under them.
        if let (Some(e), 0) = (&report.connection_error, report.frames) {
            bail!("cannot connect: {e}; is `fovea serve` running there?");
        }
        print_run(n, &report);
        reports.push(report);
    }
    let capacity = reports
        .iter()
        .filter(|r| {
            r.latency_ms.p95 <= a.budget_ms
                && r.fps_min >= a.min_fps
                && r.refused == 0
                && r.connection_failures == 0
        })
        .map(|r| r.sessions)
        .max();
    let json = report_json(&a, &url, capacity, &reports);
    std::fs::write(
        a.out.join("load.json"),
        serde_json::to_string_pretty(&json)?,
    )?;
    plot_load(&json, &a.out)?;
    match capacity {
        Some(c) => println!(
            "capacity within budget (p95 ≤ {} ms, ≥ {} fps per session): {}",
            a.budget_ms,
            a.min_fps,
            sessions(c)
        ),
        None => println!(
            "no session count met the budget (p95 ≤ {} ms, ≥ {} fps per session)",
            a.budget_ms, a.min_fps
        ),
    }
    eprintln!(
        "wrote {0}/load.json, load.svg/.png and load-N.svg/.png per run",
        a.out.display()
    );
    nobody_connected(&reports, &url)?;
    Ok(())
}

/// The session counts to run (`--sweep`, or `--sessions` alone), within the stated limits.
fn session_counts(a: &LoadArgs) -> Result<Vec<usize>> {
    let counts: Vec<usize> = match &a.sweep {
        Some(s) => s
            .split(',')
            .map(|n| n.trim().parse::<usize>())
            .collect::<Result<_, _>>()
            .context("--sweep: session counts like 1,2,4,8")?,
        None => vec![a.sessions],
    };
    if counts.iter().any(|n| *n == 0 || *n > 256) {
        bail!("session counts run from 1 to 256");
    }
    if let Some(n) = counts.iter().find(|n| **n < a.mix_codecs.len()) {
        bail!(
            "--mix-codecs names {} codecs but a run has {n} sessions: every codec needs one",
            a.mix_codecs.len()
        );
    }
    Ok(counts)
}

/// What `load.json` holds: the run's settings, its budget and capacity, and every run's report.
fn report_json(
    a: &LoadArgs,
    url: &str,
    capacity: Option<usize>,
    reports: &[fovea::client::load::LoadReport],
) -> serde_json::Value {
    serde_json::json!({
        "url": url,
        "scene": a.scene, "preset": a.preset, "width": a.size.0, "height": a.size.1, "rate_hz": a.rate_hz,
        "budget": { "p95_ms": a.budget_ms, "min_fps": a.min_fps },
        "encoding": {
            "codec": a.encoding.codec.name(),
            "mix_codecs": a.mix_codecs.iter().map(|c| c.name()).collect::<Vec<_>>(),
            "bitrate_kbps": a.encoding.bitrate_kbps,
            "keyframe_s": a.encoding.keyframe_s,
            "foveated_encoding": a.encoding.foveated_encoding,
            "inset_deg": a.encoding.inset_deg,
        },
        "capacity_sessions": capacity,
        "runs": reports,
    })
}

/// A run in which no session got in measured nothing: says why and fails (a server that could
/// not be reached at all stopped the sweep before).
fn nobody_connected(reports: &[fovea::client::load::LoadReport], url: &str) -> Result<()> {
    if let Some(r) = reports
        .iter()
        .find(|r| r.connection_failures + r.refused >= r.sessions as u64)
    {
        let why = match r.refused {
            0 => "every session failed before its welcome".to_string(),
            n => format!(
                "{n} of {} refused: server at capacity",
                sessions(r.sessions)
            ),
        };
        bail!(
            "no session connected to {url} with {} ({why})",
            sessions(r.sessions)
        );
    }
    Ok(())
}

/// The sweep plot (`load.svg`, `load.png`) and each run's timeline (`load-N.*`) from the
/// report's JSON, so `fovea plot load.json` redraws exactly what a run drew.
pub fn plot_load(json: &serde_json::Value, dir: &std::path::Path) -> Result<()> {
    use fovea::plot::load::{Run, SweepPlot, TimelinePlot};
    let runs: Vec<Run> = serde_json::from_value(json["runs"].clone()).context("load.json runs")?;
    let what = format!(
        "{} {} {}x{} at {} Hz",
        json["scene"].as_str().unwrap_or("?"),
        json["preset"].as_str().unwrap_or("?"),
        json["width"],
        json["height"],
        json["rate_hz"]
    );
    for run in &runs {
        let title = format!("fovea load, {}: {what}", sessions(run.sessions));
        let plot = TimelinePlot {
            title,
            run: run.clone(),
        };
        fovea::plot::write(&plot, &dir.join(format!("load-{}", run.sessions)))?;
    }
    let title = format!("fovea load: {what}");
    fovea::plot::write(&SweepPlot { title, runs }, &dir.join("load"))?;
    Ok(())
}
