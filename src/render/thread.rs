//! The render thread: the only place that touches the GPU. Sessions send it requests over a
//! bounded channel and await the reply, so async tasks never block on GPU work.

use std::thread::JoinHandle;
use std::time::Instant;

use tokio::sync::{mpsc, oneshot};

use super::cost::CostModel;
use super::health::Health;
use super::scheduler::Scheduler;
use super::{FrameRequest, RenderError, RenderedFrame, Renderer};

/// Requests on their way to the render thread, which takes them all into its own list of
/// waiting frames and chooses among them (`scheduler.rs`).
const QUEUE_DEPTH: usize = 16;

pub(super) enum Job {
    Render {
        request: FrameRequest,
        reply: oneshot::Sender<Result<Rendered, RenderError>>,
    },
    /// A stream (session) ended: free its targets and history.
    Release(u64),
    /// Destroy the device, as a driver reset would (tests of the restart).
    LoseDevice,
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
    cost: CostModel,
    health: Health,
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

    /// Expected render milliseconds of `request` on this adapter, once a frame of its kind has
    /// been rendered (or calibrated).
    pub fn estimate_ms(&self, request: &FrameRequest) -> Option<f64> {
        self.cost.estimate_ms(request)
    }

    /// Why the renderer is failing (frames failing on the GPU, a restart that did not work),
    /// if it is: `/readyz` answers 503 meanwhile.
    pub fn failing(&self) -> Option<String> {
        self.health.failing()
    }

    /// How many times the render thread has replaced its renderer.
    pub fn restarts(&self) -> u64 {
        self.health.restarts()
    }

    /// Destroys the GPU device as a driver reset would; the render thread then opens a new one.
    #[doc(hidden)]
    pub async fn lose_device(&self) -> Result<(), RenderError> {
        self.tx
            .send(Job::LoseDevice)
            .await
            .map_err(|_| RenderError::ThreadGone)
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
        RenderThread::spawn_with(renderer, CostModel::default())
    }

    /// The same, with frame costs already learnt (see [`super::cost::calibrate`]).
    pub fn spawn_with(
        renderer: Renderer,
        cost: CostModel,
    ) -> std::io::Result<(RenderHandle, JoinHandle<()>)> {
        let adapter = renderer.adapter();
        let solves = renderer.solves();
        let (tx, rx) = mpsc::channel(QUEUE_DEPTH);
        let model = cost.clone();
        let health = Health::default();
        let reports = health.clone();
        let join = std::thread::Builder::new()
            .name("fovea-render".into())
            .spawn(move || Scheduler::new(renderer, model, reports).run(rx))?;
        Ok((
            RenderHandle {
                tx,
                adapter,
                solves,
                cost,
                health,
            },
            join,
        ))
    }
}
