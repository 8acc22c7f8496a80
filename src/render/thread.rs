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

    /// Frees what the renderer keeps for `stream` (its targets can be a gigabyte at 4K). Never
    /// blocks the caller and is never lost: when the queue is full, a task waits for room.
    pub fn release(&self, stream: u64) {
        if let Err(mpsc::error::TrySendError::Full(job)) = self.tx.try_send(Job::Release(stream)) {
            let tx = self.tx.clone();
            match tokio::runtime::Handle::try_current() {
                Ok(rt) => {
                    rt.spawn(async move { tx.send(job).await });
                }
                Err(_) => {
                    let _ = tx.blocking_send(job);
                }
            }
        }
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
        // Work only for the living: a session that ended while its job waited has dropped the
        // receiver, and nobody would see the frame.
        if reply.is_closed() {
            ::metrics::counter!("fovea_frames_abandoned_total").increment(1);
            tracing::debug!(
                stream = request.stream,
                "skipping the frame of a session that has gone"
            );
            continue;
        }
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
