//! Gaze end to end: a real recording replayed through a real server, and a session recorded by
//! the server replayed to the same frames.

use std::time::Duration;

use fovea::client::replay::{replay, ReplayOptions};
use fovea::gaze::formats::{parse, ParseOptions};
use fovea::protocol::Hello;

mod common;

async fn server(record: Option<std::path::PathBuf>) -> (String, common::Running) {
    let options = fovea::server::ServerOptions {
        record_dir: record,
        ..Default::default()
    };
    let (addr, running) = common::start(options).await;
    (format!("ws://{addr}/ws"), running)
}

/// The frame the replays ask for, as a screen for the synthetic eye.
fn small_screen() -> fovea::viewing::Viewing {
    fovea::viewing::Viewing {
        width: 96,
        height: 64,
        width_cm: 53.0,
        distance_cm: 60.0,
    }
}

fn options(url: &str) -> ReplayOptions {
    ReplayOptions {
        url: url.to_string(),
        token: None,
        // The opaque scene keeps frames cheap on the software adapter.
        hello: Hello {
            scene: "bunny".into(),
            width: 96,
            height: 64,
            preset: "fast".into(),
            ..Hello::default()
        },
        speed: 1.0,
        start_ms: 0.0,
        duration_ms: None,
        loops: 1,
        keep_images: false,
        stop: Default::default(),
    }
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn a_real_recording_replays_with_nothing_lost_and_much_coalesced() {
    let text = include_str!("../assets/gaze/eyelink_1000hz_1920x1080.csv");
    let rec = parse(
        text,
        &ParseOptions {
            screen: Some((1920, 1080)),
            ..Default::default()
        },
    )
    .unwrap();
    let (url, shutdown) = server(None).await;
    // A short replay first, so the scene's load and its pipelines' compilation (seconds on a
    // loaded software adapter) fall outside the 1.5 s whose frames are counted below.
    let warm = ReplayOptions {
        start_ms: 10_000.0,
        duration_ms: Some(200.0),
        ..options(&url)
    };
    replay(&rec.samples, &warm, |_, _| {}).await.unwrap();
    // 1.5 s of the 1000 Hz recording around a blink (blink at 11.298 s).
    let opts = ReplayOptions {
        start_ms: 10_500.0,
        duration_ms: Some(1_500.0),
        ..options(&url)
    };
    let (frames, summary) = replay(&rec.samples, &opts, |_, _| {}).await.unwrap();
    assert_eq!(summary.samples_in_selection, 1500);
    assert!(
        summary.samples_unsendable > 0,
        "the blink's samples are not sent"
    );
    assert_eq!(summary.samples_lost, 0, "{summary:?}");
    assert!(
        summary.samples_coalesced > summary.frames as u64,
        "1000 Hz samples outrun the frames: {summary:?}"
    );
    assert!(frames.len() >= 10, "{} frames", frames.len());
    assert!(frames.iter().all(|f| f.latency_ms.is_none_or(|l| l > 0.0)));
    // Frames answer samples in order.
    let seqs: Vec<u64> = frames.iter().filter_map(|f| f.seq).collect();
    assert!(seqs.windows(2).all(|w| w[0] < w[1]));
    shutdown.stop().await;
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn a_recorded_session_replays_to_the_same_frames() {
    let dir = std::env::temp_dir().join(format!("fovea-record-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    let (url, shutdown) = server(Some(dir.clone())).await;
    let synthetic = fovea::gaze::synthetic::generate(5, &small_screen(), 60.0, 1000.0);
    let slow = ReplayOptions {
        speed: 0.5,
        ..options(&url)
    };
    // A first session builds the pipelines; on a busy machine the replay's first frame had
    // otherwise waited out the whole replay, leaving it one frame.
    first_frame(&url, &slow.hello).await;
    let (first, _) = replay(&synthetic, &slow, |_, _| {}).await.unwrap();
    // The session ended with the replay; its recording lands once the server notices.
    let path = common::run_folder(&dir).join("session-2.csv");
    for _ in 0..50 {
        if path.exists() {
            break;
        }
        tokio::time::sleep(Duration::from_millis(100)).await;
    }
    let text = std::fs::read_to_string(&path).expect("the session was recorded");
    let recorded = parse(&text, &ParseOptions::default()).unwrap();
    let sent: Vec<[f64; 2]> = synthetic.iter().filter_map(fovea::gaze::sendable).collect();
    let got: Vec<[f64; 2]> = recorded.samples.iter().filter_map(|s| s.xy).collect();
    assert_eq!(got, sent, "every sent sample was recorded, exactly");
    // At its own times, though replayed at half speed: the recording keeps each sample's time.
    let sent_times: Vec<f64> = synthetic
        .iter()
        .filter(|s| fovea::gaze::sendable(s).is_some())
        .map(|s| s.t_ms)
        .collect();
    for (r, t) in recorded.samples.iter().zip(&sent_times) {
        assert!(
            (r.t_ms - (t - sent_times[0])).abs() < 1e-6,
            "{} vs {t}",
            r.t_ms
        );
    }
    let (second, _) = replay(&recorded.samples, &slow, |_, _| {}).await.unwrap();
    // A frame answering sample k shows the same gaze in both runs. (Which samples get their
    // own frame depends on timing: a slow first frame, while shaders compile, coalesces a few.)
    let gazes =
        |f: &[fovea::client::replay::FrameRecord]| -> std::collections::BTreeMap<u64, (f64, f64)> {
            f.iter()
                .filter_map(|f| Some((f.seq?, (f.gaze_x, f.gaze_y))))
                .collect()
        };
    let (a, b) = (gazes(&first), gazes(&second));
    let common: Vec<u64> = a.keys().filter(|k| b.contains_key(k)).copied().collect();
    assert!(
        common.len() > 20,
        "{} frames in common ({} and {})",
        common.len(),
        a.len(),
        b.len()
    );
    for k in common {
        assert_eq!(a[&k], b[&k], "sample {k}");
    }
    shutdown.stop().await;
    let _ = std::fs::remove_dir_all(&dir);
}

/// A replay whose server drains moves to the instance that takes its place (the same URL, as
/// behind a balancer), carries on, and says what the move cost.
#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn a_replay_follows_a_goodbye_to_the_next_instance() {
    let drainable = || fovea::server::ServerOptions {
        drain: Duration::from_secs(5),
        ..Default::default()
    };
    let (addr, first) = common::start(drainable()).await;
    let eye = fovea::gaze::synthetic::generate(9, &small_screen(), 250.0, 8000.0);
    let url = format!("ws://{addr}/ws");
    let opts = options(&url);
    // One frame first, so the replay's first frames do not wait on pipeline builds: on a cold
    // machine they once took longer than the replay had before the goodbye.
    first_frame(&url, &opts.hello).await;
    let run = tokio::spawn(async move { replay(&eye, &opts, |_, _| {}).await });
    tokio::time::sleep(Duration::from_millis(2500)).await;
    // SIGTERM's path: the replay is told goodbye, leaves, and the instance exits.
    let began = std::time::Instant::now();
    first.stop().await;
    assert!(
        began.elapsed() < Duration::from_secs(5),
        "the session left before the grace ended"
    );
    let (_, second) = common::start_on(addr, drainable()).await;
    let (frames, summary) = run.await.unwrap().expect("the replay carries on");
    println!("{summary:?}");
    assert_eq!(summary.reconnects, 1, "{summary:?}");
    assert!(summary.ended_early.is_none(), "{summary:?}");
    assert_eq!(summary.reconnect_gaps_ms.len(), 1, "{summary:?}");
    let on_second = frames.iter().filter(|f| f.connection == 1).count();
    assert!(on_second > 20, "frames from the new instance: {on_second}");
    assert!(frames.iter().any(|f| f.connection == 0));
    // Samples sent while no session was up are counted apart from losses; what the first
    // instance received after its last frame cannot be seen from here, so a few may show as lost.
    assert!(summary.samples_dropped_reconnecting > 0, "{summary:?}");
    assert!(
        (summary.samples_lost as f64) < 0.05 * summary.samples_sent as f64,
        "{summary:?}"
    );
    second.stop().await;
}

/// Opens a session, waits for its first frame and leaves.
async fn first_frame(url: &str, hello: &Hello) {
    let mut c = fovea::client::Client::connect(url).await.unwrap();
    c.hello(hello).await.unwrap();
    send_still_gaze(&mut c, 1, None).await;
    loop {
        let event = c.next_event(Duration::from_secs(60)).await.unwrap();
        if let fovea::client::Event::Frame { .. } = event {
            return;
        }
    }
}

/// A live session's rows reach its file within a second even when samples stop coming.
#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn a_live_recording_is_at_most_a_second_behind() {
    let dir = std::env::temp_dir().join(format!("fovea-flush-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    let (url, server) = server(Some(dir.clone())).await;
    let mut c = fovea::client::Client::connect(&url).await.unwrap();
    c.hello(&options(&url).hello).await.unwrap();
    send_still_gaze(&mut c, 3, None).await;
    // The samples are in once a frame says so; then nothing more is sent.
    loop {
        match c.next_event(Duration::from_secs(30)).await.unwrap() {
            fovea::client::Event::Frame { header, .. } if header.samples == 3 => break,
            fovea::client::Event::Frame { header, .. } => {
                let ack = fovea::protocol::Ack {
                    frame: header.frame,
                    t_ms: None,
                    dropped: false,
                };
                c.ack(&ack).await.unwrap();
            }
            _ => {}
        }
    }
    tokio::time::sleep(Duration::from_millis(1500)).await;
    let partial = common::run_folder(&dir).join("session-1.csv.partial");
    let text = std::fs::read_to_string(&partial).unwrap();
    assert_eq!(text.lines().count(), 4, "header and three rows: {text:?}");
    drop(c);
    server.stop().await;
    let _ = std::fs::remove_dir_all(&dir);
}

/// A recording that reaches its limit stops whole, the client is told once, and the session
/// goes on with its frames.
#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn a_recording_at_its_limit_stops_and_the_session_goes_on() {
    let dir = std::env::temp_dir().join(format!("fovea-cap-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    let (addr, server) = common::start(fovea::server::ServerOptions {
        record_dir: Some(dir.clone()),
        record_max_bytes: 200,
        ..Default::default()
    })
    .await;
    let url = format!("ws://{addr}/ws");
    let mut c = fovea::client::Client::connect(&url).await.unwrap();
    c.hello(&options(&url).hello).await.unwrap();
    send_still_gaze(&mut c, 40, Some(4.0)).await;
    let (mut stopped, mut last_seq) = (0, None);
    while last_seq != Some(40) {
        match c.next_event(Duration::from_secs(30)).await.unwrap() {
            fovea::client::Event::Error(e) => {
                assert_eq!(
                    e.code,
                    fovea::protocol::ErrorCode::RecordingStopped,
                    "{e:?}"
                );
                stopped += 1;
            }
            fovea::client::Event::Frame { header, .. } => {
                last_seq = header.seq;
                let ack = fovea::protocol::Ack {
                    frame: header.frame,
                    t_ms: None,
                    dropped: false,
                };
                c.ack(&ack).await.unwrap();
            }
            other => panic!("{other:?}"),
        }
    }
    assert_eq!(stopped, 1, "told once");
    drop(c);
    server.stop().await;
    let text = std::fs::read_to_string(common::run_folder(&dir).join("session-1.csv")).unwrap();
    assert!(text.len() <= 200 && text.ends_with('\n'), "{text:?}");
    assert!(text.lines().count() > 3, "{text:?}");
    let _ = std::fs::remove_dir_all(&dir);
}

/// Sends samples 1..=n at one point, each with its own time.
async fn send_still_gaze(c: &mut fovea::client::Client, n: u64, pupil_mm: Option<f64>) {
    for seq in 1..=n {
        let g = fovea::protocol::Gaze {
            seq,
            t_ms: seq as f64,
            x: 0.4,
            y: 0.4,
            pupil_mm,
            sample_t_ms: None,
        };
        c.gaze(&g).await.unwrap();
    }
}

/// Ctrl-C mid-replay: the replay stops sending, collects what is in flight and still writes
/// frames.csv and summary.json, marked interrupted.
#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn ctrl_c_mid_replay_leaves_complete_outputs() {
    let (url, shutdown) = server(None).await;
    let out = std::env::temp_dir().join(format!("fovea-interrupted-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&out);
    let recording = std::path::Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("assets/gaze/eyelink_500hz_1920x1200.csv");
    let child = std::process::Command::new(env!("CARGO_BIN_EXE_fovea"))
        .arg("replay")
        .arg(&recording)
        .args(["--screen", "1920x1200", "--url", &url, "--scene", "bunny"])
        .args([
            "--size", "96x64", "--preset", "fast", "--codec", "jpeg", "--out",
        ])
        .arg(&out)
        .stdout(std::process::Stdio::null())
        .stderr(std::process::Stdio::piped())
        .spawn()
        .unwrap();
    // Let frames come for a while (the recording runs for minutes), then interrupt.
    tokio::time::sleep(std::time::Duration::from_secs(4)).await;
    // SAFETY: sending a signal to our own child process.
    assert_eq!(unsafe { libc::kill(child.id() as i32, libc::SIGINT) }, 0);
    let status = tokio::task::spawn_blocking(move || child.wait_with_output())
        .await
        .unwrap()
        .unwrap();
    let stderr = String::from_utf8_lossy(&status.stderr);
    assert!(status.status.success(), "{stderr}");
    assert!(stderr.contains("interrupted"), "{stderr}");
    let summary: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("summary.json")).unwrap()).unwrap();
    assert_eq!(summary["interrupted"], true, "{summary}");
    let sent = summary["samples_sent"].as_u64().unwrap();
    let total = summary["samples_in_selection"].as_u64().unwrap();
    assert!(sent > 0 && sent < total, "{sent} of {total}");
    let csv = std::fs::read_to_string(out.join("frames.csv")).unwrap();
    let rows = csv.lines().count() - 1;
    assert_eq!(
        rows as u64,
        summary["frames"].as_u64().unwrap(),
        "{summary}"
    );
    assert!(rows > 0);
    // JPEG frames have no keyframes: the column is empty, the count none.
    assert!(csv.lines().skip(1).all(|l| l.ends_with(',')), "{csv}");
    assert_eq!(summary["keyframes"], 0, "{summary}");
    // Provenance: what was replayed, how, and against which server.
    assert_eq!(summary["recording"]["format"], "eyelink", "{summary}");
    assert_eq!(summary["recording"]["screen"], "1920x1200", "{summary}");
    assert_eq!(summary["asked"]["scene"], "bunny", "{summary}");
    assert_eq!(summary["asked"]["size"], "96x64", "{summary}");
    assert_eq!(
        summary["server"]["version"],
        env!("CARGO_PKG_VERSION"),
        "{summary}"
    );
    assert_eq!(summary["server"]["codec"], "jpeg", "{summary}");
    assert!(summary["server"]["adapter"]
        .as_str()
        .is_some_and(|a| !a.is_empty()));
    let _ = std::fs::remove_dir_all(&out);
    shutdown.stop().await;
}

/// `--save-frames` writes each frame as the file it is: an H.264 replay's frames are one raw
/// stream that a decoder plays from its first (key)frame to its last.
#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn an_h264_replay_saves_a_playable_stream() {
    let (url, shutdown) = server(None).await;
    let out = std::env::temp_dir().join(format!("fovea-saved-h264-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&out);
    let recording = std::path::Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("assets/gaze/eyelink_500hz_1920x1200.csv");
    let run = tokio::process::Command::new(env!("CARGO_BIN_EXE_fovea"))
        .arg("replay")
        .arg(&recording)
        .args(["--screen", "1920x1200", "--url", &url, "--scene", "bunny"])
        .args(["--size", "96x64", "--preset", "fast", "--codec", "h264"])
        .args(["--duration", "1.5", "--save-frames", "--out"])
        .arg(&out)
        .output()
        .await
        .unwrap();
    let stderr = String::from_utf8_lossy(&run.stderr);
    assert!(run.status.success(), "{stderr}");
    let csv = std::fs::read_to_string(out.join("frames.csv")).unwrap();
    let rows = csv.lines().count() - 1;
    assert!(rows >= 2, "{rows} frames");
    // The keyframe column: the stream's first frame is one, and 1.5 s holds no periodic one.
    let header: Vec<&str> = csv.lines().next().unwrap().split(',').collect();
    let column = |name: &str| header.iter().position(|c| *c == name).unwrap();
    let (key, bytes) = (column("keyframe"), column("bytes"));
    let cells: Vec<Vec<&str>> = csv
        .lines()
        .skip(1)
        .map(|l| l.split(',').collect())
        .collect();
    let keys: Vec<&str> = cells.iter().map(|c| c[key]).collect();
    assert_eq!(keys[0], "1", "{csv}");
    assert!(keys[1..].iter().all(|k| *k == "0"), "{csv}");
    let stream = std::fs::read(out.join("frames/stream-0.h264")).unwrap();
    let mut decoder = openh264::decoder::Decoder::new().unwrap();
    let mut pictures = 0;
    for nal in openh264::nal_units(&stream) {
        if let Ok(Some(_)) = decoder.decode(nal) {
            pictures += 1;
        }
    }
    assert_eq!(pictures, rows, "every frame decodes from the saved stream");
    assert!(
        !out.join("frames/000001.jpg").exists(),
        "no .jpg of H.264 bytes"
    );
    let summary: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("summary.json")).unwrap()).unwrap();
    assert_eq!(summary["asked"]["codec"], "h264", "{summary}");
    assert_eq!(summary["server"]["codec"], "h264", "{summary}");
    assert_eq!(summary["keyframes"], 1, "{summary}");
    assert_eq!(
        summary["keyframe_bytes"],
        cells[0][bytes].parse::<u64>().unwrap()
    );
    let _ = std::fs::remove_dir_all(&out);
    shutdown.stop().await;
}
