//! `fovea serve`: the renderer and its thread, the async runtime, the listener, and the
//! signals that start a drain.

use std::net::SocketAddr;
use std::path::PathBuf;

use anyhow::{Context, Result};
use fovea::render::{RenderThread, Renderer};
use tokio_util::sync::CancellationToken;

/// What to do when the adapter cannot run Fovea (said once, where the server refuses to start).
const DRIVER_HINT: &str = "Fovea needs a Vulkan (or Metal, DX12) adapter: install a Vulkan \
driver (without a GPU: `apt-get install mesa-vulkan-drivers`, Mesa's lavapipe) and leave \
WGPU_BACKEND unset or set to vulkan";

#[derive(clap::Args)]
pub struct ServeArgs {
    /// Address to listen on. Port 0 picks a free port.
    #[arg(long, default_value = "127.0.0.1:8080")]
    pub addr: SocketAddr,
    /// Record every session's received gaze samples to DIR/run-…/session-<id>.csv (one folder per run; generic CSV,
    /// replayable with `fovea replay`).
    #[arg(long)]
    pub record_dir: Option<PathBuf>,
    /// A session's recording stops at this many MiB (its client is told; the session goes
    /// on): ~25 bytes a sample, so 64 MiB is ~9 hours at 120 Hz.
    #[arg(long, default_value_t = 64, value_parser = clap::value_parser!(u64).range(1..=16384))]
    pub record_max_mb: u64,
    /// Recording stops for every session (each client told once) and no new recording starts
    /// once the --record-dir folder holds this many MiB, runs before this one included.
    #[arg(long, default_value_t = 1024, value_parser = clap::value_parser!(u64).range(1..=1048576))]
    pub record_dir_max_mb: u64,
    /// A folder of scenes to serve beside the built-in ones (repeatable): every scene file
    /// (.json) and glTF file (.gltf, .glb) at its top level, named by file stem. Files
    /// they refer to are read from inside the folder only.
    #[arg(long = "scenes", value_name = "DIR")]
    pub scenes: Vec<PathBuf>,
    /// Sessions served at once; more are refused (WebSocket close 1013, /readyz 503).
    #[arg(long, default_value_t = 16, value_parser = clap::value_parser!(u64).range(1..=10000))]
    pub max_sessions: u64,
    /// Seconds a client may leave frames unacknowledged (or stop reading) before it is
    /// disconnected.
    #[arg(long, default_value_t = 10.0, value_parser = super::parse::parse_seconds)]
    pub stall_timeout_s: f64,
    /// Seconds a new socket may take to say hello before it is closed (1008), so silent
    /// sockets cannot hold session slots.
    #[arg(long, default_value_t = 5.0, value_parser = super::parse::parse_seconds)]
    pub hello_timeout_s: f64,
    /// Seconds between WebSocket pings to each client; one from which nothing, not even a
    /// pong, has come for three is disconnected (half-open connections, dead peers).
    #[arg(long, default_value_t = 10.0, value_parser = super::parse::parse_seconds)]
    pub ping_every_s: f64,
    /// Seconds a drain (SIGTERM, POST /admin/drain) gives sessions to move to another
    /// instance: they are sent `goodbye` at once and closed with 1001 when it ends.
    #[arg(long, default_value_t = 10.0, value_parser = super::parse::parse_seconds)]
    pub drain_s: f64,
    #[command(flatten)]
    pub access: super::access::AccessArgs,
    /// Seconds a client may take to send a request's headers (the WebSocket upgrade's too);
    /// an idle keep-alive connection is closed after it as well.
    #[arg(long, default_value_t = 10.0, value_parser = super::parse::parse_seconds)]
    pub header_timeout_s: f64,
    /// HTTP connections open at once that are not (yet) sessions; at the cap new ones wait in
    /// the kernel's backlog until one closes.
    #[arg(long, default_value_t = 256, value_parser = clap::value_parser!(u64).range(1..=65536))]
    pub max_pending: u64,
    /// Longest a session's frame may take on the renderer, counting its share with the other
    /// sessions (its render time × sessions rendering). A hello or settings change past it is
    /// refused with `over_budget`, naming the largest size that fits. Frames longer than
    /// 100 ms are rendered in parts, so others' frames are never stuck behind one. From
    /// 0.001 to 3600.
    #[arg(long, default_value_t = 10.0, value_parser = super::parse::parse_frame_budget)]
    pub frame_budget_s: f64,
}

impl ServeArgs {
    fn options(self) -> Result<fovea::server::ServerOptions> {
        let (access, insecure) = self.access.resolve()?;
        fovea::server::check_exposure(self.addr, &access, insecure).map_err(anyhow::Error::msg)?;
        let secs = std::time::Duration::from_secs_f64;
        Ok(fovea::server::ServerOptions {
            record_dir: self.record_dir,
            record_max_bytes: self.record_max_mb * 1024 * 1024,
            record_dir_max_bytes: self.record_dir_max_mb * 1024 * 1024,
            max_sessions: self.max_sessions as usize,
            stall_timeout: secs(self.stall_timeout_s),
            hello_timeout: secs(self.hello_timeout_s),
            ping_every: secs(self.ping_every_s),
            catalog: fovea::scene::Catalog::with_folders(&self.scenes)?,
            drain: secs(self.drain_s),
            access,
            frame_budget: secs(self.frame_budget_s),
            connections: fovea::server::ConnectionLimits {
                header_timeout: secs(self.header_timeout_s),
                max_pending: self.max_pending as usize,
            },
        })
    }
}

pub fn serve(args: ServeArgs) -> Result<()> {
    let addr: SocketAddr = args.addr;
    let mut options = args.options()?;
    fit_descriptors(&mut options.connections, options.max_sessions);
    let mut renderer =
        Renderer::new().map_err(|e| anyhow::anyhow!("opening the GPU: {e}. {DRIVER_HINT}"))?;
    renderer.set_catalog(options.catalog.clone());
    renderer
        .load_scene(fovea::scene::DEFAULT_SCENE)
        .context("loading the default scene")?;
    self_test(&mut renderer)?;
    // Scenes from --scenes folders go onto the GPU now (built-in ones are small), so the first
    // viewer of a large model does not hold the render thread, and every session, while it loads.
    for entry in options
        .catalog
        .entries()
        .iter()
        .filter(|e| e.file.is_some())
    {
        if let Err(e) = renderer.load_scene(&entry.name) {
            tracing::error!("scene {} does not load onto the GPU: {e}", entry.name);
        }
    }
    let cost = fovea::render::cost::CostModel::default();
    let took = fovea::render::cost::calibrate(&mut renderer, &cost, fovea::scene::DEFAULT_SCENE);
    let took: Vec<String> = took
        .iter()
        .map(|(p, ms)| format!("{p} {ms:.0} ms"))
        .collect();
    tracing::info!(
        "estimated 1920x1080 frame times on this adapter (calibrated; admission and slicing start from these): {}",
        took.join(", ")
    );
    let (render, render_thread) =
        RenderThread::spawn_with(renderer, cost).context("starting the render thread")?;
    let runtime = tokio::runtime::Runtime::new().context("starting the async runtime")?;
    runtime.block_on(async move {
        let listener = tokio::net::TcpListener::bind(addr)
            .await
            .with_context(|| format!("binding {addr}"))?;
        let local = listener.local_addr()?;
        println!("fovea listening on http://{local}/");
        let shutdown = CancellationToken::new();
        tokio::spawn(stop_on_signal(shutdown.clone()));
        fovea::server::run_with(listener, render, shutdown, options)
            .await
            .context("serving")?;
        tracing::info!("server stopped");
        anyhow::Ok(())
    })?;
    // Every RenderHandle is gone with the server, so the render thread is finishing too.
    let _ = render_thread.join();
    Ok(())
}

/// Renders one tiny frame before serving: an adapter that lists itself but cannot run the
/// passes (the GL backend has no float render targets) is refused here, in one line, instead of
/// answering /readyz 200 and failing every frame.
fn self_test(renderer: &mut Renderer) -> Result<()> {
    let probe = fovea::render::FrameRequest::new(fovea::scene::DEFAULT_SCENE, 16, 16);
    let result = renderer.render(&probe);
    renderer.release_stream(probe.stream);
    match result {
        Ok(_) => Ok(()),
        Err(e) => {
            // wgpu's validation errors span lines; the refusal stays one line.
            let why = e
                .to_string()
                .split_whitespace()
                .collect::<Vec<_>>()
                .join(" ");
            anyhow::bail!(
                "the GPU adapter {} cannot run Fovea's passes ({why}). {DRIVER_HINT}",
                renderer.adapter()
            )
        }
    }
}

async fn stop_on_signal(shutdown: CancellationToken) {
    let ctrl_c = tokio::signal::ctrl_c();
    #[cfg(unix)]
    {
        let mut term =
            match tokio::signal::unix::signal(tokio::signal::unix::SignalKind::terminate()) {
                Ok(t) => t,
                Err(e) => {
                    tracing::warn!("cannot watch SIGTERM: {e}");
                    let _ = ctrl_c.await;
                    shutdown.cancel();
                    return;
                }
            };
        tokio::select! {
            _ = ctrl_c => {}
            _ = term.recv() => {}
        }
    }
    #[cfg(not(unix))]
    let _ = ctrl_c.await;
    tracing::info!("signal: draining (a second signal is not needed; the drain is bounded)");
    shutdown.cancel();
}

/// Keeps the pending-connection cap inside the process's file descriptors: the soft limit is
/// raised to the hard one, and if pending connections, sessions (a socket and a recording
/// each) and a reserve for the driver and files still do not fit, the cap is lowered (said once)
/// so a flood of half-open connections cannot leave the server unable to accept or open files.
fn fit_descriptors(limits: &mut fovea::server::ConnectionLimits, max_sessions: usize) {
    const RESERVE: u64 = 64;
    let mut lim = libc::rlimit {
        rlim_cur: 0,
        rlim_max: 0,
    };
    // SAFETY: getrlimit/setrlimit only read and write the struct we pass.
    if unsafe { libc::getrlimit(libc::RLIMIT_NOFILE, &mut lim) } != 0 {
        return;
    }
    if lim.rlim_cur < lim.rlim_max {
        let raised = libc::rlimit {
            rlim_cur: lim.rlim_max,
            rlim_max: lim.rlim_max,
        };
        // SAFETY: as above.
        if unsafe { libc::setrlimit(libc::RLIMIT_NOFILE, &raised) } == 0 {
            lim = raised;
        }
    }
    let fit = lim
        .rlim_cur
        .saturating_sub(RESERVE + 2 * max_sessions as u64)
        .max(8);
    if (limits.max_pending as u64) > fit {
        tracing::warn!(
            "--max-pending {} lowered to {fit}: the process may open {} files (ulimit -n)",
            limits.max_pending,
            lim.rlim_cur
        );
        limits.max_pending = fit as usize;
    }
}
