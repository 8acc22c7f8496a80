//! The server under load, on loopback, bounded in count and time: admission control, stalled
//! clients, fairness, and the load tool's report against the server's own /metrics.

use std::net::SocketAddr;
use std::time::Duration;

use fovea::client::load::{run, LoadOptions};
use fovea::client::{Client, Event};
use fovea::protocol::{Ack, Codec, Gaze, Hello};
use fovea::server::ServerOptions;
use tokio::io::{AsyncReadExt, AsyncWriteExt};

const WAIT: Duration = Duration::from_secs(30);
/// The metrics recorder is process-wide: tests that read /metrics must not overlap.
static SERIAL: tokio::sync::Mutex<()> = tokio::sync::Mutex::const_new(());

mod common;

async fn server(options: ServerOptions) -> (SocketAddr, common::Running) {
    common::start(options).await
}

fn small() -> Hello {
    Hello {
        scene: "bunny".into(),
        width: 64,
        height: 48,
        preset: "fast".into(),
        ..Hello::default()
    }
}

async fn http_get(addr: SocketAddr, path: &str) -> String {
    let mut s = tokio::net::TcpStream::connect(addr).await.unwrap();
    s.write_all(format!("GET {path} HTTP/1.1\r\nHost: x\r\nConnection: close\r\n\r\n").as_bytes())
        .await
        .unwrap();
    let mut out = String::new();
    s.read_to_string(&mut out).await.unwrap();
    out
}

async fn frame_for(c: &mut Client, seq: u64) {
    c.gaze(&Gaze {
        seq,
        t_ms: seq as f64,
        x: 0.3 + 0.01 * (seq % 10) as f64,
        y: 0.5,
        pupil_mm: None,
        sample_t_ms: None,
    })
    .await
    .unwrap();
    loop {
        match c.next_event(WAIT).await.unwrap() {
            Event::Frame { header, .. } => {
                c.ack(&Ack {
                    frame: header.frame,
                    t_ms: None,
                    dropped: false,
                })
                .await
                .unwrap();
                if header.seq == Some(seq) {
                    return;
                }
            }
            Event::Closed(reason) => panic!("closed: {reason:?}"),
            _ => {}
        }
    }
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn admission_stalls_and_the_load_report() {
    let _serial = SERIAL.lock().await;
    let (addr, shutdown) = server(ServerOptions {
        max_sessions: 2,
        stall_timeout: Duration::from_millis(1500),
        ..Default::default()
    })
    .await;
    let url = format!("ws://{addr}/ws");
    assert!(http_get(addr, "/readyz").await.starts_with("HTTP/1.1 200"));

    // Admission: two sessions fit, the third is refused with 1013 and /readyz says not ready.
    let mut a = Client::connect(&url).await.unwrap();
    let mut b = Client::connect(&url).await.unwrap();
    a.hello(&small()).await.unwrap();
    b.hello(&small()).await.unwrap();
    let mut c = Client::connect(&url).await.unwrap();
    match c.next_event(WAIT).await.unwrap() {
        Event::Closed(Some((code, reason))) => assert!(
            code == 1013 && reason.contains("capacity"),
            "{code} {reason}"
        ),
        other => panic!("the third client got {other:?}"),
    }
    assert!(http_get(addr, "/readyz").await.starts_with("HTTP/1.1 503"));
    // The admitted sessions are undisturbed.
    frame_for(&mut a, 1).await;
    frame_for(&mut b, 1).await;

    // A stalled client (never acks) is disconnected while the other keeps getting frames.
    // b asks for one more frame and never acknowledges it.
    b.gaze(&Gaze {
        seq: 2,
        t_ms: 2.0,
        x: 0.6,
        y: 0.5,
        pupil_mm: None,
        sample_t_ms: None,
    })
    .await
    .unwrap();
    let mut seq = 10;
    let closed = loop {
        frame_for(&mut a, seq).await;
        seq += 1;
        match b.next_event(Duration::from_millis(100)).await {
            Ok(Event::Closed(reason)) => break reason,
            _ => continue,
        }
    };
    let (code, reason) = closed.expect("a close frame with a reason");
    assert!(
        code == 1008 && reason.contains("acknowledged"),
        "{code} {reason}"
    );
    frame_for(&mut a, seq).await;
    drop(a);
    tokio::time::sleep(Duration::from_millis(300)).await;

    // The load tool against the same server: fields present, counts agree with /metrics.
    let before = metric(&http_get(addr, "/metrics").await, "fovea_frames_sent_total");
    let opts = LoadOptions {
        token: None,
        url: url.clone(),
        sessions: 2,
        duration: Duration::from_secs(3),
        ramp_up: Duration::from_millis(50),
        rate_hz: 60.0,
        hello: small(),
        seed: 3,
        recording: None,
        // One session per codec: the per-codec split is exercised on a real server.
        codecs: vec![Codec::Jpeg, Codec::H264],
    };
    let report = run(&opts, |_, _| {}).await;
    // The sessions end as the tool leaves; the count is read once they have.
    for _ in 0..100 {
        let m = http_get(addr, "/metrics").await;
        if metric(&m, "fovea_sessions_active") == 0.0 {
            break;
        }
        tokio::time::sleep(Duration::from_millis(50)).await;
    }
    let after = metric(&http_get(addr, "/metrics").await, "fovea_frames_sent_total");
    assert_eq!(report.refused + report.connection_failures, 0);
    assert!(report.frames > 5, "{report:?}");
    // The last frame or two may be in flight when a session closes: sent but not received.
    let sent = (after - before) as u64;
    assert!(
        sent >= report.frames && sent <= report.frames + 2 * report.sessions as u64,
        "server sent {sent}, clients received {}",
        report.frames
    );
    assert!(
        report.latency_ms.count > 0
            && report.latency_ms.p50 > 0.0
            && report.latency_ms.p99 >= report.latency_ms.p50
    );
    for stage in ["queue", "render", "readback", "encode"] {
        assert!(report.stages_ms.contains_key(stage), "{stage}");
    }
    assert_eq!(report.fps_per_session.len(), 2);
    let names: Vec<&str> = report.by_codec.keys().map(|k| k.as_str()).collect();
    assert_eq!(names, ["h264", "jpeg"]);
    for (codec, c) in &report.by_codec {
        assert!(
            c.sessions == 1
                && c.frames > 0
                && c.latency_ms.count > 0
                && c.encode_ms.p50 > 0.0
                && c.kbit_s_per_session > 0.0,
            "{codec}: {c:?}"
        );
    }
    assert_eq!(
        report.by_codec.values().map(|c| c.frames).sum::<u64>(),
        report.frames
    );
    let json = serde_json::to_value(&report).unwrap();
    for field in [
        "fps_total",
        "fairness",
        "latency_ms",
        "stages_ms",
        "errors",
        "refused",
        "fps_timeline",
        "by_codec",
    ] {
        assert!(json.get(field).is_some(), "{field}");
    }
    let m = http_get(addr, "/metrics").await;
    assert!(
        m.contains("fovea_stage_seconds_bucket") && m.contains("fovea_sessions_refused_total"),
        "{m}"
    );
    shutdown.stop().await;
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn load_can_be_driven_by_a_gaze_recording() {
    let _serial = SERIAL.lock().await;
    let (addr, shutdown) = server(ServerOptions::default()).await;
    let text = include_str!("../assets/gaze/eyelink_500hz_1920x1200.csv");
    let rec = fovea::gaze::formats::parse(
        text,
        &fovea::gaze::formats::ParseOptions {
            screen: Some((1920, 1200)),
            ..Default::default()
        },
    )
    .unwrap();
    // One frame first: the 2 s below count frames, not the pipelines' builds on a busy machine.
    let mut warm = Client::connect(&format!("ws://{addr}/ws")).await.unwrap();
    warm.hello(&small()).await.unwrap();
    frame_for(&mut warm, 1).await;
    drop(warm);
    let opts = LoadOptions {
        token: None,
        url: format!("ws://{addr}/ws"),
        sessions: 2,
        duration: Duration::from_secs(2),
        ramp_up: Duration::ZERO,
        rate_hz: 60.0,
        hello: small(),
        seed: 1,
        recording: Some(std::sync::Arc::new(rec.samples)),
        codecs: vec![],
    };
    let report = run(&opts, |_, _| {}).await;
    // 500 Hz for ~2 s per session, minus blinks and track loss.
    assert!(report.gaze_sent > 1000, "{} samples sent", report.gaze_sent);
    assert!(
        report.frames > 4 && report.samples_coalesced > 0,
        "{report:?}"
    );
    shutdown.stop().await;
}

fn metric(text: &str, name: &str) -> f64 {
    text.lines()
        .find(|l| l.starts_with(name) && l[name.len()..].starts_with(' '))
        .and_then(|l| l.split_whitespace().last())
        .and_then(|v| v.parse().ok())
        .unwrap_or(0.0)
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn three_sessions_share_the_renderer_fairly() {
    let _serial = SERIAL.lock().await;
    let (addr, shutdown) = server(ServerOptions::default()).await;
    let url = format!("ws://{addr}/ws");
    let opts = LoadOptions {
        token: None,
        url,
        sessions: 3,
        duration: Duration::from_secs(4),
        ramp_up: Duration::ZERO,
        rate_hz: 120.0,
        hello: small(),
        seed: 9,
        recording: None,
        codecs: vec![],
    };
    let report = run(&opts, |_, _| {}).await;
    assert_eq!(report.fps_per_session.len(), 3);
    assert!(
        report.fps_per_session.iter().all(|f| *f > 1.0),
        "every session gets frames: {:?}",
        report.fps_per_session
    );
    // One frame in the render queue per session at a time: nobody starves.
    assert!(
        report.fairness > 0.6,
        "fps per session {:?}, frames a second {:?}, reconnects {}, render {:?}",
        report.fps_per_session,
        report.fps_timeline,
        report.reconnects,
        report.stages_ms.get("render")
    );
    shutdown.stop().await;
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn metrics_describe_every_series_before_the_first_session() {
    let _serial = SERIAL.lock().await;
    let (addr, running) = server(ServerOptions::default()).await;
    let text = http_get(addr, "/metrics").await;
    for name in [
        "fovea_sessions_total",
        "fovea_sessions_refused_total",
        "fovea_sessions_stalled_total",
        "fovea_sessions_active",
        "fovea_frames_rendered_total",
        "fovea_frames_sent_total",
        "fovea_frames_failed_total",
        "fovea_frames_skipped_total",
        "fovea_gaze_samples_total",
        "fovea_gaze_coalesced_total",
    ] {
        assert!(
            text.contains(&format!("# HELP {name} ")),
            "no HELP for {name}:\n{text}"
        );
        assert!(
            text.lines()
                .any(|l| l.starts_with(name) && !l.starts_with('#')),
            "{name} has no value before any session:\n{text}"
        );
    }
    running.stop().await;
}

#[test]
fn load_against_a_closed_port_fails_and_says_why() {
    // A port nothing listens on: bind one, note it, let it go.
    let port = std::net::TcpListener::bind("127.0.0.1:0")
        .and_then(|l| l.local_addr())
        .unwrap()
        .port();
    let out_dir = std::env::temp_dir().join(format!("fovea-load-closed-{}", std::process::id()));
    let out = std::process::Command::new(env!("CARGO_BIN_EXE_fovea"))
        .args(["load", "--url", &format!("ws://127.0.0.1:{port}/ws")])
        .args(["--sweep", "1,2", "--duration", "1", "--out"])
        .arg(&out_dir)
        .output()
        .unwrap();
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(!out.status.success(), "exit status {}", out.status);
    assert!(stderr.contains("cannot connect"), "{stderr}");
    // Nothing was measured: no lines of zeros, no report or plots of them, no second count.
    assert_eq!(String::from_utf8_lossy(&out.stdout), "");
    assert!(!out_dir.join("load.json").exists());
    assert!(
        stderr.contains("fovea serve"),
        "the message names the likely fix: {stderr}"
    );
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn frames_of_sessions_that_left_are_not_rendered() {
    let _serial = SERIAL.lock().await;
    let (addr, running) = server(ServerOptions::default()).await;
    let url = format!("ws://{addr}/ws");
    let before = metric(
        &http_get(addr, "/metrics").await,
        "fovea_frames_abandoned_total",
    );
    // Five sessions ask for a slow first frame (720p, every pixel shaded) and leave at once:
    // one frame is rendering while the others wait, and those must be skipped.
    for _ in 0..5 {
        let mut c = Client::connect(&url).await.unwrap();
        c.hello(&Hello {
            scene: "bunny-marble".into(),
            width: 1280,
            height: 720,
            preset: "full".into(),
            ..Hello::default()
        })
        .await
        .unwrap();
        drop(c);
    }
    let deadline = tokio::time::Instant::now() + WAIT;
    let abandoned = loop {
        let n = metric(
            &http_get(addr, "/metrics").await,
            "fovea_frames_abandoned_total",
        );
        if n - before >= 3.0 || tokio::time::Instant::now() > deadline {
            break n - before;
        }
        tokio::time::sleep(Duration::from_millis(200)).await;
    };
    assert!(
        abandoned >= 3.0,
        "{abandoned} of 5 abandoned frames skipped"
    );
    // The renderer is free for the living.
    let mut live = Client::connect(&url).await.unwrap();
    live.hello(&small()).await.unwrap();
    frame_for(&mut live, 1).await;
    running.stop().await;
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn silent_sockets_are_closed_by_the_hello_deadline_and_a_viewer_gets_in() {
    use futures_util::StreamExt;
    let (addr, running) = server(ServerOptions {
        max_sessions: 2,
        hello_timeout: Duration::from_millis(800),
        ..Default::default()
    })
    .await;
    let url = format!("ws://{addr}/ws");
    // Two sockets that never say hello fill both slots…
    let mut silent = Vec::new();
    for _ in 0..2 {
        silent.push(tokio_tungstenite::connect_async(&url).await.unwrap().0);
    }
    assert!(
        http_get(addr, "/readyz").await.contains(" 503 "),
        "both slots are held"
    );
    // …until the deadline closes them with 1008 and a reason.
    for ws in &mut silent {
        let msg = tokio::time::timeout(WAIT, ws.next()).await.unwrap();
        let Some(Ok(tokio_tungstenite::tungstenite::Message::Close(Some(frame)))) = msg else {
            panic!("expected a close frame, got {msg:?}");
        };
        assert_eq!(u16::from(frame.code), 1008);
        assert!(frame.reason.contains("no hello"), "{}", frame.reason);
    }
    let mut viewer = Client::connect(&url).await.unwrap();
    viewer.hello(&small()).await.unwrap();
    frame_for(&mut viewer, 1).await;
    running.stop().await;
}
