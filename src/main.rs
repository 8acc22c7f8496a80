//! The `fovea` command line: `serve` and `render` (replay, load and bench come with their work).

use std::net::SocketAddr;
use std::path::PathBuf;

use anyhow::{bail, Context, Result};
use clap::{Parser, Subcommand};
use glam::Vec3;
use tokio_util::sync::CancellationToken;

use fovea::protocol::Codec;
use fovea::render::{FrameRequest, RenderThread, Renderer};

#[derive(Parser)]
#[command(name = "fovea", version, about = "Gaze-streaming rendering service: frames that follow the eye, rendered headless on the GPU and streamed to a browser")]
struct Cli {
    #[command(subcommand)]
    command: Command,
}

#[derive(Subcommand)]
enum Command {
    /// Serve the web client on / and gaze-driven frames over the WebSocket /ws.
    ///
    /// Logs go to stderr (RUST_LOG=fovea=debug for more); the first line on stdout is
    /// "fovea listening on http://ADDR/", with the real port when --addr asks for port 0.
    Serve {
        /// Address to listen on. Port 0 picks a free port.
        #[arg(long, default_value = "127.0.0.1:8080")]
        addr: SocketAddr,
    },
    /// Render one frame to an image file, without a server.
    Render {
        /// Scene to render (built-in: bunny).
        #[arg(long, default_value = fovea::scene::DEFAULT_SCENE)]
        scene: String,
        #[arg(long, default_value_t = 640)]
        width: u32,
        #[arg(long, default_value_t = 480)]
        height: u32,
        /// Gaze as X,Y in [0,1], top-left origin; the marker is drawn there.
        #[arg(long, value_parser = parse_gaze, default_value = "0.5,0.5")]
        gaze: [f32; 2],
        /// Leave out the gaze marker.
        #[arg(long)]
        no_marker: bool,
        /// Override the light: direction towards it as X,Y,Z.
        #[arg(long, value_parser = parse_vec3)]
        light: Option<Vec3>,
        /// Output file; .png (lossless) or .jpg/.jpeg.
        #[arg(long)]
        out: PathBuf,
        /// JPEG quality 1–100.
        #[arg(long, default_value_t = 90, value_parser = clap::value_parser!(u8).range(1..=100))]
        quality: u8,
    },
}

fn parse_gaze(s: &str) -> Result<[f32; 2], String> {
    let v: Vec<f32> = s.split(',').map(|p| p.trim().parse::<f32>()).collect::<Result<_, _>>().map_err(|e| format!("{s:?}: {e}"))?;
    match v.as_slice() {
        [x, y] if (0.0..=1.0).contains(x) && (0.0..=1.0).contains(y) => Ok([*x, *y]),
        [_, _] => Err(format!("{s:?}: both coordinates must lie in [0, 1]")),
        _ => Err(format!("{s:?}: expected X,Y")),
    }
}

fn parse_vec3(s: &str) -> Result<Vec3, String> {
    let v: Vec<f32> = s.split(',').map(|p| p.trim().parse::<f32>()).collect::<Result<_, _>>().map_err(|e| format!("{s:?}: {e}"))?;
    match v.as_slice() {
        [x, y, z] if Vec3::new(*x, *y, *z).try_normalize().is_some() => Ok(Vec3::new(*x, *y, *z)),
        [_, _, _] => Err(format!("{s:?}: the direction must be finite and non-zero")),
        _ => Err(format!("{s:?}: expected X,Y,Z")),
    }
}

fn main() -> Result<()> {
    tracing_subscriber::fmt()
        .with_env_filter(
            tracing_subscriber::EnvFilter::try_from_default_env()
                .unwrap_or_else(|_| "fovea=info,wgpu_core=warn,wgpu_hal=warn".into()),
        )
        .with_writer(std::io::stderr)
        .init();
    match Cli::parse().command {
        Command::Serve { addr } => serve(addr),
        Command::Render { scene, width, height, gaze, no_marker, light, out, quality } => {
            let mut request = FrameRequest::new(&scene, width, height);
            request.gaze = (!no_marker).then_some(gaze);
            request.to_light = light;
            render(request, &out, quality)
        }
    }
}

fn serve(addr: SocketAddr) -> Result<()> {
    let mut renderer = Renderer::new().context("opening the GPU")?;
    renderer.load_scene(fovea::scene::DEFAULT_SCENE).context("loading the default scene")?;
    let (render, render_thread) = RenderThread::spawn(renderer).context("starting the render thread")?;
    let runtime = tokio::runtime::Runtime::new().context("starting the async runtime")?;
    runtime.block_on(async move {
        let listener = tokio::net::TcpListener::bind(addr).await.with_context(|| format!("binding {addr}"))?;
        let local = listener.local_addr()?;
        println!("fovea listening on http://{local}/");
        let shutdown = CancellationToken::new();
        tokio::spawn(stop_on_signal(shutdown.clone()));
        fovea::server::run(listener, render, shutdown).await.context("serving")?;
        tracing::info!("server stopped");
        anyhow::Ok(())
    })?;
    // Every RenderHandle is gone with the server, so the render thread is finishing too.
    let _ = render_thread.join();
    Ok(())
}

async fn stop_on_signal(shutdown: CancellationToken) {
    let ctrl_c = tokio::signal::ctrl_c();
    #[cfg(unix)]
    {
        let mut term = match tokio::signal::unix::signal(tokio::signal::unix::SignalKind::terminate()) {
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
    tracing::info!("shutting down: closing sessions");
    shutdown.cancel();
}

fn render(request: FrameRequest, out: &std::path::Path, quality: u8) -> Result<()> {
    let ext = out.extension().and_then(|e| e.to_str()).map(str::to_ascii_lowercase);
    let codec = match ext.as_deref() {
        Some("png") => Codec::Png,
        Some("jpg" | "jpeg") => Codec::Jpeg,
        _ => bail!("{}: the output must end in .png, .jpg or .jpeg", out.display()),
    };
    let mut renderer = Renderer::new().context("opening the GPU")?;
    eprintln!("adapter: {}", renderer.adapter());
    let frame = renderer.render(&request).with_context(|| format!("rendering scene {:?}", request.scene))?;
    let started = std::time::Instant::now();
    let bytes = fovea::encode::encode(&frame.rgba, frame.width, frame.height, codec, quality)?;
    let encode_ms = started.elapsed().as_secs_f64() * 1e3;
    std::fs::write(out, &bytes).with_context(|| format!("writing {}", out.display()))?;
    eprintln!(
        "wrote {} ({}x{}, {} bytes): render {:.2} ms, readback {:.2} ms, encode {:.2} ms",
        out.display(),
        frame.width,
        frame.height,
        bytes.len(),
        frame.render_ms,
        frame.readback_ms,
        encode_ms
    );
    Ok(())
}
