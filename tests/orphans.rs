//! The orphan storm: sockets that say hello at a large size and vanish 50 ms later, over and
//! over. Their frames must not be rendered for nobody and their targets must not stay: another
//! session keeps its frame rate within a stated factor, and the server's memory comes back to
//! within 10% of where it was within 5 s of the storm's end.

mod common;

use std::time::{Duration, Instant};

use fovea::client::Client;
use fovea::protocol::Hello;
use fovea::server::ServerOptions;

/// How much slower the other session's frames may come during the storm.
const FACTOR: f64 = 3.0;

fn rss_bytes() -> u64 {
    let statm = std::fs::read_to_string("/proc/self/statm").unwrap_or_default();
    let pages: u64 = statm
        .split_whitespace()
        .nth(1)
        .and_then(|p| p.parse().ok())
        .unwrap_or(0);
    pages * 4096
}

/// `n` sockets, alternately 4K foveated and 720p full-shading hellos, each gone 50 ms after
/// its hello; returns how many hellos were sent.
async fn storm(url: String, n: usize) -> usize {
    let mut sent = 0;
    for i in 0..n {
        let (w, h, preset) = if i % 2 == 0 {
            (3840, 2160, "balanced")
        } else {
            (1280, 720, "full")
        };
        let Ok(mut c) = Client::connect(&url).await else {
            continue;
        };
        let hello = format!(r#"{{"type":"hello","width":{w},"height":{h},"preset":"{preset}"}}"#);
        if c.send_text(&hello).await.is_ok() {
            sent += 1;
        }
        tokio::time::sleep(Duration::from_millis(50)).await;
        drop(c);
    }
    sent
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn an_orphan_storm_leaves_other_sessions_and_memory_as_they_were() {
    let (addr, server) = common::start_calibrated(ServerOptions::default()).await;
    let url = format!("ws://{addr}/ws");
    let mut victim = Client::connect(&url).await.unwrap();
    victim
        .hello(&Hello {
            width: 320,
            height: 240,
            ..Default::default()
        })
        .await
        .unwrap();
    let alone = common::median(common::frame_intervals(&mut victim, Duration::from_secs(3)).await);

    // A small storm first, so what any first 720p frame builds once (pipelines, the
    // allocator's pools) is in the baseline; then the storm, beside the other session.
    storm(url.clone(), 4).await;
    tokio::time::sleep(Duration::from_secs(1)).await;
    let rss_before = rss_bytes();
    let storm = tokio::spawn(storm(url.clone(), 40));
    let during = common::median(common::frame_intervals(&mut victim, Duration::from_secs(4)).await);
    let sent = storm.await.unwrap();
    let ended = Instant::now();
    let mut rss_after = rss_bytes();
    while rss_after as f64 > 1.1 * rss_before as f64 && ended.elapsed() < Duration::from_secs(5) {
        tokio::time::sleep(Duration::from_millis(200)).await;
        rss_after = rss_bytes();
    }
    eprintln!(
        "orphan storm ({sent} hellos): the other session's median frame interval {alone:.0} ms \
         before, {during:.0} ms during; memory {:.0} MB before, {:.0} MB {:.1} s after",
        rss_before as f64 / 1e6,
        rss_after as f64 / 1e6,
        ended.elapsed().as_secs_f64()
    );
    assert!(sent >= 30, "only {sent} hellos reached the server");
    assert!(
        during <= FACTOR * alone,
        "frames every {during:.0} ms during the storm against {alone:.0} ms before"
    );
    assert!(
        rss_after as f64 <= 1.1 * rss_before as f64,
        "memory {} MB, against {} MB before the storm",
        rss_after / 1_000_000,
        rss_before / 1_000_000
    );
    server.stop().await;
}
