//! The server on 127.0.0.1:0, spoken to by a real WebSocket client.

use std::net::SocketAddr;
use std::time::Duration;

use fovea::client::{Client, Event};
use fovea::protocol::{Ack, Codec, ErrorCode, FrameHeader, Gaze, Hello};
use fovea::render::{FrameRequest, RenderThread, Renderer};
use tokio::io::{AsyncReadExt, AsyncWriteExt};
use tokio_util::sync::CancellationToken;

const WAIT: Duration = Duration::from_secs(30);

struct Server {
    addr: SocketAddr,
    shutdown: CancellationToken,
    task: tokio::task::JoinHandle<std::io::Result<()>>,
    /// Joined in `stop`: a process must not exit while the render thread is in the driver.
    thread: std::thread::JoinHandle<()>,
}

impl Server {
    async fn start() -> Server {
        let renderer =
            Renderer::new().unwrap_or_else(|e| panic!("server tests need a GPU adapter: {e}"));
        let (render, thread) = RenderThread::spawn(renderer).unwrap();
        let listener = tokio::net::TcpListener::bind("127.0.0.1:0").await.unwrap();
        let addr = listener.local_addr().unwrap();
        let shutdown = CancellationToken::new();
        // A short drain: a test client that ignores the goodbye is closed (1001) after 2 s.
        let options = fovea::server::ServerOptions {
            drain: Duration::from_secs(2),
            ..Default::default()
        };
        let task = tokio::spawn(fovea::server::run_with(
            listener,
            render,
            shutdown.clone(),
            options,
        ));
        Server {
            addr,
            shutdown,
            task,
            thread,
        }
    }

    fn ws(&self) -> String {
        format!("ws://{}/ws", self.addr)
    }

    async fn client(&self) -> Client {
        Client::connect(&self.ws()).await.unwrap()
    }

    async fn stop(self) {
        self.shutdown.cancel();
        tokio::time::timeout(WAIT, self.task)
            .await
            .expect("server stops")
            .unwrap()
            .unwrap();
        let thread = self.thread;
        tokio::time::timeout(WAIT, tokio::task::spawn_blocking(move || thread.join()))
            .await
            .expect("the render thread ends once the server is gone")
            .unwrap()
            .unwrap();
    }
}

fn gaze(seq: u64, x: f64, y: f64) -> Gaze {
    Gaze {
        seq,
        t_ms: seq as f64 * 4.0,
        x,
        y,
        pupil_mm: Some(4.0),
        sample_t_ms: None,
    }
}

fn hello(width: u32, height: u32) -> Hello {
    Hello {
        width,
        height,
        ..Hello::default()
    }
}

/// Waits for the next frame, failing on anything else.
async fn next_frame(c: &mut Client) -> (FrameHeader, Vec<u8>) {
    match c.next_event(WAIT).await.unwrap() {
        Event::Frame { header, image } => (header, image),
        other => panic!("expected a frame, got {other:?}"),
    }
}

async fn next_error(c: &mut Client) -> ErrorCode {
    loop {
        match c.next_event(WAIT).await.unwrap() {
            Event::Error(e) => return e.code,
            Event::Frame { .. } => continue,
            other => panic!("expected an error, got {other:?}"),
        }
    }
}

/// Sends a gaze sample, then reads frames (acking each) until one answers that sample.
async fn frame_for(c: &mut Client, g: Gaze) -> (FrameHeader, Vec<u8>) {
    c.gaze(&g).await.unwrap();
    loop {
        let (h, img) = next_frame(c).await;
        c.ack(&Ack {
            frame: h.frame,
            t_ms: None,
            dropped: false,
        })
        .await
        .unwrap();
        if h.seq == Some(g.seq) {
            return (h, img);
        }
    }
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn two_sessions_each_get_frames_that_answer_their_own_gaze() {
    let server = Server::start().await;
    let mut a = server.client().await;
    let mut b = server.client().await;
    let wa = a.hello(&hello(96, 64)).await.unwrap();
    let wb = b.hello(&hello(80, 80)).await.unwrap();
    assert_ne!(wa.session, wb.session);
    assert_eq!(
        wa.limits,
        fovea::protocol::Limits {
            slice_ms: fovea::render::SLICE_MS,
            ..fovea::protocol::Limits::default()
        },
        "welcome states the limits"
    );
    let (mut frames_a, mut frames_b) = (0, 0);
    for seq in 1..=4u64 {
        let t = seq as f64 / 5.0;
        let (ha, ia) = frame_for(&mut a, gaze(seq, t, 0.5)).await;
        let (hb, ib) = frame_for(&mut b, gaze(100 + seq, 0.5, t)).await;
        assert_eq!(ha.seq, Some(seq));
        assert_eq!(
            (ha.gaze.x, ha.gaze.y),
            (t as f32 as f64, 0.5),
            "marker at the gaze used"
        );
        assert_eq!(
            ha.t_ms,
            Some(seq as f64 * 4.0),
            "the sample's own time is echoed"
        );
        assert_eq!(hb.seq, Some(100 + seq));
        let da = image::load_from_memory(&ia).unwrap();
        let db = image::load_from_memory(&ib).unwrap();
        assert_eq!((da.width(), da.height()), (96, 64));
        assert_eq!((db.width(), db.height()), (80, 80));
        assert!(ha.stages_ms.render > 0.0 && ha.stages_ms.encode > 0.0);
        assert!(
            ha.sampled > 0.0 && ha.sampled <= 1.0,
            "sampled {}",
            ha.sampled
        );
        frames_a += 1;
        frames_b += 1;
    }
    assert!(frames_a >= 3 && frames_b >= 3);
    server.stop().await;
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn bad_input_gets_an_error_and_leaves_both_sessions_working() {
    let server = Server::start().await;
    let mut bad = server.client().await;
    let mut good = server.client().await;
    good.hello(&hello(64, 48)).await.unwrap();

    // Before hello.
    bad.send_text(r#"{"type":"gaze","seq":1,"t_ms":0,"x":0.5,"y":0.5}"#)
        .await
        .unwrap();
    assert_eq!(next_error(&mut bad).await, ErrorCode::NoHello);
    bad.send_text(r#"{"type":"hello","scene":"teapot"}"#)
        .await
        .unwrap();
    assert_eq!(next_error(&mut bad).await, ErrorCode::UnknownScene);
    bad.send_text(r#"{"type":"hello","preset":"ultra"}"#)
        .await
        .unwrap();
    assert_eq!(next_error(&mut bad).await, ErrorCode::UnknownPreset);
    bad.send_text(r#"{"type":"hello","width":0,"height":48}"#)
        .await
        .unwrap();
    assert_eq!(next_error(&mut bad).await, ErrorCode::OutOfRange);
    // A valid hello still works after the refused ones.
    bad.hello(&hello(64, 48)).await.unwrap();
    let cases: &[(&str, ErrorCode)] = &[
        ("definitely not json", ErrorCode::BadJson),
        (r#"{"type":"warp"}"#, ErrorCode::UnknownType),
        (r#"{"seq":1}"#, ErrorCode::MissingType),
        (
            r#"{"type":"gaze","seq":2,"t_ms":0,"x":0.5}"#,
            ErrorCode::BadField,
        ),
        (
            r#"{"type":"gaze","seq":2,"t_ms":0,"x":NaN,"y":0.5}"#,
            ErrorCode::NotFinite,
        ),
        (
            r#"{"type":"gaze","seq":2,"t_ms":0,"x":Infinity,"y":0.5}"#,
            ErrorCode::NotFinite,
        ),
        (
            r#"{"type":"gaze","seq":2,"t_ms":0,"x":1.5,"y":0.5}"#,
            ErrorCode::OutOfRange,
        ),
        (
            r#"{"type":"gaze","seq":2,"t_ms":0,"x":0.5,"y":0.5,"pupil_mm":12}"#,
            ErrorCode::OutOfRange,
        ),
        (r#"{"type":"ack","frame":999}"#, ErrorCode::BadAck),
        (r#"{"type":"hello"}"#, ErrorCode::AlreadyStarted),
    ];
    for (text, code) in cases {
        bad.send_text(text).await.unwrap();
        assert_eq!(next_error(&mut bad).await, *code, "for {text}");
        // Meanwhile the other session is served as usual.
        let (h, _) = frame_for(&mut good, gaze(7, 0.3, 0.3)).await;
        assert_eq!(h.seq, Some(7));
    }
    bad.send_text(&format!(
        r#"{{"type":"gaze","pad":"{}"}}"#,
        "x".repeat(10_000)
    ))
    .await
    .unwrap();
    assert_eq!(next_error(&mut bad).await, ErrorCode::TooLarge);
    bad.send_binary(vec![1, 2, 3]).await.unwrap();
    assert_eq!(next_error(&mut bad).await, ErrorCode::UnexpectedBinary);
    // The session that got every bad message still renders.
    let (h, img) = frame_for(&mut bad, gaze(42, 0.9, 0.1)).await;
    assert_eq!(h.seq, Some(42));
    assert_eq!(image::load_from_memory(&img).unwrap().width(), 64);
    server.stop().await;
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn credits_pace_frames_and_newest_gaze_wins() {
    let server = Server::start().await;
    let mut c = server.client().await;
    c.hello(&Hello {
        max_in_flight: 1,
        ..hello(48, 48)
    })
    .await
    .unwrap();
    // The first frame comes without any gaze; then the only credit is spent.
    let (first, _) = next_frame(&mut c).await;
    assert_eq!((first.frame, first.seq), (1, None));
    for seq in 1..=50 {
        c.gaze(&gaze(seq, 0.2, 0.2)).await.unwrap();
    }
    // No ack yet: no credit, so no frame, however many samples arrive.
    match c.next_event(Duration::from_millis(500)).await {
        Err(fovea::client::ClientError::Timeout(_)) => {}
        other => panic!("a client without credit got {other:?}"),
    }
    c.ack(&Ack {
        frame: 1,
        t_ms: Some(1.0),
        dropped: false,
    })
    .await
    .unwrap();
    let (second, _) = next_frame(&mut c).await;
    // Samples 1..49 were coalesced: the frame answers the newest one.
    assert_eq!((second.frame, second.seq), (2, Some(50)));
    server.stop().await;
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn png_frames_are_exactly_the_rendered_pixels() {
    let server = Server::start().await;
    let mut c = server.client().await;
    c.hello(&Hello {
        codec: Codec::Png,
        preset: "full".into(),
        ..hello(72, 40)
    })
    .await
    .unwrap();
    let (h, png) = frame_for(&mut c, gaze(3, 0.25, 0.75)).await;
    assert_eq!(h.codec, Codec::Png);
    let streamed = image::load_from_memory(&png).unwrap().to_rgba8().into_raw();
    let mut req = FrameRequest::new(fovea::scene::DEFAULT_SCENE, 72, 40);
    req.gaze = [0.25, 0.75];
    req.marker = true;
    let direct = Renderer::new().unwrap().render(&req).unwrap().rgba;
    assert!(
        streamed == direct,
        "PNG frame differs from a direct render of the same request"
    );
    server.stop().await;
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn settings_change_the_sampling_live_and_bad_settings_are_refused() {
    let server = Server::start().await;
    let mut c = server.client().await;
    // Large enough that the periphery is finer than the eye resolves (at 96×72 on a 53 cm
    // display every pixel is coarser than the fovea's MAR, and every pixel is needed).
    let w = c
        .hello(&Hello {
            preset: "full".into(),
            ..hello(320, 240)
        })
        .await
        .unwrap();
    assert!(
        w.presets.iter().any(|p| p == "balanced") && w.presets.iter().any(|p| p == "reference")
    );
    let (h, _) = frame_for(&mut c, gaze(1, 0.5, 0.5)).await;
    assert_eq!(h.sampled, 1.0, "full shades every pixel");
    c.send_text(r#"{"type":"settings","preset":"fast"}"#)
        .await
        .unwrap();
    let (h, _) = frame_for(&mut c, gaze(2, 0.5, 0.5)).await;
    assert!(
        h.sampled > 0.0 && h.sampled < 0.5,
        "fast shades a fraction: {}",
        h.sampled
    );
    c.send_text(r#"{"type":"settings","min_probability":1.0}"#)
        .await
        .unwrap();
    let (h3, _) = frame_for(&mut c, gaze(3, 0.5, 0.5)).await;
    assert!(
        h3.sampled > h.sampled,
        "ξ = 1 shades every covered pixel: {} vs {}",
        h3.sampled,
        h.sampled
    );
    let cases: &[(&str, ErrorCode)] = &[
        (
            r#"{"type":"settings","preset":"ultra"}"#,
            ErrorCode::UnknownPreset,
        ),
        (
            r#"{"type":"settings","mar_slope":-1}"#,
            ErrorCode::OutOfRange,
        ),
        (
            r#"{"type":"settings","min_probability":2}"#,
            ErrorCode::OutOfRange,
        ),
        (
            r#"{"type":"settings","warp_drive":true}"#,
            ErrorCode::BadField,
        ),
        (r#"{"type":"settings","noise":"pink"}"#, ErrorCode::BadField),
    ];
    for (text, code) in cases {
        c.send_text(text).await.unwrap();
        assert_eq!(next_error(&mut c).await, *code, "for {text}");
    }
    let (h, _) = frame_for(&mut c, gaze(4, 0.2, 0.2)).await;
    assert_eq!(h.seq, Some(4), "the session survives bad settings");
    server.stop().await;
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

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn page_health_and_shutdown() {
    let server = Server::start().await;
    let health = http_get(server.addr, "/healthz").await;
    assert!(
        health.starts_with("HTTP/1.1 200") && health.ends_with("ok\n"),
        "{health}"
    );
    let page = http_get(server.addr, "/").await;
    assert!(
        page.starts_with("HTTP/1.1 200") && page.contains("<canvas"),
        "{page}"
    );
    let js = http_get(server.addr, "/app.js").await;
    assert!(js.contains("content-type: text/javascript"), "{js}");
    assert!(http_get(server.addr, "/nope")
        .await
        .starts_with("HTTP/1.1 404"));

    let mut c = server.client().await;
    c.hello(&hello(32, 32)).await.unwrap();
    let _ = next_frame(&mut c).await;
    server.shutdown.cancel();
    let mut told = false;
    let close = loop {
        match c.next_event(WAIT).await {
            Ok(Event::Closed(close)) => break close,
            Ok(Event::Goodbye(g)) => told = g.reason == "draining",
            Ok(_) => continue,
            Err(e) => panic!("expected a close frame, got {e}"),
        }
    };
    assert!(told, "a goodbye came before the close");
    assert_eq!(
        close.map(|(code, _)| code),
        Some(1001),
        "sessions are told the server is going away"
    );
    tokio::time::timeout(WAIT, server.task)
        .await
        .expect("server stops")
        .unwrap()
        .unwrap();
}
