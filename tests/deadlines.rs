//! Connections that never become sessions cannot hold the server: a request (or upgrade) whose
//! headers do not arrive in time is closed, and past the cap on pending connections newcomers
//! wait in the backlog until one closes, then get served.

mod common;

use std::time::{Duration, Instant};

use fovea::server::{ConnectionLimits, ServerOptions};
use tokio::io::{AsyncReadExt, AsyncWriteExt};
use tokio::net::TcpStream;

const WAIT: Duration = Duration::from_secs(30);

fn options(header_timeout: Duration, max_pending: usize) -> ServerOptions {
    ServerOptions {
        connections: ConnectionLimits {
            header_timeout,
            max_pending,
        },
        ..ServerOptions::default()
    }
}

/// Reads until the peer closes; returns what came.
async fn read_to_close(tcp: &mut TcpStream) -> Vec<u8> {
    let mut got = Vec::new();
    tokio::time::timeout(WAIT, tcp.read_to_end(&mut got))
        .await
        .expect("the server closes the connection")
        .ok();
    got
}

async fn healthz(addr: std::net::SocketAddr) -> String {
    let mut tcp = TcpStream::connect(addr).await.unwrap();
    tcp.write_all(b"GET /healthz HTTP/1.1\r\nHost: x\r\nConnection: close\r\n\r\n")
        .await
        .unwrap();
    String::from_utf8_lossy(&read_to_close(&mut tcp).await).into_owned()
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn a_half_sent_upgrade_is_closed_by_the_header_deadline() {
    let (addr, server) = common::start(options(Duration::from_millis(500), 256)).await;
    let mut tcp = TcpStream::connect(addr).await.unwrap();
    // The upgrade's first lines, then silence (a slowloris client).
    tcp.write_all(b"GET /ws HTTP/1.1\r\nHost: x\r\nUpgrade: websocket\r\n")
        .await
        .unwrap();
    let start = Instant::now();
    read_to_close(&mut tcp).await;
    let waited = start.elapsed();
    assert!(
        waited >= Duration::from_millis(400),
        "closed before the deadline: {waited:?}"
    );
    // An idle keep-alive connection is closed by the same deadline.
    let mut idle = TcpStream::connect(addr).await.unwrap();
    idle.write_all(b"GET /healthz HTTP/1.1\r\nHost: x\r\n\r\n")
        .await
        .unwrap();
    let answer = String::from_utf8_lossy(&read_to_close(&mut idle).await).into_owned();
    assert!(answer.starts_with("HTTP/1.1 200"), "{answer}");
    server.stop().await;
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn past_the_pending_cap_newcomers_wait_and_are_served_when_room_comes() {
    let (addr, server) = common::start(options(Duration::from_millis(1500), 4)).await;
    let mut silent = Vec::new();
    for _ in 0..4 {
        let mut tcp = TcpStream::connect(addr).await.unwrap();
        tcp.write_all(b"GET / HTTP/1.1\r\n").await.unwrap();
        silent.push(tcp);
    }
    // Let the server accept all four before the newcomer arrives.
    tokio::time::sleep(Duration::from_millis(200)).await;
    let start = Instant::now();
    let answer = healthz(addr).await;
    let waited = start.elapsed();
    assert!(answer.starts_with("HTTP/1.1 200"), "{answer}");
    assert!(
        waited >= Duration::from_millis(800),
        "the fifth connection was served while four held every permit ({waited:?})"
    );
    // With room again, a request is served at once (well before another deadline).
    drop(silent);
    let answer = healthz(addr).await;
    assert!(answer.starts_with("HTTP/1.1 200"), "{answer}");
    server.stop().await;
}

/// SIGTERM's path with a client that never reads: its frames pile up unsent, yet the server
/// exits within the drain's grace (plus the wait for close frames), and the recording holds
/// every gaze sample the client sent.
#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn a_drain_ends_on_time_with_a_client_that_never_reads_and_keeps_its_gaze() {
    use fovea::client::Client;
    use fovea::protocol::{Gaze, Hello};
    let dir = std::env::temp_dir().join(format!("fovea-blocked-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    let grace = Duration::from_millis(1500);
    let (addr, server) = common::start(ServerOptions {
        drain: grace,
        record_dir: Some(dir.clone()),
        ..ServerOptions::default()
    })
    .await;
    let mut c = Client::connect(&format!("ws://{addr}/ws")).await.unwrap();
    c.hello(&Hello {
        width: 640,
        height: 480,
        codec: fovea::protocol::Codec::Png,
        max_in_flight: 8,
        ..Hello::default()
    })
    .await
    .unwrap();
    // Gaze for two seconds, never reading: PNG frames fill the socket's buffers.
    let sent = 400u64;
    for seq in 1..=sent {
        let x = 0.2 + 0.6 * (seq % 50) as f64 / 50.0;
        let g = Gaze {
            seq,
            t_ms: seq as f64 * 5.0,
            x,
            y: 0.5,
            pupil_mm: None,
            sample_t_ms: None,
        };
        c.gaze(&g).await.unwrap();
        tokio::time::sleep(Duration::from_millis(5)).await;
    }
    let began = Instant::now();
    server.stop().await;
    let took = began.elapsed();
    assert!(
        took <= grace + Duration::from_secs(4),
        "the server took {took:?} to stop with a {grace:?} drain"
    );
    let run = common::run_folder(&dir);
    let text = std::fs::read_to_string(run.join("session-1.csv")).unwrap();
    assert_eq!(
        text.lines().count() as u64,
        sent + 1,
        "header and every sample"
    );
    drop(c);
    let _ = std::fs::remove_dir_all(&dir);
}
