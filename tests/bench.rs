//! The sweep on a tiny frame with two configurations: it runs, and writes a valid JSON report,
//! a Markdown table and an SVG plot (their structure is asserted, never their timings).

use std::sync::atomic::AtomicBool;

use fovea::bench::{run, sweep, write_reports, BenchOptions, GroundTruth};
use fovea::protocol::Display;
use fovea::render::Renderer;

/// One scene at one size, the gaze at the centre, still, the default display and pupil.
fn options(scene: &str, size: (u32, u32), warmup: u32, frames: u32, configs: &str) -> BenchOptions {
    BenchOptions {
        scenes: vec![scene.into()],
        sizes: vec![size],
        gazes: vec![[0.5, 0.5]],
        moving: false,
        warmup,
        frames,
        configs: sweep(configs).unwrap(),
        display: Display::default(),
        pupil_mm: 4.0,
        against: None,
    }
}

#[test]
fn a_tiny_sweep_writes_json_markdown_and_svg() {
    let mut renderer = Renderer::new().unwrap_or_else(|e| panic!("GPU tests need an adapter: {e}"));
    let opts = options("bunny-marble", (64, 64), 1, 2, "full,fast");
    let mut calls = 0;
    let report = run(
        &mut renderer,
        &opts,
        &AtomicBool::new(false),
        &mut |done, total, _| {
            assert!(done <= total);
            calls += 1;
        },
    )
    .unwrap();
    assert!(calls > 0, "progress is reported");
    assert_eq!(report.records.len(), 2);
    let dir = std::env::temp_dir().join(format!("fovea-bench-{}", std::process::id()));
    write_reports(&report, &dir).unwrap();

    let json: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(dir.join("bench.json")).unwrap()).unwrap();
    assert!(json["machine"]["adapter"]
        .as_str()
        .is_some_and(|a| !a.is_empty()));
    let records = json["records"].as_array().unwrap();
    assert_eq!(records.len(), 2);
    for r in records {
        for key in [
            "config",
            "frame_ms",
            "passes_ms",
            "encode_ms",
            "bytes",
            "sampled",
            "errors",
            "settings",
            "pareto",
        ] {
            assert!(r.get(key).is_some(), "record lacks {key}");
        }
        for e in [
            "psnr",
            "ssim",
            "flip",
            "psnr_pooled",
            "flip_pooled",
            "flip_fovea",
        ] {
            assert!(r["errors"][e].is_number(), "errors.{e}");
        }
    }
    let full = records.iter().find(|r| r["config"] == "full").unwrap();
    assert_eq!(
        full["speedup_vs_full"].as_f64(),
        Some(1.0),
        "full is its own baseline"
    );
    assert!(
        records.iter().any(|r| r["pareto"] == true),
        "someone is on the front"
    );

    let md = std::fs::read_to_string(dir.join("bench.md")).unwrap();
    assert!(md.contains("| ") && md.contains("full") && md.contains("fast") && md.contains("FLIP"));
    // What the server would do with `fast`'s frames follows from the measured ratio.
    let fast = records.iter().find(|r| r["config"] == "fast").unwrap();
    let speedup = fast["speedup_vs_full"].as_f64().unwrap();
    let table = &md[md
        .find("## Foveation against full")
        .expect("foveation section")..];
    let row = table
        .lines()
        .find(|l| l.contains("| fast |"))
        .expect("a row for fast");
    let expect = if speedup * 0.95 > 1.0 {
        "| foveates |"
    } else {
        "| shades whole |"
    };
    assert!(row.contains(expect), "{speedup}: {row}");
    // The per-pass table: a column per configuration, the foveated passes only under `fast`,
    // frame order (G-buffer before sampling before shading).
    let passes = &md[md.find("## Per pass").expect("per-pass section")..];
    assert!(passes.contains("| pass (ms) | full | fast |"), "{passes}");
    let sampling = passes
        .lines()
        .find(|l| l.starts_with("| sampling |"))
        .unwrap();
    assert!(sampling.starts_with("| sampling | – | "), "{sampling}");
    let at = |p: &str| passes.find(&format!("| {p} |")).unwrap();
    assert!(at("gbuffer") < at("sampling") && at("sampling") < at("shade"));
    let svg = std::fs::read_to_string(dir.join("bench.svg")).unwrap();
    assert!(
        svg.starts_with("<svg")
            && svg.trim_end().ends_with("</svg>")
            && svg.contains("<polyline")
            && svg.contains("fast")
    );
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn stopping_early_keeps_what_was_measured() {
    let mut renderer = Renderer::new().unwrap_or_else(|e| panic!("GPU tests need an adapter: {e}"));
    let opts = options("bunny", (32, 32), 0, 3, "full,fast");
    let stop = AtomicBool::new(false);
    let report = run(&mut renderer, &opts, &stop, &mut |done, _, _| {
        if done >= 4 {
            stop.store(true, std::sync::atomic::Ordering::Relaxed);
        }
    })
    .unwrap();
    assert!(report.interrupted);
    assert!(
        !report.records.is_empty() && report.records.iter().all(|r| r.frames >= 1),
        "partial results are kept"
    );
}

/// A scene lit by radiosity is measured once its solve has converged: while it refines, a
/// frame and the reference it is compared with would be lit by different solutions.
#[test]
fn a_radiosity_scene_is_measured_on_its_converged_solution() {
    let mut renderer = Renderer::new().unwrap_or_else(|e| panic!("GPU tests need an adapter: {e}"));
    let solve = renderer
        .radiosity("cornell")
        .unwrap()
        .expect("cornell has a solve");
    let opts = options("cornell", (32, 24), 0, 1, "full,balanced");
    let stop = AtomicBool::new(false);
    let (mut frames, mut before_converged) = (0, 0);
    run(&mut renderer, &opts, &stop, &mut |done, _, _| {
        if done > 0 {
            frames += 1;
            before_converged += usize::from(!solve.converged());
        }
    })
    .unwrap();
    // Progress is told after each configuration's frame (the reference's counted with it).
    assert!(frames >= 2, "both configurations: {frames}");
    assert_eq!(
        before_converged, 0,
        "frames rendered while the solve refined"
    );
}

#[test]
fn against_ground_truth_compares_the_reference_rung_and_every_configuration() {
    let mut renderer = Renderer::new().unwrap_or_else(|e| panic!("GPU tests need an adapter: {e}"));
    // Ground truth that is exactly our reference render: the reference must then score
    // perfectly against it, and every configuration exactly as against the reference.
    let mut req = fovea::render::FrameRequest::new("bunny-marble", 48, 32);
    req.settings = fovea::settings::RenderSettings::of(fovea::settings::Preset::Reference);
    let frame = renderer.render(&req).unwrap();
    let dir = std::env::temp_dir().join(format!("fovea-truth-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let png = dir.join("truth.png");
    std::fs::write(
        &png,
        fovea::encode::encode(&frame.rgba, 48, 32, fovea::protocol::Codec::Png, 90).unwrap(),
    )
    .unwrap();
    let opts = BenchOptions {
        against: Some(GroundTruth::load(&png).unwrap()),
        ..options("bunny-marble", (48, 32), 0, 1, "full,fast")
    };
    let report = run(
        &mut renderer,
        &opts,
        &AtomicBool::new(false),
        &mut |_, _, _| {},
    )
    .unwrap();
    let t = &report.reference_truth;
    assert_eq!(t.len(), 1);
    assert!(
        t[0].errors.flip == 0.0 && t[0].errors.ssim == 1.0,
        "{:?}",
        t[0].errors
    );
    for r in &report.records {
        let g = r
            .ground_truth
            .as_ref()
            .expect("every configuration is compared");
        assert_eq!(g.flip, r.errors.flip, "{}", r.config);
    }
    assert!(report.markdown().contains("Against physical ground truth"));

    // EXR is linear: 0.5 becomes sRGB 188, and values above 1 clamp to white.
    let exr = dir.join("truth.exr");
    let img = image::Rgb32FImage::from_fn(2, 1, |x, _| {
        image::Rgb(if x == 0 { [0.5; 3] } else { [4.0; 3] })
    });
    img.save(&exr).unwrap();
    let g = GroundTruth::load(&exr).unwrap();
    assert_eq!((g.width, g.height), (2, 1));
    assert_eq!(g.rgba, vec![188, 188, 188, 255, 255, 255, 255, 255]);
    assert!(GroundTruth::load(&dir.join("missing.png")).is_err());
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn the_bench_runs_a_model_file_as_well_as_a_built_in_scene() {
    let dir = std::env::temp_dir().join(format!("fovea-bench-model-{}", std::process::id()));
    let model = concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/assets/models/plaster-bunny.glb"
    );
    let run = |scene: &str| {
        std::process::Command::new(env!("CARGO_BIN_EXE_fovea"))
            .args([
                "bench", "--sweep", "presets", "--frames", "1", "--warmup", "0",
            ])
            .args([
                "--size", "64x48", "--gaze", "0.5,0.5", "--scene", scene, "--out",
            ])
            .arg(&dir)
            .env("NODEVICE_SELECT", "1")
            .env_remove("RUST_BACKTRACE")
            .output()
            .unwrap()
    };
    let out = run(&format!("bunny,{model}"));
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let md = std::fs::read_to_string(dir.join("bench.md")).unwrap();
    assert!(
        md.contains("## bunny 64×48") && md.contains("## plaster-bunny 64×48"),
        "{md}"
    );
    let out = run("no-such-scene");
    let e = String::from_utf8_lossy(&out.stderr);
    assert!(
        !out.status.success() && e.contains("neither a built-in scene (gallery"),
        "{e}"
    );
    std::fs::remove_dir_all(&dir).ok();
}
