//! The render thread: the only place that touches the GPU. Sessions send it requests over a
//! bounded channel and await the reply, so async tasks never block on GPU work.

use std::panic::AssertUnwindSafe;
use std::thread::JoinHandle;
use std::time::Instant;

use tokio::sync::{mpsc, oneshot};

use super::{FrameRequest, RenderError, RenderedFrame, Renderer};

/// Requests waiting for the GPU. Small on purpose: sessions hold at most one request each in
/// flight, and a queue longer than that would only add latency.
const QUEUE_DEPTH: usize = 16;

enum Job {
    Render {
        request: FrameRequest,
        reply: oneshot::Sender<Result<Rendered, RenderError>>,
    },
    /// A stream (session) ended: free its targets and history.
    Release(u64),
}

/// A rendered frame plus when the render thread started on it (its wait ended).
#[derive(Debug)]
pub struct Rendered {
    pub frame: RenderedFrame,
    pub started: Instant,
}

/// Cloneable handle sessions use to get frames rendered.
#[derive(Clone)]
pub struct RenderHandle {
    tx: mpsc::Sender<Job>,
    adapter: String,
    solves: super::renderer::Solves,
}

impl RenderHandle {
    pub async fn render(&self, request: FrameRequest) -> Result<Rendered, RenderError> {
        let (reply, rx) = oneshot::channel();
        let job = Job::Render { request, reply };
        self.tx
            .send(job)
            .await
            .map_err(|_| RenderError::ThreadGone)?;
        rx.await.map_err(|_| RenderError::ThreadGone)?
    }

    /// Frees what the renderer keeps for `stream`. Never blocks: if the queue is full the
    /// targets simply age out of the renderer's cache instead.
    pub fn release(&self, stream: u64) {
        let _ = self.tx.try_send(Job::Release(stream));
    }

    /// The radiosity solves of the scenes loaded so far.
    pub fn solves(&self) -> Vec<crate::radiosity::RadiosityHandle> {
        self.solves.lock().map(|s| s.clone()).unwrap_or_default()
    }

    /// The adapter's one-line description.
    pub fn adapter(&self) -> &str {
        &self.adapter
    }
}

pub struct RenderThread;

impl RenderThread {
    /// Moves `renderer` onto a new thread. The thread ends when every handle is dropped.
    pub fn spawn(renderer: Renderer) -> std::io::Result<(RenderHandle, JoinHandle<()>)> {
        let adapter = renderer.adapter();
        let solves = renderer.solves();
        let (tx, rx) = mpsc::channel(QUEUE_DEPTH);
        let join = std::thread::Builder::new()
            .name("fovea-render".into())
            .spawn(move || run(renderer, rx))?;
        Ok((
            RenderHandle {
                tx,
                adapter,
                solves,
            },
            join,
        ))
    }
}

fn run(mut renderer: Renderer, mut rx: mpsc::Receiver<Job>) {
    while let Some(job) = rx.blocking_recv() {
        let (request, reply) = match job {
            Job::Render { request, reply } => (request, reply),
            Job::Release(stream) => {
                renderer.release_stream(stream);
                continue;
            }
        };
        let started = Instant::now();
        let span = tracing::debug_span!("render", w = request.width, h = request.height);
        let _enter = span.enter();
        // A panic inside the driver stack must not take every session down with it.
        let result = std::panic::catch_unwind(AssertUnwindSafe(|| renderer.render(&request)))
            .unwrap_or_else(|panic| {
                let what = panic
                    .downcast_ref::<String>()
                    .cloned()
                    .or_else(|| panic.downcast_ref::<&str>().map(|s| s.to_string()))
                    .unwrap_or_else(|| "unknown panic".into());
                tracing::error!("render panicked: {what}");
                Err(RenderError::Gpu(format!("renderer panicked: {what}")))
            });
        // The session may have gone away meanwhile; then nobody wants the frame.
        let _ = reply.send(result.map(|frame| Rendered { frame, started }));
    }
    tracing::debug!("render thread stopping: no more handles");
}
