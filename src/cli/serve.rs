//! `fovea serve`: the renderer and its thread, the async runtime, the listener, and the
//! signals that start a drain.

use std::net::SocketAddr;

use anyhow::{Context, Result};
use fovea::render::{RenderThread, Renderer};
use tokio_util::sync::CancellationToken;

/// What to do when the adapter cannot run Fovea (said once, where the server refuses to start).
const DRIVER_HINT: &str = "Fovea needs a Vulkan (or Metal, DX12) adapter: install a Vulkan \
driver (without a GPU: `apt-get install mesa-vulkan-drivers`, Mesa's lavapipe) and leave \
WGPU_BACKEND unset or set to vulkan";

pub fn serve(addr: SocketAddr, options: fovea::server::ServerOptions) -> Result<()> {
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

/// Renders one tiny frame before serving: an adapter that lists itself but cannot run the
/// passes (the GL backend has no float render targets) is refused here, in one line, instead of
/// answering /readyz 200 and failing every frame.
fn self_test(renderer: &mut Renderer) -> Result<()> {
    let probe = fovea::render::FrameRequest::new(fovea::scene::DEFAULT_SCENE, 16, 16);
    let result = renderer.render(&probe);
    renderer.release_stream(probe.stream);
    match result {
        Ok(_) => Ok(()),
        Err(e) => anyhow::bail!(
            "the GPU adapter {} cannot run Fovea's passes ({e}). {DRIVER_HINT}",
            renderer.adapter()
        ),
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
