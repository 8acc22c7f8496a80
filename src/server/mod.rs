//! The HTTP + WebSocket server: `GET /` (the embedded web client), `GET /ws` (one session per
//! socket), `GET /healthz`. `run` takes its listener and shutdown signal as arguments so tests
//! can bind 127.0.0.1:0 and stop it when they are done.

pub mod access;
mod admission;
mod app;
mod assets;
mod camera;
mod connection;
mod drain;
mod frame_maker;
mod listen;
pub mod metrics;
mod pacing;
mod recorder;
mod recordings;
mod session;
mod timing;

use std::sync::atomic::AtomicU64;
use std::sync::Arc;
use std::time::Duration;

use tokio::net::TcpListener;
use tokio_util::sync::CancellationToken;
use tokio_util::task::TaskTracker;

use crate::protocol::{Limits, SceneInfo};
use crate::render::RenderHandle;

pub use app::router;
pub use listen::ConnectionLimits;

/// Hard cap on one WebSocket message; above `Limits::max_message_bytes` messages still get a
/// polite `too_large` error, above this the transport closes the socket (code 1009).
pub const HARD_MESSAGE_LIMIT: usize = 64 * 1024;

/// State shared by every request handler and session.
pub struct ServerState {
    /// The only way to the GPU: a queue into the render thread.
    pub render: RenderHandle,
    /// Enforced per message and announced in `welcome`.
    pub limits: Limits,
    /// Scenes a `hello` may name, with their sizes for `welcome`.
    pub scenes: Vec<SceneInfo>,
    /// Each scene's own camera, which `camera` messages start from.
    pub cameras: std::collections::HashMap<String, crate::scene::Camera>,
    /// Session ids, unique for the server's life (logs and `welcome`).
    pub next_session: AtomicU64,
    /// Cancelled to ask for a drain (SIGTERM, `POST /admin/drain`, a test). From that instant
    /// `/readyz` answers 503, no session is admitted and every session says goodbye; one token
    /// (not a second one set by the drain task) so the 202 to a drain request is never followed
    /// by a `ready`.
    pub drain_request: CancellationToken,
    /// Cancelled when the drain's grace period ends: every session closes with 1001.
    pub closing: CancellationToken,
    /// How long sessions get to leave by themselves once the drain begins.
    pub drain_grace: Duration,
    /// Counts live sessions so the drain can wait for them.
    pub sessions: TaskTracker,
    /// Who may open sessions, read metrics and drain.
    pub access: access::Access,
    /// This run's recording folder (inside `--record-dir`), if the server records.
    pub record_dir: Option<std::path::PathBuf>,
    /// Largest recording file; a session's recording stops there.
    pub record_max_bytes: u64,
    /// What the recording folder may still take, shared by every recorder.
    pub record_quota: Arc<recorder::Quota>,
    /// Each recording session's file, fetchable by its own client only.
    pub recordings: recordings::Recordings,
    /// One permit per session: admission control (a new client past the limit is refused
    /// with 1013 and `/readyz` reports not ready).
    pub slots: Arc<tokio::sync::Semaphore>,
    pub max_sessions: usize,
    /// A client that neither acknowledges frames nor reads for this long is disconnected.
    pub stall_timeout: Duration,
    /// WebSocket pings this often; a client silent for three (no pong either) is gone.
    pub ping_every: Duration,
    /// A socket that has not said hello this long after opening is closed (1008), so silent
    /// sockets cannot hold session slots.
    pub hello_timeout: Duration,
}

/// How a server runs beyond its listener and renderer.
#[derive(Debug, Clone)]
pub struct ServerOptions {
    /// Record every session's received gaze samples to `run-…/session-<id>.csv` here.
    pub record_dir: Option<std::path::PathBuf>,
    /// A session's recording stops (and its client is told) at this many bytes.
    pub record_max_bytes: u64,
    /// Recordings stop (and no new one starts) once the record folder holds this many bytes.
    pub record_dir_max_bytes: u64,
    /// Sessions served at once; more are refused with WebSocket close code 1013.
    pub max_sessions: usize,
    /// Disconnect a client with frames outstanding and no acknowledgement for this long.
    pub stall_timeout: Duration,
    /// Ping each client this often; one silent for three pings is disconnected.
    pub ping_every: Duration,
    /// Close a socket that has not said hello this long after opening.
    pub hello_timeout: Duration,
    /// The scenes clients may name (the renderer must have the same catalog).
    pub catalog: crate::scene::Catalog,
    /// Grace period of a drain: sessions are told goodbye at once and closed (1001) after it.
    pub drain: Duration,
    pub access: access::Access,
    /// Header deadline and cap on HTTP connections that are not sessions.
    pub connections: ConnectionLimits,
    /// Longest a session's frame may take, its render time × the sessions sharing the GPU.
    pub frame_budget: Duration,
}

impl Default for ServerOptions {
    fn default() -> Self {
        ServerOptions {
            record_dir: None,
            record_max_bytes: 64 * 1024 * 1024,
            record_dir_max_bytes: 1024 * 1024 * 1024,
            max_sessions: 16,
            stall_timeout: Duration::from_secs(10),
            ping_every: Duration::from_secs(10),
            hello_timeout: Duration::from_secs(5),
            catalog: crate::scene::Catalog::builtin(),
            drain: Duration::from_secs(10),
            access: access::Access::default(),
            connections: ConnectionLimits::default(),
            frame_budget: Duration::from_secs(10),
        }
    }
}

/// Serves until `shutdown` is cancelled, then drains (see `drain`) and returns.
pub async fn run(
    listener: TcpListener,
    render: RenderHandle,
    shutdown: CancellationToken,
) -> std::io::Result<()> {
    run_with(listener, render, shutdown, ServerOptions::default()).await
}

pub async fn run_with(
    listener: TcpListener,
    render: RenderHandle,
    shutdown: CancellationToken,
    options: ServerOptions,
) -> std::io::Result<()> {
    let record_dir = options
        .record_dir
        .as_deref()
        .map(recorder::start_run)
        .transpose()?;
    // Every scene is loaded once here, so a broken file is reported at start-up (and left out)
    // rather than when a client first asks for it.
    let mut cameras = std::collections::HashMap::new();
    let scenes = options
        .catalog
        .names()
        .into_iter()
        .filter_map(|name| match options.catalog.load(&name) {
            Ok(s) => {
                for note in &s.notes {
                    tracing::info!(scene = %name, "{note}");
                }
                cameras.insert(name.clone(), s.file.camera);
                Some(SceneInfo {
                    triangles: s.mesh.triangle_count(),
                    name,
                })
            }
            Err(e) => {
                tracing::error!("scene {name} does not load and is not offered: {e}");
                None
            }
        })
        .collect();
    let state = Arc::new(ServerState {
        render,
        limits: Limits {
            frame_budget_ms: options.frame_budget.as_secs_f64() * 1e3,
            slice_ms: crate::render::SLICE_MS,
            ..Limits::default()
        },
        scenes,
        cameras,
        next_session: AtomicU64::new(1),
        drain_request: shutdown.clone(),
        closing: CancellationToken::new(),
        drain_grace: options.drain,
        sessions: TaskTracker::new(),
        access: options.access,
        record_dir,
        record_max_bytes: options.record_max_bytes,
        record_quota: Arc::new(recorder::Quota::for_folder(
            options
                .record_dir
                .as_deref()
                .unwrap_or(std::path::Path::new("")),
            options.record_dir_max_bytes,
        )),
        recordings: Default::default(),
        slots: Arc::new(tokio::sync::Semaphore::new(options.max_sessions.max(1))),
        max_sessions: options.max_sessions.max(1),
        stall_timeout: options.stall_timeout,
        ping_every: options.ping_every,
        hello_timeout: options.hello_timeout,
    });
    // The exporter's histograms keep growing buckets until upkeep drains them; it runs on a
    // scrape, so a server nobody scrapes would creep (~90 bytes a frame). Run it on a timer.
    if let Some(handle) = metrics::handle() {
        let stop = state.closing.clone();
        tokio::spawn(async move {
            let mut tick = tokio::time::interval(Duration::from_secs(5));
            loop {
                tokio::select! {
                    _ = stop.cancelled() => break,
                    _ = tick.tick() => handle.run_upkeep(),
                }
            }
        });
    }
    let app = router(state.clone());
    let stopped = CancellationToken::new();
    tokio::spawn(drain::run(state.clone(), stopped.clone()));
    listen::serve(
        listener,
        app,
        options.connections,
        stopped,
        drain::CLOSE_WAIT,
    )
    .await?;
    Ok(())
}

/// Refuses to listen beyond this machine with nobody asked for a token: anyone who can reach
/// the port would get sessions on the GPU (`--insecure-no-auth` says that is intended).
pub fn check_exposure(
    addr: std::net::SocketAddr,
    access: &access::Access,
    insecure_no_auth: bool,
) -> Result<(), String> {
    if addr.ip().is_loopback() || access.token.is_some() || insecure_no_auth {
        return Ok(());
    }
    Err(format!(
        "refusing to serve on {addr} without a token: anyone who reaches it could open sessions. \
         Set --token (or FOVEA_TOKEN), listen on 127.0.0.1, or pass --insecure-no-auth"
    ))
}
