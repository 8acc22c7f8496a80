//! The `fovea` command line: `serve` and `render` (replay, load and bench come with their work).

use std::net::SocketAddr;
use std::path::PathBuf;

use anyhow::{bail, Context, Result};
use clap::{Parser, Subcommand};
use glam::Vec3;
use tokio_util::sync::CancellationToken;

use fovea::protocol::Codec;
use fovea::render::{FrameRequest, RenderThread, Renderer};

#[derive(Parser)]
#[command(name = "fovea", version, about = "Gaze-streaming rendering service: frames that follow the eye, rendered headless on the GPU and streamed to a browser")]
struct Cli {
    #[command(subcommand)]
    command: Command,
}

#[derive(Subcommand)]
enum Command {
    /// Serve the web client on / and gaze-driven frames over the WebSocket /ws.
    ///
    /// Logs go to stderr (RUST_LOG=fovea=debug for more); the first line on stdout is
    /// "fovea listening on http://ADDR/", with the real port when --addr asks for port 0.
    Serve {
        /// Address to listen on. Port 0 picks a free port.
        #[arg(long, default_value = "127.0.0.1:8080")]
        addr: SocketAddr,
        /// Record every session's received gaze samples to DIR/session-<id>.csv (generic CSV,
        /// replayable with `fovea replay`).
        #[arg(long)]
        record_dir: Option<PathBuf>,
        /// Sessions served at once; more are refused (WebSocket close 1013, /readyz 503).
        #[arg(long, default_value_t = 16, value_parser = clap::value_parser!(u64).range(1..=10000))]
        max_sessions: u64,
        /// Seconds a client may leave frames unacknowledged (or stop reading) before it is
        /// disconnected.
        #[arg(long, default_value_t = 10.0)]
        stall_timeout_s: f64,
    },
    /// Render one frame to an image file, without a server.
    ///
    /// Quality knobs start from --preset; any knob flag then overrides that one knob. With
    /// --frames N the same gaze is rendered N times as one stream (so reprojection has history)
    /// and the last frame is written.
    Render {
        /// Scene to render (built-in: bunny).
        #[arg(long, default_value = fovea::scene::DEFAULT_SCENE)]
        scene: String,
        #[arg(long, default_value_t = 640)]
        width: u32,
        #[arg(long, default_value_t = 480)]
        height: u32,
        /// Gaze as X,Y in [0,1], top-left origin; foveation centres here and the marker is drawn here.
        #[arg(long, value_parser = parse_gaze, default_value = "0.5,0.5")]
        gaze: [f32; 2],
        /// Leave out the gaze marker.
        #[arg(long)]
        no_marker: bool,
        /// Override the light: direction towards it as X,Y,Z.
        #[arg(long, value_parser = parse_vec3)]
        light: Option<Vec3>,
        /// Output file; .png (lossless) or .jpg/.jpeg.
        #[arg(long, required_unless_present = "explain")]
        out: Option<PathBuf>,
        /// Print the scene plan (which passes run, and why) for this scene and size, and exit.
        #[arg(long)]
        explain: bool,
        /// JPEG quality 1–100.
        #[arg(long, default_value_t = 90, value_parser = clap::value_parser!(u8).range(1..=100))]
        quality: u8,
        /// Quality preset: reference, full, quality, balanced, fast.
        #[arg(long, default_value = "full")]
        preset: String,
        /// Frames to render before writing the last one.
        #[arg(long, default_value_t = 1, value_parser = clap::value_parser!(u32).range(1..=10000))]
        frames: u32,
        /// Pupil diameter in mm (1–10); sets the depth of field.
        #[arg(long, default_value_t = fovea::render::DEFAULT_PUPIL_MM)]
        pupil_mm: f32,
        /// Physical width of the displayed frame, cm.
        #[arg(long, default_value_t = 53.0)]
        display_width_cm: f64,
        /// Viewing distance, cm.
        #[arg(long, default_value_t = 60.0)]
        distance_cm: f64,
        #[command(flatten)]
        knobs: Knobs,
    },
    /// Measure every preset and knob: frame time, per-pass GPU time, encode cost and the error
    /// against the reference render of the same frame; writes bench.json, bench.md, bench.svg.
    ///
    /// Ctrl-C stops after the current frame and still writes what was measured.
    Bench(BenchArgs),
    /// Stream a gaze recording to a server at its recorded timing and record every frame.
    ///
    /// Formats: EyeLink CSV (t_s, xpos, ypos, ps), Pupil Labs Core gaze_positions.csv, Pupil Labs
    /// Neon gaze.csv, Tobii-style (device_time_stamp, gaze_point_x, gaze_point_y,
    /// pupil_diameter), and generic CSV (t_ms, x, y, pupil_mm; see --time-col and friends).
    /// Track loss, blinks and samples far off the frame are not sent: the server keeps the last
    /// valid gaze. Writes DIR/frames.csv, DIR/summary.json and, with --save-frames, the images.
    Replay(ReplayArgs),
    /// Evaluate gaze prediction on a recording: angular error at several horizons, holding the
    /// last sample vs predicting, for fixation and saccade samples.
    Gaze(GazeArgs),
    /// Load-test a server: N concurrent sessions driven by the synthetic eye for a fixed time,
    /// acknowledging frames like real clients. Reports gaze-to-frame latency and the server's
    /// stage times as HDR percentiles, fps per session and in total, fairness, errors and
    /// refusals; writes DIR/load.json and DIR/load.svg. Loopback targets only.
    Load(LoadArgs),
}

#[derive(clap::Args)]
struct LoadArgs {
    #[arg(long, default_value = "ws://127.0.0.1:8080/ws")]
    url: String,
    /// Concurrent sessions.
    #[arg(long, default_value_t = 4)]
    sessions: usize,
    /// Run several session counts in turn (e.g. 1,2,4,8) and report where the budget breaks.
    #[arg(long)]
    sweep: Option<String>,
    /// Seconds per run (bounded: at most 600).
    #[arg(long, default_value_t = 30.0)]
    duration: f64,
    /// Milliseconds between session starts.
    #[arg(long, default_value_t = 100.0)]
    ramp_up_ms: f64,
    /// Gaze samples per second per session.
    #[arg(long, default_value_t = 120.0)]
    rate_hz: f64,
    #[arg(long, default_value = fovea::scene::DEFAULT_SCENE)]
    scene: String,
    #[arg(long, default_value = "balanced")]
    preset: String,
    #[arg(long, default_value_t = 640)]
    width: u32,
    #[arg(long, default_value_t = 480)]
    height: u32,
    /// Sweep budget: p95 gaze-to-frame latency, ms.
    #[arg(long, default_value_t = 500.0)]
    budget_ms: f64,
    /// Sweep budget: slowest session's frames per second.
    #[arg(long, default_value_t = 2.0)]
    min_fps: f64,
    /// Synthetic-eye seed.
    #[arg(long, default_value_t = 1)]
    seed: u32,
    /// Drive sessions with a gaze recording instead of the synthetic eye (each session starts
    /// at a different offset; the recording loops). Samples are sent at their recorded timing.
    #[arg(long)]
    recording: Option<PathBuf>,
    /// Screen size WxH of the recording, for formats in pixels.
    #[arg(long)]
    screen: Option<String>,
    /// A non-loopback host this load may target (repeatable).
    #[arg(long)]
    allow_host: Vec<String>,
    #[arg(long)]
    out: PathBuf,
}

#[derive(clap::Args)]
struct RecordingArgs {
    /// The recording.
    file: PathBuf,
    /// Screen size WxH in pixels, for formats in pixels (EyeLink, Neon, generic --pixels).
    #[arg(long)]
    screen: Option<String>,
    /// eyelink, pupil_core, pupil_neon, tobii or generic (default: from the header).
    #[arg(long, value_parser = parse_enum::<fovea::gaze::formats::Format>)]
    format: Option<fovea::gaze::formats::Format>,
    /// EyeLink pupil areas are scaled so the recording's median pupil is this diameter, mm.
    #[arg(long, default_value_t = 4.0)]
    pupil_median_mm: f64,
    /// Generic CSV: column names and time unit (s, ms, us, ns); --pixels for pixel coordinates.
    #[arg(long, default_value = "t_ms")]
    time_col: String,
    #[arg(long, default_value = "x")]
    x_col: String,
    #[arg(long, default_value = "y")]
    y_col: String,
    #[arg(long, default_value = "pupil_mm")]
    pupil_col: String,
    #[arg(long, default_value = "ms")]
    time_unit: String,
    #[arg(long)]
    pixels: bool,
}

impl RecordingArgs {
    fn load(&self) -> Result<fovea::gaze::formats::Recording> {
        let text = std::fs::read_to_string(&self.file).with_context(|| format!("reading {}", self.file.display()))?;
        let screen = self.screen.as_deref().map(parse_size).transpose()?;
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
            ..Default::default()
        };
        let rec = fovea::gaze::formats::parse(&text, &opts).with_context(|| format!("parsing {}", self.file.display()))?;
        let lost = rec.samples.iter().filter(|s| s.xy.is_none()).count();
        let span = rec.samples.last().map(|s| s.t_ms / 1e3).unwrap_or(0.0);
        eprintln!("{}: {:?}, {} samples over {span:.1} s, {lost} without gaze (track loss or blink)", self.file.display(), rec.format, rec.samples.len());
        if let Some(rule) = &rec.pupil_rule {
            eprintln!("pupil: {rule}");
        }
        Ok(rec)
    }
}

#[derive(clap::Args)]
struct ReplayArgs {
    #[command(flatten)]
    recording: RecordingArgs,
    /// Server WebSocket URL.
    #[arg(long, default_value = "ws://127.0.0.1:8080/ws")]
    url: String,
    /// Output directory for frames.csv and summary.json.
    #[arg(long)]
    out: PathBuf,
    /// A non-loopback host this replay may target (repeatable).
    #[arg(long)]
    allow_host: Vec<String>,
    /// Playback speed factor (2 = twice as fast).
    #[arg(long, default_value_t = 1.0)]
    speed: f64,
    /// Start this many seconds into the recording.
    #[arg(long, default_value_t = 0.0)]
    start_s: f64,
    /// Play only this many seconds of it.
    #[arg(long)]
    duration_s: Option<f64>,
    /// Play the selection this many times.
    #[arg(long = "loop", default_value_t = 1)]
    loops: u32,
    #[arg(long, default_value = fovea::scene::DEFAULT_SCENE)]
    scene: String,
    #[arg(long, default_value = "balanced")]
    preset: String,
    #[arg(long, default_value_t = 640)]
    width: u32,
    #[arg(long, default_value_t = 480)]
    height: u32,
    /// Save every received frame as DIR/frames/NNNNNN.jpg.
    #[arg(long)]
    save_frames: bool,
}

#[derive(clap::Args)]
struct GazeArgs {
    #[command(flatten)]
    recording: RecordingArgs,
    /// Prediction horizons, ms.
    #[arg(long, default_value = "10,20,30,50")]
    horizons: String,
    /// Physical width of the screen the recording was made on, cm, and the viewing distance.
    #[arg(long, default_value_t = 53.0)]
    display_width_cm: f64,
    #[arg(long, default_value_t = 60.0)]
    distance_cm: f64,
}

#[derive(clap::Args)]
struct BenchArgs {
    /// Scenes, comma-separated.
    #[arg(long, default_value = fovea::scene::DEFAULT_SCENE)]
    scene: String,
    #[arg(long, default_value_t = 640)]
    width: u32,
    #[arg(long, default_value_t = 480)]
    height: u32,
    /// More frame sizes as WxH, comma-separated (in addition to --width/--height).
    #[arg(long)]
    sizes: Option<String>,
    /// Gaze points X,Y separated by ';' (default: centre and near a corner).
    #[arg(long, default_value = "0.5,0.5;0.1,0.1")]
    gaze: String,
    /// Move the gaze slowly around each point (smooth pursuit), so temporal reuse is exercised.
    #[arg(long)]
    moving: bool,
    /// Configurations: presets, rungs, knobs, or a comma-separated list of names from knobs.
    #[arg(long, default_value = "knobs")]
    sweep: String,
    /// Unmeasured frames per configuration and gaze before measuring.
    #[arg(long, default_value_t = 3)]
    warmup: u32,
    /// Measured frames per configuration and gaze.
    #[arg(long, default_value_t = 10, value_parser = clap::value_parser!(u32).range(1..=100000))]
    frames: u32,
    /// Pupil diameter, mm.
    #[arg(long, default_value_t = fovea::render::DEFAULT_PUPIL_MM)]
    pupil_mm: f32,
    #[arg(long, default_value_t = 53.0)]
    display_width_cm: f64,
    #[arg(long, default_value_t = 60.0)]
    distance_cm: f64,
    /// Output directory for bench.json, bench.md and bench.svg.
    #[arg(long)]
    out: PathBuf,
}

/// Single-knob overrides, the same names as the protocol's `settings` message.
#[derive(clap::Args)]
struct Knobs {
    /// Foveated sampling on or off.
    #[arg(long)]
    foveation: Option<bool>,
    /// MAR slope m (degrees per degree of eccentricity).
    #[arg(long)]
    mar_slope: Option<f64>,
    /// MAR at the fovea w0, degrees.
    #[arg(long)]
    mar_w0_deg: Option<f64>,
    /// Minimum sampling probability ξ in [0, 1].
    #[arg(long)]
    min_probability: Option<f64>,
    /// Probability form: linear (thesis eq. 2) or density ((w_min/w)²).
    #[arg(long, value_parser = parse_enum::<fovea::optics::acuity::ProbabilityForm>)]
    probability: Option<fovea::optics::acuity::ProbabilityForm>,
    #[arg(long)]
    saliency: Option<bool>,
    #[arg(long)]
    motion: Option<bool>,
    /// blue (WSE rank map) or white.
    #[arg(long, value_parser = parse_enum::<fovea::foveation::Noise>)]
    noise: Option<fovea::foveation::Noise>,
    #[arg(long)]
    reprojection: Option<bool>,
    #[arg(long)]
    max_history_age: Option<u32>,
    /// nearest or sibson.
    #[arg(long, value_parser = parse_enum::<fovea::foveation::Reconstruction>)]
    reconstruction: Option<fovea::foveation::Reconstruction>,
    /// Sibson window bound in pixels (0: from ξ).
    #[arg(long)]
    sibson_window: Option<u32>,
    #[arg(long)]
    compaction: Option<bool>,
    /// Translucency rung: opaque, normal_blur, screen, hierarchical, brute_force.
    #[arg(long, value_parser = parse_enum::<fovea::foveation::Rung>)]
    translucency: Option<fovea::foveation::Rung>,
    /// Finest photon-pyramid level a cluster may come from (0–6; 0: single photons).
    #[arg(long)]
    cut_level: Option<u32>,
    /// Use a cluster whole when its extent < ε × its distance.
    #[arg(long)]
    cut_epsilon: Option<f64>,
    /// Blur by the eye's depth of field.
    #[arg(long)]
    dof: Option<bool>,
    /// none, samples or probability.
    #[arg(long, value_parser = parse_enum::<fovea::foveation::settings::Overlay>)]
    overlay: Option<fovea::foveation::settings::Overlay>,
}

impl Knobs {
    fn patch(&self) -> fovea::protocol::SettingsPatch {
        fovea::protocol::SettingsPatch {
            preset: None,
            foveation: self.foveation,
            mar_slope: self.mar_slope,
            mar_w0_deg: self.mar_w0_deg,
            min_probability: self.min_probability,
            probability: self.probability,
            saliency: self.saliency,
            motion: self.motion,
            noise: self.noise,
            reprojection: self.reprojection,
            max_history_age: self.max_history_age,
            reconstruction: self.reconstruction,
            sibson_window: self.sibson_window,
            compaction: self.compaction,
            translucency: self.translucency,
            cut_level: self.cut_level,
            cut_epsilon: self.cut_epsilon,
            dof: self.dof,
            overlay: self.overlay,
            prediction: None,
            prediction_horizon_ms: None,
        }
    }
}

/// Parses a snake_case name of any of our serde enums.
fn parse_enum<T: serde::de::DeserializeOwned>(s: &str) -> Result<T, String> {
    serde_json::from_value(serde_json::Value::String(s.to_string())).map_err(|e| format!("{s:?}: {e}"))
}

fn parse_gaze(s: &str) -> Result<[f32; 2], String> {
    let v: Vec<f32> = s.split(',').map(|p| p.trim().parse::<f32>()).collect::<Result<_, _>>().map_err(|e| format!("{s:?}: {e}"))?;
    match v.as_slice() {
        [x, y] if (0.0..=1.0).contains(x) && (0.0..=1.0).contains(y) => Ok([*x, *y]),
        [_, _] => Err(format!("{s:?}: both coordinates must lie in [0, 1]")),
        _ => Err(format!("{s:?}: expected X,Y")),
    }
}

fn parse_vec3(s: &str) -> Result<Vec3, String> {
    let v: Vec<f32> = s.split(',').map(|p| p.trim().parse::<f32>()).collect::<Result<_, _>>().map_err(|e| format!("{s:?}: {e}"))?;
    match v.as_slice() {
        [x, y, z] if Vec3::new(*x, *y, *z).try_normalize().is_some() => Ok(Vec3::new(*x, *y, *z)),
        [_, _, _] => Err(format!("{s:?}: the direction must be finite and non-zero")),
        _ => Err(format!("{s:?}: expected X,Y,Z")),
    }
}

fn main() -> Result<()> {
    tracing_subscriber::fmt()
        .with_env_filter(
            tracing_subscriber::EnvFilter::try_from_default_env()
                .unwrap_or_else(|_| "fovea=info,wgpu_core=warn,wgpu_hal=warn".into()),
        )
        .with_writer(std::io::stderr)
        .init();
    match Cli::parse().command {
        Command::Serve { addr, record_dir, max_sessions, stall_timeout_s } => serve(
            addr,
            fovea::server::ServerOptions {
                record_dir,
                max_sessions: max_sessions as usize,
                stall_timeout: std::time::Duration::from_secs_f64(stall_timeout_s.clamp(0.1, 3600.0)),
            },
        ),
        Command::Bench(args) => bench(args),
        Command::Replay(args) => replay(args),
        Command::Gaze(args) => gaze(args),
        Command::Load(args) => load(args),
        Command::Render {
            scene,
            width,
            height,
            gaze,
            no_marker,
            light,
            out,
            explain,
            quality,
            preset,
            frames,
            pupil_mm,
            display_width_cm,
            distance_cm,
            knobs,
        } => {
            if explain {
                let scene = fovea::scene::Scene::builtin(&scene)?;
                print!("{}", fovea::scene::Plan::of(&scene, width, height));
                return Ok(());
            }
            let out = out.context("--out is required")?;
            let mut settings = fovea::foveation::Settings::preset(&preset)
                .with_context(|| format!("unknown preset {preset:?}; available: {}", fovea::foveation::PRESETS.join(", ")))?;
            let patch = knobs.patch();
            let limits = fovea::protocol::Limits::default();
            // The same validation a `settings` message gets.
            let mut msg = serde_json::to_value(&patch)?;
            msg["type"] = "settings".into();
            fovea::protocol::parse_client_message(&msg.to_string(), &limits).map_err(|e| anyhow::anyhow!("{}", e.message))?;
            if !(limits.pupil_mm[0]..=limits.pupil_mm[1]).contains(&f64::from(pupil_mm)) {
                bail!("--pupil-mm {pupil_mm} is outside [{}, {}]", limits.pupil_mm[0], limits.pupil_mm[1]);
            }
            settings.apply(&patch).map_err(|p| anyhow::anyhow!("unknown preset {p}"))?;
            let mut request = FrameRequest::new(&scene, width, height);
            request.gaze = gaze;
            request.marker = !no_marker;
            request.to_light = light;
            request.settings = settings;
            request.pupil_mm = pupil_mm;
            request.display = fovea::protocol::Display { width_cm: display_width_cm, distance_cm };
            render(request, &out, quality, frames)
        }
    }
}

fn parse_size(s: &str) -> Result<(u32, u32)> {
    let (w, h) = s.trim().split_once('x').with_context(|| format!("{s:?}: expected WxH"))?;
    let (w, h): (u32, u32) = (w.parse().with_context(|| format!("{s:?}: width"))?, h.parse().with_context(|| format!("{s:?}: height"))?);
    if w == 0 || h == 0 || w > 8192 || h > 8192 {
        bail!("{s:?}: sizes run from 1x1 to 8192x8192");
    }
    Ok((w, h))
}

fn bench(a: BenchArgs) -> Result<()> {
    use std::sync::atomic::{AtomicBool, Ordering};
    use std::sync::Arc;
    let configs = fovea::bench::sweep(&a.sweep).map_err(anyhow::Error::msg)?;
    let mut sizes = vec![parse_size(&format!("{}x{}", a.width, a.height))?];
    if let Some(more) = &a.sizes {
        for s in more.split(',') {
            sizes.push(parse_size(s)?);
        }
    }
    let gazes = a.gaze.split(';').map(parse_gaze).collect::<Result<Vec<_>, _>>().map_err(anyhow::Error::msg)?;
    let scenes: Vec<String> = a.scene.split(',').map(|s| s.trim().to_string()).collect();
    for s in &scenes {
        fovea::scene::Scene::builtin(s)?;
    }
    let opts = fovea::bench::BenchOptions {
        scenes,
        sizes,
        gazes,
        moving: a.moving,
        warmup: a.warmup,
        frames: a.frames,
        configs,
        display: fovea::protocol::Display { width_cm: a.display_width_cm, distance_cm: a.distance_cm },
        pupil_mm: a.pupil_mm,
    };
    let stop = Arc::new(AtomicBool::new(false));
    let flag = stop.clone();
    ctrlc::set_handler(move || {
        eprintln!("\nstopping after this frame; writing the results so far");
        flag.store(true, Ordering::Relaxed);
    })
    .context("installing the Ctrl-C handler")?;
    let mut renderer = Renderer::new().context("opening the GPU")?;
    eprintln!("adapter: {}", renderer.adapter());
    let started = std::time::Instant::now();
    let mut last_draw = std::time::Instant::now() - std::time::Duration::from_secs(1);
    let mut progress = |done: usize, total: usize, what: &str| {
        if last_draw.elapsed().as_millis() < 200 && done < total {
            return;
        }
        last_draw = std::time::Instant::now();
        let frac = done as f64 / total.max(1) as f64;
        let eta = if frac > 0.0 { started.elapsed().as_secs_f64() * (1.0 - frac) / frac } else { 0.0 };
        let bar: String = (0..30).map(|i| if (i as f64) < frac * 30.0 { '#' } else { '-' }).collect();
        eprint!("\r[{bar}] {done}/{total} ({:.0}%) ETA {:.0}s  {what:<28}", frac * 100.0, eta);
    };
    let report = fovea::bench::run(&mut renderer, &opts, &stop, &mut progress)?;
    eprintln!();
    fovea::bench::write_reports(&report, &a.out).with_context(|| format!("writing reports to {}", a.out.display()))?;
    println!("{}", report.markdown());
    eprintln!("wrote {}/bench.json, bench.md, bench.svg{}", a.out.display(), if report.interrupted { " (interrupted)" } else { "" });
    Ok(())
}

fn replay(a: ReplayArgs) -> Result<()> {
    let rec = a.recording.load()?;
    let url = url_is_allowed(&a.url, &a.allow_host)?;
    let opts = fovea::client::replay::ReplayOptions {
        url,
        hello: fovea::protocol::Hello { scene: a.scene.clone(), preset: a.preset.clone(), width: a.width, height: a.height, ..Default::default() },
        speed: a.speed,
        start_ms: a.start_s * 1e3,
        duration_ms: a.duration_s.map(|d| d * 1e3),
        loops: a.loops,
        keep_images: a.save_frames,
    };
    let runtime = tokio::runtime::Runtime::new()?;
    let started = std::time::Instant::now();
    let (frames, summary) = runtime.block_on(fovea::client::replay::replay(&rec.samples, &opts, |done, total| {
        eprint!("\rsent {done}/{total} samples ({:.0}%), {:.1} s", 100.0 * done as f64 / total.max(1) as f64, started.elapsed().as_secs_f64());
    }))?;
    eprintln!();
    std::fs::create_dir_all(&a.out).with_context(|| format!("creating {}", a.out.display()))?;
    std::fs::write(a.out.join("frames.csv"), fovea::client::replay::frames_csv(&frames))?;
    std::fs::write(a.out.join("summary.json"), serde_json::to_string_pretty(&summary)?)?;
    if a.save_frames {
        let dir = a.out.join("frames");
        std::fs::create_dir_all(&dir)?;
        for f in &frames {
            if let Some(img) = &f.image {
                std::fs::write(dir.join(format!("{:06}.jpg", f.frame)), img)?;
            }
        }
    }
    println!("{}", serde_json::to_string_pretty(&summary)?);
    eprintln!("wrote {}/frames.csv and summary.json", a.out.display());
    Ok(())
}

fn load(a: LoadArgs) -> Result<()> {
    let url = url_is_allowed(&a.url, &a.allow_host)?;
    let recording = match &a.recording {
        Some(file) => {
            let args = RecordingArgs {
                file: file.clone(),
                screen: a.screen.clone(),
                format: None,
                pupil_median_mm: 4.0,
                time_col: "t_ms".into(),
                x_col: "x".into(),
                y_col: "y".into(),
                pupil_col: "pupil_mm".into(),
                time_unit: "ms".into(),
                pixels: false,
            };
            Some(std::sync::Arc::new(args.load()?.samples))
        }
        None => None,
    };
    let counts: Vec<usize> = match &a.sweep {
        Some(s) => s.split(',').map(|n| n.trim().parse::<usize>()).collect::<Result<_, _>>().context("--sweep: session counts like 1,2,4,8")?,
        None => vec![a.sessions],
    };
    if counts.iter().any(|n| *n == 0 || *n > 256) {
        bail!("session counts run from 1 to 256");
    }
    let duration = std::time::Duration::from_secs_f64(a.duration.clamp(1.0, 600.0));
    let runtime = tokio::runtime::Runtime::new()?;
    let mut reports = Vec::new();
    std::fs::create_dir_all(&a.out).with_context(|| format!("creating {}", a.out.display()))?;
    for n in counts {
        let opts = fovea::client::load::LoadOptions {
            url: url.clone(),
            sessions: n,
            duration,
            ramp_up: std::time::Duration::from_secs_f64(a.ramp_up_ms.max(0.0) / 1000.0),
            rate_hz: a.rate_hz,
            hello: fovea::protocol::Hello { scene: a.scene.clone(), preset: a.preset.clone(), width: a.width, height: a.height, ..Default::default() },
            seed: a.seed,
            recording: recording.clone(),
        };
        let total = duration.as_secs_f64();
        let report = runtime.block_on(fovea::client::load::run(&opts, move |sessions, t| {
            eprint!("\r{sessions} sessions: {t:.0}/{total:.0} s");
        }));
        eprintln!();
        println!(
            "{} sessions: {} frames, {:.2} fps total, {:.2}–{:.2} fps per session (fairness {:.2}), gaze→frame p50 {:.1} p95 {:.1} p99 {:.1} max {:.1} ms; render p50 {:.1} ms; samples coalesced {}; errors {}, refused {}, failed {}",
            n,
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
        std::fs::write(a.out.join(format!("load-{n}.svg")), fovea::client::load::svg(&report))?;
        reports.push(report);
    }
    let capacity = reports
        .iter()
        .filter(|r| r.latency_ms.p95 <= a.budget_ms && r.fps_min >= a.min_fps && r.refused == 0 && r.connection_failures == 0)
        .map(|r| r.sessions)
        .max();
    let json = serde_json::json!({
        "url": url,
        "scene": a.scene, "preset": a.preset, "width": a.width, "height": a.height, "rate_hz": a.rate_hz,
        "budget": { "p95_ms": a.budget_ms, "min_fps": a.min_fps },
        "capacity_sessions": capacity,
        "runs": reports,
    });
    std::fs::write(a.out.join("load.json"), serde_json::to_string_pretty(&json)?)?;
    if let Some(last) = reports.last() {
        std::fs::write(a.out.join("load.svg"), fovea::client::load::svg(last))?;
    }
    match capacity {
        Some(c) => println!("capacity within budget (p95 ≤ {} ms, ≥ {} fps per session): {c} sessions", a.budget_ms, a.min_fps),
        None => println!("no session count met the budget (p95 ≤ {} ms, ≥ {} fps per session)", a.budget_ms, a.min_fps),
    }
    eprintln!("wrote {}/load.json and load.svg", a.out.display());
    Ok(())
}

/// Replay and load generate traffic: only loopback targets, or hosts named with --allow-host.
fn url_is_allowed(url: &str, allowed: &[String]) -> Result<String> {
    let rest = url.strip_prefix("ws://").with_context(|| format!("{url:?}: expected ws://HOST:PORT/ws"))?;
    let host = if rest.starts_with('[') { rest.split(']').next().map(|h| format!("{h}]")).unwrap_or_default() } else { rest.split(['/', ':']).next().unwrap_or("").to_string() };
    let loopback = host == "localhost" || host == "[::1]" || host.parse::<std::net::Ipv4Addr>().is_ok_and(|ip| ip.is_loopback());
    if !loopback && !allowed.iter().any(|a| *a == host) {
        bail!("{url:?}: only loopback servers (127.0.0.0/8, localhost, [::1]) or hosts given with --allow-host may be targeted");
    }
    Ok(url.to_string())
}

fn gaze(a: GazeArgs) -> Result<()> {
    let rec = a.recording.load()?;
    let (w, h) = a.recording.screen.as_deref().map(parse_size).transpose()?.unwrap_or((1920, 1080));
    let viewing = fovea::optics::acuity::Viewing { width: w, height: h, width_cm: a.display_width_cm, distance_cm: a.distance_cm };
    let horizons: Vec<f64> = a.horizons.split(',').map(|s| s.trim().parse::<f64>()).collect::<Result<_, _>>().context("--horizons: numbers in ms")?;
    let rows = fovea::gaze::evaluate::evaluate(&rec.samples, &viewing, &horizons);
    println!("{}", fovea::gaze::evaluate::markdown(&rows));
    Ok(())
}

fn serve(addr: SocketAddr, options: fovea::server::ServerOptions) -> Result<()> {
    let mut renderer = Renderer::new().context("opening the GPU")?;
    renderer.load_scene(fovea::scene::DEFAULT_SCENE).context("loading the default scene")?;
    let (render, render_thread) = RenderThread::spawn(renderer).context("starting the render thread")?;
    let runtime = tokio::runtime::Runtime::new().context("starting the async runtime")?;
    runtime.block_on(async move {
        let listener = tokio::net::TcpListener::bind(addr).await.with_context(|| format!("binding {addr}"))?;
        let local = listener.local_addr()?;
        println!("fovea listening on http://{local}/");
        let shutdown = CancellationToken::new();
        tokio::spawn(stop_on_signal(shutdown.clone()));
        fovea::server::run_with(listener, render, shutdown, options).await.context("serving")?;
        tracing::info!("server stopped");
        anyhow::Ok(())
    })?;
    // Every RenderHandle is gone with the server, so the render thread is finishing too.
    let _ = render_thread.join();
    Ok(())
}

async fn stop_on_signal(shutdown: CancellationToken) {
    let ctrl_c = tokio::signal::ctrl_c();
    #[cfg(unix)]
    {
        let mut term = match tokio::signal::unix::signal(tokio::signal::unix::SignalKind::terminate()) {
            Ok(t) => t,
            Err(e) => {
                tracing::warn!("cannot watch SIGTERM: {e}");
                let _ = ctrl_c.await;
                shutdown.cancel();
                return;
            }
        };
        tokio::select! {
            _ = ctrl_c => {}
            _ = term.recv() => {}
        }
    }
    #[cfg(not(unix))]
    let _ = ctrl_c.await;
    tracing::info!("shutting down: closing sessions");
    shutdown.cancel();
}

fn render(request: FrameRequest, out: &std::path::Path, quality: u8, frames: u32) -> Result<()> {
    let ext = out.extension().and_then(|e| e.to_str()).map(str::to_ascii_lowercase);
    let codec = match ext.as_deref() {
        Some("png") => Codec::Png,
        Some("jpg" | "jpeg") => Codec::Jpeg,
        _ => bail!("{}: the output must end in .png, .jpg or .jpeg", out.display()),
    };
    let mut renderer = Renderer::new().context("opening the GPU")?;
    eprintln!("adapter: {}", renderer.adapter());
    let mut frame = renderer.render(&request).with_context(|| format!("rendering scene {:?}", request.scene))?;
    let mut times = Vec::new();
    for _ in 1..frames {
        frame = renderer.render(&request).with_context(|| format!("rendering scene {:?}", request.scene))?;
        times.push(frame.render_ms);
    }
    if times.len() >= 3 {
        times.sort_by(|a, b| a.total_cmp(b));
        eprintln!(
            "render ms over frames 2..{frames}: median {:.2}, min {:.2}, max {:.2}",
            times[times.len() / 2],
            times[0],
            times[times.len() - 1]
        );
    }
    let started = std::time::Instant::now();
    let bytes = fovea::encode::encode(&frame.rgba, frame.width, frame.height, codec, quality)?;
    let encode_ms = started.elapsed().as_secs_f64() * 1e3;
    std::fs::write(out, &bytes).with_context(|| format!("writing {}", out.display()))?;
    if !frame.passes_ms.is_empty() {
        let passes: Vec<String> = frame.passes_ms.iter().map(|(k, v)| format!("{k} {v:.2}")).collect();
        eprintln!("GPU ms per pass: {}", passes.join(", "));
    }
    eprintln!(
        "wrote {} ({}x{}, {} bytes, preset {}, sampled {:.1}%): render {:.2} ms, readback {:.2} ms, encode {:.2} ms",
        out.display(),
        frame.width,
        frame.height,
        bytes.len(),
        request.settings.preset,
        frame.sampled * 100.0,
        frame.render_ms,
        frame.readback_ms,
        encode_ms
    );
    Ok(())
}
