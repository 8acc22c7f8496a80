//! `fovea bench --sweep codecs`: every encoder configuration on the same frames along a gaze
//! path, scored against the lossless frame. Structure and orderings are asserted, never times.

use std::process::Command;
use std::sync::atomic::AtomicBool;

use fovea::bench::{codec_configs, run_codecs, write_codec_reports, CodecOptions, TARGET};
use fovea::protocol::{Codec, Display};
use fovea::render::Renderer;

#[test]
fn the_codec_sweep_measures_every_configuration_on_the_same_frames() {
    let mut renderer = Renderer::new().unwrap_or_else(|e| panic!("GPU tests need an adapter: {e}"));
    let dir = std::env::temp_dir().join(format!("fovea-codecs-{}", std::process::id()));
    let opts = CodecOptions {
        scene: "gallery".into(),
        width: 320,
        height: 240,
        // A saccade across the frame between frames 2 and 3.
        path: vec![[0.3, 0.4], [0.31, 0.4], [0.7, 0.6], [0.7, 0.61]],
        stretch_frames: 4,
        recording: "a test path".into(),
        configs: codec_configs(),
        display: Display::default(),
        pictures: Some(dir.join("codecs")),
        orbit_deg_per_s: 0.0,
    };
    let report = run_codecs(
        &mut renderer,
        &opts,
        &AtomicBool::new(false),
        &mut |_, _, _| {},
    )
    .expect("the sweep runs");
    assert_eq!(report.frames, 4);
    assert_eq!(report.rows.len(), opts.configs.len());
    let row = |name: &str| {
        report
            .rows
            .iter()
            .find(|r| r.name == name)
            .unwrap_or_else(|| {
                panic!(
                    "no row {name}: {:?}",
                    report.rows.iter().map(|r| &r.name).collect::<Vec<_>>()
                )
            })
    };
    for r in &report.rows {
        assert!(r.bytes.median > 0.0 && r.kbps > 0.0, "{}", r.name);
        assert!(r.flip_fovea.is_finite() && r.flip.is_finite(), "{}", r.name);
        assert!(
            r.flip_fovea > 0.0 && r.flip_fovea < 0.5,
            "{} {}",
            r.name,
            r.flip_fovea
        );
        // Only an H.264 stream has a keyframe, and it costs more than the frames after it.
        match r.config.codec {
            Codec::H264 => assert!(r.keyframe_bytes.unwrap() > r.bytes.median, "{}", r.name),
            _ => assert_eq!(r.keyframe_bytes, None, "{}", r.name),
        }
    }
    // More JPEG quality: more bytes and a better fovea.
    assert!(row("JPEG q95").bytes.median > row("JPEG q50").bytes.median);
    assert!(row("JPEG q95").flip_fovea < row("JPEG q50").flip_fovea);
    // The low-pass spends fewer bytes and leaves the fovea as it was (JPEG blocks at the edge of
    // the untouched disc may differ a little).
    let (plain, low) = (row("JPEG q85"), row("JPEG q85 + low-pass"));
    assert!(low.bytes.median < plain.bytes.median);
    assert!((low.flip_fovea - plain.flip_fovea).abs() < 0.1 * plain.flip_fovea);
    assert!(low.flip > plain.flip, "the periphery is blurred");
    // The floor: 4:2:0 alone costs some quality (shown with chroma repeated or filtered), and
    // H.264 at its best comes close to it but not under it. 8-bit 4:4:4 costs some too, less.
    assert_eq!(report.floors.len(), 3);
    assert!(
        report.floors.iter().all(|f| f.flip_fovea > 0.0),
        "{:?}",
        report.floors
    );
    assert!(report.floors[2].flip_fovea < report.floors[0].flip_fovea);
    let best = row("H.264 8000 kbit/s").flip_fovea;
    assert!(best >= report.floors[0].flip_fovea * 0.95, "{best}");
    // Every family is read off at the target's quality; the target is itself.
    let families: Vec<&str> = report
        .equal_quality
        .iter()
        .map(|e| e.family.as_str())
        .collect();
    assert_eq!(
        families,
        [
            "JPEG",
            "H.264",
            "JPEG + low-pass",
            "H.264 + low-pass",
            "JPEG + inset 20°",
            "H.264 + inset 20°",
            "JPEG + inset 16°",
            "H.264 + inset 16°",
            "H.264 + inset 16° + low-pass",
            "H.264 + hold",
            "H.264 + low-pass + hold",
            "H.264 + inset 16° + low-pass + hold",
            "JPEG + inset 13.3°"
        ]
    );
    // Where the quantiser reaches its floor a held periphery is not re-coded every frame.
    let (plain, held) = (row("H.264 8000 kbit/s"), row("H.264 8000 kbit/s + hold"));
    assert!(
        held.bytes.median < plain.bytes.median,
        "{} held against {} plain",
        held.bytes.median,
        plain.bytes.median
    );
    assert_eq!(
        held.keyframe_bytes, plain.keyframe_bytes,
        "a keyframe holds nothing"
    );
    let jpeg = &report.equal_quality[0];
    assert!((jpeg.vs_target.unwrap() - 1.0).abs() < 1e-9);
    // Foveated families are also read at the strictest foveal FLIP they and their plain codec
    // reach.
    for e in &report.equal_quality {
        assert_eq!(
            e.at_strictest.is_some(),
            e.family.contains(" + "),
            "{}",
            e.family
        );
    }
    let best = report.equal_quality[2].at_strictest.unwrap();
    let low = row("JPEG q95 + low-pass").flip_fovea;
    assert_eq!(best.flip_fovea, row("JPEG q95").flip_fovea.max(low));
    assert!(report
        .markdown()
        .contains(&format!("At {TARGET}'s foveal quality")));

    write_codec_reports(&report, &dir).unwrap();
    for f in [
        "codecs.json",
        "codecs.md",
        "codecs.svg",
        "codecs.png",
        "codecs/lossless.png",
        "codecs/JPEG_q85___low_pass.png",
    ] {
        assert!(dir.join(f).is_file(), "{f} written");
    }
    // `fovea plot` redraws the chart from the JSON, and rewrites the report's read-offs.
    std::fs::remove_file(dir.join("codecs.svg")).unwrap();
    std::fs::remove_file(dir.join("codecs.md")).unwrap();
    let out = Command::new(env!("CARGO_BIN_EXE_fovea"))
        .arg("plot")
        .arg(dir.join("codecs.json"))
        .output()
        .unwrap();
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    assert!(dir.join("codecs.svg").is_file());
    let md = std::fs::read_to_string(dir.join("codecs.md")).unwrap();
    assert_eq!(md, report.markdown());
    std::fs::remove_dir_all(&dir).ok();
}

#[test]
fn the_codec_sweep_asks_for_a_gaze_path_and_one_scene() {
    let run = |args: &[&str]| {
        let out = Command::new(env!("CARGO_BIN_EXE_fovea"))
            .args(["bench", "--sweep", "codecs", "--out", "/nonexistent/never"])
            .args(args)
            .env_remove("RUST_BACKTRACE")
            .output()
            .unwrap();
        assert!(!out.status.success());
        String::from_utf8_lossy(&out.stderr).into_owned()
    };
    assert!(run(&[]).contains("--gaze-file"));
    let gaze = concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/assets/gaze/eyelink_500hz_1920x1200.csv"
    );
    let e = run(&["--gaze-file", gaze, "--scene", "gallery,opaque"]);
    assert!(e.contains("one scene at one size"), "{e}");
    let e = run(&["--gaze-file", gaze, "--gaze-from-s=-1"]);
    assert!(e.contains("--gaze-from-s"), "{e}");
    let e = run(&[
        "--gaze-file",
        gaze,
        "--screen",
        "1920x1200",
        "--gaze-from-s",
        "100000",
    ]);
    assert!(e.contains("no gaze"), "{e}");
    let e = run(&["--gaze-file", gaze, "--orbit-deg-per-s", "400"]);
    assert!(e.contains("--orbit-deg-per-s"), "{e}");
    // A filter that names nothing says which names there are.
    let e = run(&[
        "--gaze-file",
        gaze,
        "--screen",
        "1920x1200",
        "--only",
        "vp9",
    ]);
    assert!(
        e.contains("--only vp9") && e.contains("H.264 4000 kbit/s"),
        "{e}"
    );
}

/// A turning camera changes the whole picture every frame, so an H.264 stream's P-frames cost
/// more than with the camera still on the same gaze; the report says it turned.
#[test]
fn an_orbiting_camera_changes_what_the_encoder_sees() {
    let mut renderer = Renderer::new().unwrap_or_else(|e| panic!("GPU tests need an adapter: {e}"));
    let h264 = codec_configs()
        .into_iter()
        .filter(|c| c.name == "H.264 4000 kbit/s")
        .collect::<Vec<_>>();
    assert_eq!(h264.len(), 1);
    let run = |renderer: &mut Renderer, orbit_deg_per_s: f64| {
        let opts = CodecOptions {
            scene: "gallery".into(),
            width: 160,
            height: 120,
            path: vec![[0.5, 0.5]; 4],
            stretch_frames: 4,
            recording: "a still gaze".into(),
            configs: h264.clone(),
            display: Display::default(),
            pictures: None,
            orbit_deg_per_s,
        };
        run_codecs(renderer, &opts, &AtomicBool::new(false), &mut |_, _, _| {})
            .expect("the sweep runs")
    };
    let still = run(&mut renderer, 0.0);
    // 3° a frame: a fast drag.
    let turning = run(&mut renderer, 180.0);
    let (a, b) = (&still.rows[0], &turning.rows[0]);
    assert!(
        b.bytes.median > 2.0 * a.bytes.median,
        "P-frames still {} bytes, turning {}",
        a.bytes.median,
        b.bytes.median
    );
    assert!(turning.markdown().contains("the camera orbiting 180°/s"));
    assert!(!still.markdown().contains("orbiting"));
}

/// Stretches pooled in one report are streams of their own: a stretch repeated is encoded as
/// it was the first time (a fresh encoder, render history and clock), so two copies of one
/// stretch pool to that stretch's figures, keyframe included; run as one stream, the copy's
/// frames would be P-frames of an encoder that had seen them.
#[test]
fn a_repeated_stretch_pools_to_itself() {
    let mut renderer = Renderer::new().unwrap_or_else(|e| panic!("GPU tests need an adapter: {e}"));
    let configs = codec_configs()
        .into_iter()
        .filter(|c| c.name == TARGET || c.name == "H.264 1000 kbit/s + inset 16°")
        .collect::<Vec<_>>();
    assert_eq!(configs.len(), 2);
    let stretch = [[0.3, 0.4], [0.32, 0.41], [0.6, 0.55]];
    let run = |renderer: &mut Renderer, copies: usize, stretch_frames: usize| {
        let opts = CodecOptions {
            scene: "gallery".into(),
            width: 160,
            height: 120,
            path: stretch.repeat(copies),
            stretch_frames,
            recording: "a test path".into(),
            configs: configs.clone(),
            display: Display::default(),
            pictures: None,
            orbit_deg_per_s: 0.0,
        };
        run_codecs(renderer, &opts, &AtomicBool::new(false), &mut |_, _, _| {})
    };
    let once = run(&mut renderer, 1, 3).expect("the sweep runs");
    let twice = run(&mut renderer, 2, 3).expect("the sweep runs");
    let joined = run(&mut renderer, 2, 6).expect("the sweep runs");
    assert_eq!(twice.frames, 6);
    for ((a, b), c) in once.rows.iter().zip(&twice.rows).zip(&joined.rows) {
        assert_eq!(a.name, b.name);
        assert_eq!(a.bytes, b.bytes, "{}", a.name);
        assert_eq!(a.keyframe_bytes, b.keyframe_bytes, "{}", a.name);
        assert!((a.kbps - b.kbps).abs() < 1e-9, "{}", a.name);
        assert!((a.flip_fovea - b.flip_fovea).abs() < 1e-12, "{}", a.name);
        if a.config.h264_kbps.is_some() {
            assert!(a.keyframe_bytes.is_some());
            // One stream over both copies: the second copy costs less than a fresh start.
            assert!(c.kbps < b.kbps, "{} {} {}", a.name, c.kbps, b.kbps);
        }
    }
    assert!(matches!(
        run(&mut renderer, 2, 4),
        Err(fovea::bench::CodecBenchError::Stretch { .. })
    ));
}
