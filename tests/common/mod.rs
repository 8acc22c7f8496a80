//! A server on a loopback port for tests, stopped the way production stops: cancel, wait for
//! the server task, then join the render thread, so no test process exits while the render
//! thread is still inside the Vulkan driver (lavapipe crashes at exit if it is).

#![allow(dead_code)] // each test binary uses a part of this

pub mod frames;
pub mod images;
pub mod radiosity;

use std::net::SocketAddr;
use std::time::Duration;

use fovea::render::{RenderThread, Renderer};
use fovea::server::ServerOptions;
use tokio_util::sync::CancellationToken;

pub struct Running {
    shutdown: CancellationToken,
    task: tokio::task::JoinHandle<std::io::Result<()>>,
    thread: std::thread::JoinHandle<()>,
}

impl Running {
    pub async fn stop(self) {
        self.shutdown.cancel();
        let wait = Duration::from_secs(30);
        let _ = tokio::time::timeout(wait, self.task).await;
        let thread = self.thread;
        let _ =
            tokio::time::timeout(wait, tokio::task::spawn_blocking(move || thread.join())).await;
    }
}

pub async fn start(options: ServerOptions) -> (SocketAddr, Running) {
    start_on("127.0.0.1:0".parse().unwrap(), options).await
}

/// A server on `addr`: a given port lets a test put a second instance where a drained one was.
pub async fn start_on(addr: SocketAddr, options: ServerOptions) -> (SocketAddr, Running) {
    let renderer = Renderer::new().unwrap_or_else(|e| panic!("GPU tests need an adapter: {e}"));
    start_with(addr, options, renderer, Default::default()).await
}

/// A server whose frame costs are calibrated first, as `fovea serve` does (admission and
/// slicing then work from this adapter's figures).
pub async fn start_calibrated(options: ServerOptions) -> (SocketAddr, Running) {
    let (renderer, cost) = calibrated();
    start_with("127.0.0.1:0".parse().unwrap(), options, renderer, cost).await
}

/// A renderer and its calibrated frame costs, for a test that sets budgets from them.
pub fn calibrated() -> (Renderer, fovea::render::cost::CostModel) {
    let mut renderer = Renderer::new().unwrap_or_else(|e| panic!("GPU tests need an adapter: {e}"));
    let cost = fovea::render::cost::CostModel::default();
    fovea::render::cost::calibrate(&mut renderer, &cost, fovea::scene::DEFAULT_SCENE);
    (renderer, cost)
}

pub async fn start_with(
    addr: SocketAddr,
    options: ServerOptions,
    mut renderer: Renderer,
    cost: fovea::render::cost::CostModel,
) -> (SocketAddr, Running) {
    renderer.set_catalog(options.catalog.clone());
    let (render, thread) = RenderThread::spawn_with(renderer, cost).unwrap();
    let listener = tokio::net::TcpListener::bind(addr).await.unwrap();
    let addr = listener.local_addr().unwrap();
    let shutdown = CancellationToken::new();
    let task = tokio::spawn(fovea::server::run_with(
        listener,
        render,
        shutdown.clone(),
        options,
    ));
    (
        addr,
        Running {
            shutdown,
            task,
            thread,
        },
    )
}

/// Unit view ray through pixel `k`'s centre of a `w`×`h` frame of `scene` (what the shaders'
/// `view_ray` computes), for tests that rebuild a pixel's shading on the CPU.
pub fn view_ray(scene: &fovea::scene::Scene, w: u32, h: u32, k: usize) -> glam::Vec3 {
    let cam = scene.file.camera;
    let inv = cam.view_proj(w, h).inverse();
    let (x, y) = ((k as u32 % w) as f32 + 0.5, (k as u32 / w) as f32 + 0.5);
    let ndc = glam::Vec4::new(x / w as f32 * 2.0 - 1.0, 1.0 - y / h as f32 * 2.0, 1.0, 1.0);
    let far = inv * ndc;
    (far.truncate() / far.w - glam::Vec3::from(cam.eye)).normalize()
}

/// The one run folder (`run-…`) a server made inside its `--record-dir`.
pub fn run_folder(record_dir: &std::path::Path) -> std::path::PathBuf {
    let runs: Vec<_> = std::fs::read_dir(record_dir)
        .unwrap_or_else(|e| panic!("{}: {e}", record_dir.display()))
        .map(|e| e.unwrap().path())
        .filter(|p| p.is_dir())
        .collect();
    assert_eq!(
        runs.len(),
        1,
        "one run folder in {}: {runs:?}",
        record_dir.display()
    );
    runs[0].clone()
}

/// Drives a session for `span` like a viewer (a moving gaze, every frame acknowledged) and
/// returns the intervals between its frames, in ms.
pub async fn frame_intervals(c: &mut fovea::client::Client, span: Duration) -> Vec<f64> {
    use fovea::client::Event;
    use fovea::protocol::{Ack, Gaze};
    let start = std::time::Instant::now();
    let (mut last, mut out, mut seq) = (None::<std::time::Instant>, Vec::new(), 0u64);
    while start.elapsed() < span {
        seq += 1;
        let x = 0.3 + 0.4 * ((seq as f64) / 70.0).sin().abs();
        let g = Gaze {
            seq,
            t_ms: seq as f64 * 10.0,
            x,
            y: 0.5,
            pupil_mm: None,
            sample_t_ms: None,
        };
        c.gaze(&g).await.unwrap();
        match c.next_event(Duration::from_secs(60)).await.unwrap() {
            Event::Frame { header, .. } => {
                let now = std::time::Instant::now();
                if let Some(l) = last {
                    out.push((now - l).as_secs_f64() * 1e3);
                }
                last = Some(now);
                let ack = Ack {
                    frame: header.frame,
                    t_ms: None,
                    dropped: false,
                };
                c.ack(&ack).await.unwrap();
            }
            other => panic!("unexpected {other:?}"),
        }
    }
    out
}

pub fn median(mut v: Vec<f64>) -> f64 {
    assert!(!v.is_empty(), "no intervals");
    v.sort_by(f64::total_cmp);
    v[v.len() / 2]
}
