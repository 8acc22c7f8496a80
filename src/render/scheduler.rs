//! The render thread's loop. It takes every request that has arrived into its own list, drops
//! those nobody waits for any more, and runs one piece of work at a time: a whole frame, or one
//! part of a frame expected to take longer than [`SLICE_MS`] (see `sliced.rs`). Which piece
//! runs next is the fair choice of [`Turns`]: the stream that has had the least render time.

use std::panic::AssertUnwindSafe;
use std::time::Instant;

use tokio::sync::{mpsc, oneshot};

use super::cost::CostModel;
use super::foveation_policy::FoveationPolicy;
use super::health::Health;
use super::sliced::{FrameInFlight, Progress};
use super::thread::{Job, Rendered};
use super::turns::Turns;
use super::{FrameRequest, RenderError, Renderer};

/// Longest piece of work other sessions wait behind: frames expected to take longer are split
/// into parts of about this length (announced in `welcome.limits`).
pub const SLICE_MS: f64 = 100.0;

/// Pixels per part for a full-shading frame of a kind never rendered before: about a slice of
/// the reference rung on a software adapter.
const UNKNOWN_COST_PIXELS: u32 = 32 * 1024;

struct Task {
    request: FrameRequest,
    reply: oneshot::Sender<Result<Rendered, RenderError>>,
    seq: u64,
    /// Why its foveated request is being shaded whole, if it is.
    unfoveated: Option<String>,
    /// Set once its first part has run.
    going: Option<Going>,
}

struct Going {
    frame: Box<FrameInFlight>,
    started: Instant,
    spent_ms: f64,
}

pub struct Scheduler {
    renderer: Renderer,
    cost: CostModel,
    turns: Turns,
    tasks: Vec<Task>,
    arrivals: u64,
    health: Health,
    /// (stream, scene, width, height, foveated) that have rendered a frame: a stream's first
    /// frame of a kind at a size makes its targets and may compile pipelines or build the
    /// scene's maps, seconds on a cold software driver, so it teaches the cost model nothing
    /// about the next ones.
    warm: std::collections::HashSet<(u64, String, u32, u32, bool)>,
    foveation: FoveationPolicy,
}

impl Scheduler {
    pub fn new(renderer: Renderer, cost: CostModel, health: Health) -> Scheduler {
        Scheduler {
            renderer,
            cost,
            turns: Turns::default(),
            tasks: Vec::new(),
            arrivals: 0,
            health,
            warm: Default::default(),
            foveation: FoveationPolicy::default(),
        }
    }

    pub fn run(mut self, mut rx: mpsc::Receiver<Job>) {
        loop {
            // Sleep only with nothing to do; otherwise take what has come and go on.
            if self.tasks.is_empty() {
                match rx.blocking_recv() {
                    Some(job) => self.take(job),
                    None => break,
                }
            }
            while let Ok(job) = rx.try_recv() {
                self.take(job);
            }
            self.drop_unwanted();
            if let Some(i) = self.pick() {
                self.run_piece(i);
            }
        }
        tracing::debug!("render thread stopping: no more handles");
    }

    fn take(&mut self, job: Job) {
        match job {
            Job::Render { mut request, reply } => {
                self.arrivals += 1;
                self.turns.arrive(request.stream);
                let unfoveated = self.foveation.apply(&self.cost, &mut request);
                self.tasks.push(Task {
                    request,
                    reply,
                    seq: self.arrivals,
                    unfoveated,
                    going: None,
                });
            }
            Job::Release(stream) => {
                self.turns.forget(stream);
                self.foveation.forget(stream);
                self.warm.retain(|k| k.0 != stream);
                let before = self.tasks.len();
                self.tasks.retain(|t| t.request.stream != stream);
                let dropped = (before - self.tasks.len()) as u64;
                ::metrics::counter!("fovea_frames_abandoned_total").increment(dropped);
                // Its frame in flight, if any, is unpinned along with its targets.
                self.renderer.release_stream(stream);
            }
            Job::LoseDevice => self.renderer.lose_device(),
        }
    }

    /// Work only for the living: a session that ended has dropped its receiver, and nobody
    /// would see the frame.
    fn drop_unwanted(&mut self) {
        let mut i = 0;
        while i < self.tasks.len() {
            if !self.tasks[i].reply.is_closed() {
                i += 1;
                continue;
            }
            let task = self.tasks.remove(i);
            ::metrics::counter!("fovea_frames_abandoned_total").increment(1);
            tracing::debug!(
                stream = task.request.stream,
                "dropping the frame of a session that has gone"
            );
            if let Some(g) = task.going {
                self.renderer.abandon(*g.frame);
            }
        }
    }

    /// The next task to run a piece of: frames in flight always may; a waiting frame may not
    /// start while it would rebuild what a frame in flight of its scene reads.
    fn pick(&mut self) -> Option<usize> {
        let eligible: Vec<usize> = (0..self.tasks.len())
            .filter(|&i| {
                let t = &self.tasks[i];
                t.going.is_some()
                    || !self.tasks.iter().any(|o| {
                        o.going
                            .as_ref()
                            .is_some_and(|g| self.renderer.conflicts(&t.request, &g.frame))
                    })
            })
            .collect();
        let keys: Vec<(u64, u64)> = eligible
            .iter()
            .map(|&i| (self.tasks[i].request.stream, self.tasks[i].seq))
            .collect();
        self.turns.pick(&keys).map(|k| eligible[k])
    }

    /// How many parts `request` is split into: enough that each is about `SLICE_MS`. A
    /// foveated frame is split only while other streams share the renderer: its parts cannot
    /// be shorter than its fixed passes (G-buffer and sampling, reconstruction), and alone the
    /// parts would only add submissions.
    fn slices(&self, request: &FrameRequest) -> u32 {
        if request.settings.foveation.enabled && self.turns.streams() <= 1 {
            return 1;
        }
        match self.cost.estimate_ms(request) {
            Some(ms) => (ms / SLICE_MS).ceil().clamp(1.0, 1024.0) as u32,
            None => {
                let rows = (UNKNOWN_COST_PIXELS / request.width.max(1)).max(8);
                request.height.div_ceil(rows)
            }
        }
    }

    fn run_piece(&mut self, i: usize) {
        let begun = Instant::now();
        let slices = self.slices(&self.tasks[i].request);
        let task = &mut self.tasks[i];
        let stream = task.request.stream;
        let span = tracing::debug_span!(
            "render",
            stream,
            w = task.request.width,
            h = task.request.height
        );
        let _enter = span.enter();
        let cold = task.going.is_none() && !self.warm.contains(&kind(&task.request));
        let renderer = &mut self.renderer;
        let outcome = match task.going.as_mut() {
            None => guarded(|| renderer.begin(&task.request, slices)).map(|p| match p {
                Progress::Done(frame) => Some(frame),
                Progress::Going(frame) => {
                    task.going = Some(Going {
                        frame,
                        started: begun,
                        spent_ms: 0.0,
                    });
                    None
                }
            }),
            Some(g) => guarded(|| renderer.step(&mut g.frame)),
        };
        let ms = begun.elapsed().as_secs_f64() * 1e3;
        if cold {
            self.turns.charge_cold(stream, ms);
        } else {
            self.turns.charge(stream, ms);
        }
        let task = &mut self.tasks[i];
        if let Some(g) = task.going.as_mut() {
            g.spent_ms += ms;
        }
        if matches!(outcome, Ok(None)) {
            return;
        }
        let task = self.tasks.remove(i);
        let (started, spent) = task
            .going
            .as_ref()
            .map_or((begun, ms), |g| (g.started, g.spent_ms));
        let mut restart = false;
        let result = match outcome {
            Ok(Some(mut frame)) => {
                if !self.warm.insert(kind(&task.request)) {
                    self.cost.record(&task.request, spent);
                }
                frame.unfoveated = task.unfoveated.clone();
                self.health.frame_ok();
                Ok(Rendered { frame, started })
            }
            Ok(None) => return,
            Err(e) => {
                if let Some(g) = task.going {
                    self.renderer.abandon(*g.frame);
                }
                restart = self.health.frame_failed(&e, self.renderer.is_lost());
                Err(e)
            }
        };
        // The session may have gone away meanwhile; then nobody wants the frame.
        let _ = task.reply.send(result);
        if restart {
            self.restart();
        }
    }

    /// Replaces a renderer that keeps failing (or lost its device). Frames in flight on the
    /// old one are lost and their sessions told; waiting frames render on the new one.
    fn restart(&mut self) {
        let Some(fresh) = self.health.restart(&self.renderer) else {
            return;
        };
        self.renderer = fresh;
        let mut i = 0;
        while i < self.tasks.len() {
            if self.tasks[i].going.is_none() {
                i += 1;
                continue;
            }
            let task = self.tasks.remove(i);
            let lost = RenderError::Gpu("the renderer restarted; this frame was lost".into());
            let _ = task.reply.send(Err(lost));
        }
    }
}

/// What makes a frame cold when a stream renders it for the first time (see `Scheduler::warm`).
fn kind(r: &FrameRequest) -> (u64, String, u32, u32, bool) {
    let foveated = r.settings.foveation.enabled;
    (r.stream, r.scene.clone(), r.width, r.height, foveated)
}

/// A panic inside the driver stack must not take every session down with it.
fn guarded<T>(f: impl FnOnce() -> Result<T, RenderError>) -> Result<T, RenderError> {
    std::panic::catch_unwind(AssertUnwindSafe(f)).unwrap_or_else(|panic| {
        let what = panic
            .downcast_ref::<String>()
            .cloned()
            .or_else(|| panic.downcast_ref::<&str>().map(|s| s.to_string()))
            .unwrap_or_else(|| "unknown panic".into());
        tracing::error!("render panicked: {what}");
        Err(RenderError::Gpu(format!("renderer panicked: {what}")))
    })
}
