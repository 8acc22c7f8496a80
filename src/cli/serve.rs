//! `fovea serve`: the renderer and its thread, the async runtime, the listener, and the
//! signals that start a drain.

use std::net::SocketAddr;

use anyhow::{Context, Result};
use fovea::render::{RenderThread, Renderer};
use tokio_util::sync::CancellationToken;

pub fn serve(addr: SocketAddr, options: fovea::server::ServerOptions) -> Result<()> {
    let mut renderer = Renderer::new().context("opening the GPU")?;
    renderer.set_catalog(options.catalog.clone());
    renderer
        .load_scene(fovea::scene::DEFAULT_SCENE)
        .context("loading the default scene")?;
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
    let (render, render_thread) =
        RenderThread::spawn(renderer).context("starting the render thread")?;
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
