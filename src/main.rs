//! The `fovea` command line: `serve` and `render` here, the other subcommands in `cli/`.

mod cli;

use std::path::PathBuf;

use anyhow::{bail, Context, Result};
use clap::{Parser, Subcommand};
use glam::Vec3;

use fovea::protocol::Codec;
use fovea::render::{FrameRequest, Renderer};

use cli::bench::{bench, BenchArgs};
use cli::gaze::{gaze, replay, GazeArgs, ReplayArgs};
use cli::load::{load, LoadArgs};
use cli::parse::{parse_gaze, parse_size, parse_vec3};
use cli::radiosity::{radiosity, RadiosityArgs};

#[derive(Parser)]
#[command(
    name = "fovea",
    version,
    about = "Gaze-streaming rendering service: frames that follow the eye, rendered headless on the GPU and streamed to a browser"
)]
struct Cli {
    #[command(subcommand)]
    command: Command,
    /// Log format on stderr: text for people, json (one object per line) for log collectors.
    /// Colours only when stderr is a terminal.
    #[arg(long, global = true, value_enum, default_value_t = LogFormat::Text)]
    log_format: LogFormat,
}

#[derive(Clone, Copy, clap::ValueEnum)]
enum LogFormat {
    Text,
    Json,
}

#[derive(Subcommand)]
enum Command {
    /// Serve the web client on / and gaze-driven frames over the WebSocket /ws.
    ///
    /// Logs go to stderr (RUST_LOG=fovea=debug for more); the first line on stdout is
    /// "fovea listening on http://ADDR/", with the real port when --addr asks for port 0.
    Serve(cli::serve::ServeArgs),
    /// Render one frame to an image file, without a server.
    ///
    /// Quality knobs start from --preset; any knob flag then overrides that one knob. With
    /// --frames N the same gaze is rendered N times as one stream (so reprojection has history)
    /// and the last frame is written.
    Render {
        /// Built-in scene to render.
        #[arg(long, default_value = fovea::scene::DEFAULT_SCENE, value_parser = cli::parse::scene_names())]
        scene: String,
        /// A scene file of your own (docs/scenes.md) instead of a built-in scene; the meshes
        /// and glTF files it names are read from beside it (never from outside its folder).
        #[arg(long, conflicts_with_all = ["scene", "model"])]
        scene_file: Option<PathBuf>,
        /// A model file (.gltf, .glb, .ply, .obj) rendered as a scene: its own lights and
        /// camera, or a default key light and a camera framing its bounds.
        #[arg(long, conflicts_with = "scene")]
        model: Option<PathBuf>,
        /// Frame size WxH.
        #[arg(long, value_parser = parse_size, default_value = "640x480")]
        size: (u32, u32),
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
        /// With --explain: render the scene here both ways, foveated and shaded whole, and say
        /// whether foveation pays on this adapter at this size (what the server decides per frame).
        #[arg(long, requires = "explain")]
        measure: bool,
        /// JPEG quality 1–100.
        #[arg(long, default_value_t = 90, value_parser = clap::value_parser!(u8).range(1..=100))]
        quality: u8,
        /// Quality preset (the same default as a `serve` session).
        #[arg(long, value_enum, default_value_t = fovea::settings::Preset::DEFAULT)]
        preset: fovea::settings::Preset,
        /// Frames to render before writing the last one.
        #[arg(long, default_value_t = 1, value_parser = clap::value_parser!(u32).range(1..=10000))]
        frames: u32,
        /// Pupil diameter in mm (1–10); sets the depth of field.
        #[arg(long, default_value_t = fovea::render::DEFAULT_PUPIL_MM)]
        pupil_mm: f32,
        /// Physical width of the displayed frame, cm (1–1000, as `hello.display`).
        #[arg(long, default_value_t = 53.0, value_parser = cli::parse::display_width_cm)]
        display_width_cm: f64,
        /// Viewing distance, cm (1–10000, as `hello.display`).
        #[arg(long, default_value_t = 60.0, value_parser = cli::parse::distance_cm)]
        distance_cm: f64,
        /// Single-knob overrides: the protocol's `settings` knobs (docs/protocol.md).
        #[command(flatten)]
        knobs: fovea::settings::SettingsPatch,
    },
    /// Measure every preset and knob: frame time, per-pass GPU time, encode cost and the error
    /// against the reference render of the same frame; writes bench.json, bench.md, bench.svg.
    /// `--sweep codecs --gaze-file F` compares the encoders instead (codecs.json, .md, .svg).
    ///
    /// Ctrl-C stops after the current frame and still writes what was measured.
    Bench(BenchArgs),
    /// Stream a gaze recording to a server at its recorded timing and record every frame.
    ///
    /// Formats: EyeLink CSV (t_s, xpos, ypos, ps), Pupil Labs Core gaze_positions.csv, Pupil Labs
    /// Neon gaze.csv, Tobii-style (device_time_stamp, gaze_point_x, gaze_point_y,
    /// pupil_diameter), and generic CSV (t_ms, x, y, pupil_mm; see --time-col and friends).
    /// Track loss, blinks and samples far off the frame are not sent: the server keeps the last
    /// valid gaze. Writes DIR/frames.csv, DIR/summary.json and, with --save-frames, the images;
    /// Ctrl-C stops early and writes what came so far (summary.json says "interrupted").
    Replay(ReplayArgs),
    /// Score gaze prediction on recordings: the angular error at several horizons of holding
    /// the last sample, constant velocity and the server's predictor, per class (fixation,
    /// saccade, pursuit, post-gap, saccade onset), per recording and pooled
    /// (docs/gaze/prediction.md says how).
    Gaze(GazeArgs),
    /// Load-test a server: N concurrent sessions driven by the synthetic eye for a fixed time,
    /// acknowledging frames like real clients. Reports gaze-to-frame latency and the server's
    /// stage times as HDR percentiles, fps per session and in total, fairness, errors and
    /// refusals; writes DIR/load.json and its plots (load.svg/.png, and load-N.* per session
    /// count). Loopback targets unless --allow-host names the host.
    Load(LoadArgs),
    /// Solve a scene's radiosity in the foreground and report its convergence (elements,
    /// shots, time to 90% and 99% of the converged energy), then the frame time with the cached
    /// result against direct light only and radiosity off; writes DIR/radiosity.json, .md and
    /// the direct / with-radiosity images.
    Radiosity(RadiosityArgs),
    /// Redraw the plots of a bench.json, codecs.json or load.json (SVG and PNG beside it); a
    /// codecs report is rewritten too (json and md), its read-offs as this build computes them.
    Plot {
        /// A bench.json or codecs.json (fovea bench) or load.json (fovea load).
        file: PathBuf,
    },
}

fn main() -> Result<()> {
    // Mesa's Vulkan device-select layer looks for a Wayland display to rank GPUs and, on a
    // headless machine, prints "XDG_RUNTIME_DIR is invalid" for every instance; wgpu picks the
    // adapter itself. Set before any thread starts, so nothing reads the environment meanwhile.
    if std::env::var_os("NODEVICE_SELECT").is_none() {
        std::env::set_var("NODEVICE_SELECT", "1");
    }
    let cli = Cli::parse();
    let filter = tracing_subscriber::EnvFilter::try_from_default_env()
        .unwrap_or_else(|_| "fovea=info,wgpu_core=warn,wgpu_hal=warn".into());
    let logs = tracing_subscriber::fmt()
        .with_env_filter(filter)
        .with_writer(std::io::stderr);
    match cli.log_format {
        LogFormat::Json => logs.json().init(),
        LogFormat::Text => {
            use std::io::IsTerminal;
            logs.with_ansi(std::io::stderr().is_terminal()).init()
        }
    }
    match cli.command {
        Command::Serve(args) => cli::serve::serve(args),
        Command::Bench(args) => bench(args),
        Command::Replay(args) => replay(args),
        Command::Gaze(args) => gaze(args),
        Command::Load(args) => load(args),
        Command::Radiosity(args) => radiosity(args),
        Command::Plot { file } => plot(&file),
        Command::Render {
            scene,
            scene_file,
            model,
            size: (width, height),
            gaze,
            no_marker,
            light,
            out,
            explain,
            measure,
            quality,
            preset,
            frames,
            pupil_mm,
            display_width_cm,
            distance_cm,
            knobs,
        } => {
            // A wrong --out is refused before a model is loaded or the GPU opened.
            let target = match out {
                Some(out) if !explain => Some((image_codec(&out)?, out)),
                _ => None,
            };
            let own = scene_file
                .or(model)
                .map(|path| cli::scenes::load_own_scene(&path))
                .transpose()?;
            let scene = own.as_ref().map_or(scene, |s| s.name().to_string());
            // The same checks a `settings` message gets.
            let mut settings = fovea::settings::Settings::of(preset);
            settings.apply(&knobs)?;
            if explain {
                let s = match &own {
                    Some(s) => s.clone(),
                    None => fovea::scene::Scene::builtin(&scene)?,
                };
                print!("{}", fovea::scene::Plan::of(&s, width, height));
                let mut request = FrameRequest::new(&scene, width, height);
                request.gaze = gaze;
                request.settings = settings.render;
                return cli::scenes::explain_foveation(request, own, measure);
            }
            let (codec, out) = target.context("--out is required")?;
            let limits = fovea::protocol::Limits::default();
            if !(limits.pupil_mm[0]..=limits.pupil_mm[1]).contains(&f64::from(pupil_mm)) {
                bail!(
                    "--pupil-mm {pupil_mm} is outside [{}, {}]",
                    limits.pupil_mm[0],
                    limits.pupil_mm[1]
                );
            }
            eprintln!("preset {}", settings.label());
            let mut request = FrameRequest::new(&scene, width, height);
            request.gaze = gaze;
            request.marker = !no_marker;
            request.to_light = light;
            request.settings = settings.render;
            request.pupil_mm = pupil_mm;
            request.display = fovea::viewing::Display {
                width_cm: display_width_cm,
                distance_cm,
            };
            render(request, own, &out, codec, quality, frames)
        }
    }
}

fn plot(file: &std::path::Path) -> Result<()> {
    let text =
        std::fs::read_to_string(file).with_context(|| format!("reading {}", file.display()))?;
    let json: serde_json::Value =
        serde_json::from_str(&text).with_context(|| format!("parsing {}", file.display()))?;
    // A bare "load.json" has the empty path as its parent, which printed as "/load.svg".
    let dir = file
        .parent()
        .filter(|d| !d.as_os_str().is_empty())
        .unwrap_or(std::path::Path::new("."));
    if json.get("runs").is_some() {
        cli::load::plot_load(&json, dir)?;
        eprintln!("wrote {}/load.svg, load.png and load-N.*", dir.display());
    } else if json.get("records").is_some() {
        let report: fovea::bench::BenchReport = serde_json::from_value(json)
            .with_context(|| format!("{} is not a bench report", file.display()))?;
        let plot = fovea::plot::bench::BenchPlot::of(&report);
        fovea::plot::write(&plot, &dir.join("bench"))?;
        eprintln!("wrote {}/bench.svg and bench.png", dir.display());
    } else if json.get("equal_quality").is_some() {
        let mut report: fovea::bench::CodecReport = serde_json::from_value(json)
            .with_context(|| format!("{} is not a codecs report", file.display()))?;
        // A report from an earlier build gains the read-offs added since.
        report.finish();
        fovea::bench::write_codec_reports(&report, dir)
            .with_context(|| format!("writing reports to {}", dir.display()))?;
        eprintln!(
            "wrote {}/codecs.json, codecs.md, codecs.svg and codecs.png",
            dir.display()
        );
    } else {
        bail!(
            "{}: neither a bench.json, a codecs.json nor a load.json",
            file.display()
        );
    }
    Ok(())
}

/// The image format `fovea render` writes, from the output's extension.
fn image_codec(out: &std::path::Path) -> Result<Codec> {
    let ext = out
        .extension()
        .and_then(|e| e.to_str())
        .map(str::to_ascii_lowercase);
    Ok(match ext.as_deref() {
        Some("png") => Codec::Png,
        Some("jpg" | "jpeg") => Codec::Jpeg,
        _ => bail!(
            "{}: the output must end in .png, .jpg or .jpeg",
            out.display()
        ),
    })
}

fn render(
    request: FrameRequest,
    own: Option<fovea::scene::Scene>,
    out: &std::path::Path,
    codec: Codec,
    quality: u8,
    frames: u32,
) -> Result<()> {
    let mut renderer = Renderer::new().context("opening the GPU")?;
    eprintln!("adapter: {}", renderer.adapter());
    if let Some(scene) = own {
        renderer.add_scene(scene)?;
    }
    // A still image shows the converged solution; the server streams the refining preview.
    if let Some(solve) = renderer.radiosity(&request.scene)? {
        eprintln!("radiosity: solving before rendering…");
        let snap = solve
            .wait(std::time::Duration::from_secs(3600))
            .context("radiosity produced no result")?;
        eprintln!(
            "radiosity: {} in {:.1} s: {} shots, {} elements, {:.2}% of the emitted power unshot",
            if snap.converged {
                "converged"
            } else {
                "stopped waiting"
            },
            snap.elapsed_s,
            snap.stats.shots,
            snap.stats.elements,
            100.0 * snap.stats.unshot_fraction
        );
    }
    let mut frame = renderer
        .render(&request)
        .with_context(|| format!("rendering scene {:?}", request.scene))?;
    let mut times = Vec::new();
    for _ in 1..frames {
        frame = renderer
            .render(&request)
            .with_context(|| format!("rendering scene {:?}", request.scene))?;
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
        let passes: Vec<String> = frame
            .passes_ms
            .iter()
            .map(|(k, v)| format!("{k} {v:.2}"))
            .collect();
        eprintln!("GPU ms per pass: {}", passes.join(", "));
    }
    eprintln!(
        "wrote {} ({}x{}, {} bytes, sampled {:.1}%): render {:.2} ms, readback {:.2} ms, encode {:.2} ms",
        out.display(),
        frame.width,
        frame.height,
        bytes.len(),
        frame.sampled * 100.0,
        frame.render_ms,
        frame.readback_ms,
        encode_ms
    );
    Ok(())
}

#[cfg(test)]
mod tests {
    use clap::CommandFactory;

    #[test]
    fn every_flag_of_every_command_is_described() {
        let cli = super::Cli::command();
        let mut bare = Vec::new();
        for sub in cli.get_subcommands() {
            assert!(
                sub.get_about().is_some(),
                "fovea {} has no description",
                sub.get_name()
            );
            for arg in sub.get_arguments() {
                if arg.is_hide_set() || matches!(arg.get_id().as_str(), "help" | "version") {
                    continue;
                }
                if arg.get_help().is_none() && arg.get_long_help().is_none() {
                    bare.push(format!("fovea {} --{}", sub.get_name(), arg.get_id()));
                }
            }
        }
        assert!(
            bare.is_empty(),
            "flags without a description:\n{}",
            bare.join("\n")
        );
    }

    #[test]
    fn sizes_and_durations_have_one_spelling() {
        let cli = super::Cli::command();
        for sub in cli.get_subcommands() {
            for arg in sub.get_arguments() {
                let long = arg.get_long().unwrap_or_default();
                assert!(
                    !matches!(
                        long,
                        "width" | "height" | "sizes" | "duration-s" | "start-s"
                    ),
                    "fovea {} --{long}: use --size WxH and --duration / --start",
                    sub.get_name()
                );
            }
        }
        cli.debug_assert();
    }
}
