//! `fovea radiosity`: solve a scene's radiosity in the foreground and report how it converges,
//! then what the cached result costs a frame.

use fovea::stats::median;
use std::path::PathBuf;
use std::time::{Duration, Instant};

use anyhow::{bail, Context, Result};

use fovea::radiosity::{Options, Solver, Stats};
use fovea::render::{FrameRequest, Renderer};
use fovea::scene::{Plan, RadiosityMode, Scene};
use fovea::settings::{Preset, RenderSettings};

use super::parse::parse_size;

#[derive(clap::Args)]
pub struct RadiosityArgs {
    /// A built-in scene whose plan runs radiosity.
    #[arg(long, default_value = "cornell")]
    scene: String,
    /// Directory for radiosity.json, radiosity.md and the direct / with-radiosity images.
    #[arg(long)]
    out: PathBuf,
    /// Frame size WxH for the frame-time comparison and the images.
    #[arg(long, default_value = "640x480")]
    size: String,
    /// Frames per configuration for the frame-time comparison, after one warm-up (0 skips it).
    #[arg(long, default_value_t = 10)]
    frames: u32,
    /// Solver threads (0: all cores).
    #[arg(long, default_value_t = 0)]
    threads: usize,
    /// Visibility: 0 for shadow rays against a BVH (the product's), or N for the seeds'
    /// alternative, the scene rasterised into a cube of N×N depth maps around each shooter.
    #[arg(long, default_value_t = 0)]
    cube: usize,
}

/// The first time the reflected power reaches `share` of its converged value.
fn time_to(curve: &[(f64, Stats)], share: f64) -> Option<(f64, u32)> {
    let last = curve.last()?.1.reflected;
    curve
        .iter()
        .find(|(_, s)| s.reflected >= share * last)
        .map(|(t, s)| (*t, s.shots))
}

pub fn radiosity(a: RadiosityArgs) -> Result<()> {
    let (w, h) = parse_size(&a.size)?;
    let scene = Scene::builtin(&a.scene)?;
    let plan = Plan::of(&scene, w, h);
    if !plan.radiosity {
        bail!("scene {:?}: radiosity {}", a.scene, plan.radiosity_reason);
    }
    std::fs::create_dir_all(&a.out).with_context(|| format!("creating {}", a.out.display()))?;
    let options = Options {
        stop_fraction: scene.file.radiosity.map_or(0.001, |r| r.stop_fraction),
        threads: a.threads,
        sun: fovea::scene::plan::radiosity_sun(&scene),
        visibility: match a.cube {
            0 => fovea::radiosity::Visibility::Rays,
            resolution => fovea::radiosity::Visibility::Cube { resolution },
        },
        ..Options::default()
    };
    let surfaces = scene.radiosity_surfaces();
    let started = Instant::now();
    let mut solver = Solver::new(&surfaces, options)?;
    let setup_s = started.elapsed().as_secs_f64();
    let first = solver.stats();
    eprintln!(
        "{}: {} patches, {} elements, {} receiving samples (set up in {setup_s:.2} s)",
        a.scene, first.patches, first.elements, first.vertices
    );
    let started = Instant::now();
    let mut curve = vec![(0.0, first)];
    let mut last_print = Instant::now();
    while !solver.converged() && solver.step().is_some() {
        let stats = solver.stats();
        curve.push((started.elapsed().as_secs_f64(), stats));
        if last_print.elapsed() >= Duration::from_secs(1) {
            eprintln!(
                "  {:>6.1} s: {} shots, {} elements, {:.2}% of the emitted power unshot",
                started.elapsed().as_secs_f64(),
                stats.shots,
                stats.elements,
                100.0 * stats.unshot_fraction
            );
            last_print = Instant::now();
        }
    }
    let (total_s, end) = *curve.last().context("no shots")?;
    let t90 = time_to(&curve, 0.9);
    let t99 = time_to(&curve, 0.99);
    let unshot_below = |f: f64| {
        curve
            .iter()
            .find(|(_, s)| s.unshot_fraction < f)
            .map(|(t, s)| (*t, s.shots))
    };
    let (u10, u1) = (unshot_below(0.1), unshot_below(0.01));
    eprintln!(
        "converged in {total_s:.2} s: {} shots, {} elements; 90% of the reflected energy after {:?}, 99% after {:?}",
        end.shots, end.elements, t90, t99
    );

    // Frame cost of the cached result: the same frames with interreflection, with the area
    // light's direct part only, and with radiosity off in the scene file.
    let mut rows = Vec::new();
    if a.frames > 0 {
        let mut renderer = Renderer::new().context("opening the GPU")?;
        let solve = renderer
            .radiosity(&a.scene)?
            .context("no radiosity solve")?;
        solve
            .wait(Duration::from_secs(3600))
            .context("radiosity produced no result")?;
        let mut off = scene.file.clone();
        off.name = format!("{}-no-radiosity", a.scene);
        if let Some(r) = off.radiosity.as_mut() {
            r.mode = RadiosityMode::Off;
        }
        renderer.add_scene(Scene::from_json(&serde_json::to_string(&off)?)?)?;
        let configs = [
            ("radiosity (cached)", a.scene.as_str(), true),
            ("direct light only", a.scene.as_str(), false),
            ("radiosity off", off.name.as_str(), true),
        ];
        for preset in ["full", "balanced"] {
            for (k, (label, name, indirect)) in configs.iter().enumerate() {
                let mut req = FrameRequest::new(name, w, h);
                req.settings = RenderSettings::of(Preset::from_name(preset).context("preset")?);
                req.settings.indirect = *indirect;
                req.marker = false;
                req.stream = 100 + k as u64;
                let mut times = Vec::new();
                let mut frame = renderer.render(&req)?;
                for _ in 0..a.frames {
                    frame = renderer.render(&req)?;
                    times.push(frame.render_ms);
                }
                let ms = median(times);
                eprintln!("  {preset:>8} {label:<20} {ms:8.1} ms");
                if preset == "full" && k < 2 {
                    let file = a.out.join(if *indirect {
                        "radiosity.png"
                    } else {
                        "direct.png"
                    });
                    let png = fovea::encode::encode(
                        &frame.rgba,
                        frame.width,
                        frame.height,
                        fovea::protocol::Codec::Png,
                        90,
                    )?;
                    std::fs::write(&file, png)
                        .with_context(|| format!("writing {}", file.display()))?;
                }
                rows.push((preset, *label, ms));
            }
        }
    }

    let at = |t: Option<(f64, u32)>| {
        t.map_or(
            serde_json::Value::Null,
            |(s, n)| serde_json::json!({ "seconds": s, "shots": n }),
        )
    };
    let json = serde_json::json!({
        "scene": a.scene,
        "machine": std::env::consts::ARCH,
        "threads": options.threads,
        "visibility": format!("{:?}", options.visibility),
        "patches": end.patches,
        "elements_initial": first.elements,
        "elements": end.elements,
        "receiving_samples": end.vertices,
        "shots": end.shots,
        "setup_s": setup_s,
        "total_s": total_s,
        "unshot_fraction": end.unshot_fraction,
        "to_90_percent_of_reflected": at(t90),
        "to_99_percent_of_reflected": at(t99),
        "unshot_below_10_percent": at(u10),
        "unshot_below_1_percent": at(u1),
        "frames": rows.iter().map(|(p, l, ms)| serde_json::json!({ "preset": p, "config": l, "render_ms_median": ms })).collect::<Vec<_>>(),
        "curve": curve.iter().step_by((curve.len() / 200).max(1)).map(|(t, s)| serde_json::json!([t, s.shots, s.reflected / end.reflected.max(1e-30), s.unshot_fraction])).collect::<Vec<_>>(),
    });
    std::fs::write(
        a.out.join("radiosity.json"),
        serde_json::to_string_pretty(&json)?,
    )?;
    let fmt = |t: Option<(f64, u32)>| {
        t.map_or("–".to_string(), |(s, n)| format!("{s:.2} s ({n} shots)"))
    };
    let mut md = format!(
        "# Radiosity: `{}` ({:?} visibility)\n\n{} patches; {} elements at the start, {} after adaptive subdivision; {} receiving samples.\n\n\
         | | time |\n|---|---|\n| set-up (elements, BVH) | {:.0} ms |\n| 90% of the converged reflected energy | {} |\n\
         | 99% of the converged reflected energy | {} |\n| unshot < 10% of emitted | {} |\n| unshot < 1% of emitted | {} |\n\
         | converged (unshot < {}%) | {total_s:.2} s ({} shots) |\n",
        a.scene, options.visibility, end.patches, first.elements, end.elements, end.vertices, setup_s * 1e3, fmt(t90), fmt(t99), fmt(u10), fmt(u1),
        100.0 * options.stop_fraction, end.shots
    );
    if !rows.is_empty() {
        md.push_str(&format!("\nMedian render time per frame at {w}x{h} over {} frames:\n\n| preset | configuration | render ms |\n|---|---|---|\n", a.frames));
        for (p, l, ms) in &rows {
            md.push_str(&format!("| {p} | {l} | {ms:.1} |\n"));
        }
    }
    std::fs::write(a.out.join("radiosity.md"), &md)?;
    println!("{md}");
    eprintln!("wrote {}", a.out.display());
    Ok(())
}
