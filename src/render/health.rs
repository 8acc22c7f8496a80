//! Whether the renderer works, as `/readyz` reports it, and what the render thread does when it
//! does not: after [`FAILURES_BEFORE_RESTART`] frames in a row fail on the GPU (not for a bad
//! request), or as soon as the device is lost, the thread drops the renderer and opens a new
//! one; sessions get one error for the frames lost and go on. Until a frame renders again the
//! renderer counts as failing, so load balancers send new viewers elsewhere.

use std::sync::{Arc, Mutex};
use std::time::{Duration, Instant};

use super::{RenderError, Renderer};

/// GPU failures in a row that restart the renderer.
pub const FAILURES_BEFORE_RESTART: u32 = 3;
/// Least time between two attempts to open a new device when opening fails.
const RETRY_OPEN: Duration = Duration::from_secs(5);

#[derive(Debug, Default)]
struct State {
    in_a_row: u32,
    failing: Option<String>,
    restarts: u64,
    last_attempt: Option<Instant>,
}

/// Shared between the render thread (which reports) and the server (which asks).
#[derive(Debug, Clone, Default)]
pub struct Health(Arc<Mutex<State>>);

/// Whether an error says the GPU (rather than the request) is at fault.
pub fn gpu_fault(e: &RenderError) -> bool {
    matches!(
        e,
        RenderError::Gpu(_) | RenderError::Readback(_) | RenderError::Graph(_)
    )
}

impl Health {
    /// Why the renderer is failing, if it is.
    pub fn failing(&self) -> Option<String> {
        self.0.lock().ok().and_then(|s| s.failing.clone())
    }

    /// How many times the renderer has been replaced.
    pub fn restarts(&self) -> u64 {
        self.0.lock().map(|s| s.restarts).unwrap_or(0)
    }

    pub(super) fn frame_ok(&self) {
        if let Ok(mut s) = self.0.lock() {
            s.in_a_row = 0;
            s.failing = None;
        }
    }

    /// Notes a failed frame; true when the renderer should be replaced now.
    pub(super) fn frame_failed(&self, e: &RenderError, lost: bool) -> bool {
        let Ok(mut s) = self.0.lock() else {
            return false;
        };
        if !(gpu_fault(e) || lost) {
            return false;
        }
        s.in_a_row += 1;
        if lost || s.in_a_row >= FAILURES_BEFORE_RESTART {
            s.failing = Some(format!("{} frames failed in a row: {e}", s.in_a_row));
            let due = s.last_attempt.is_none_or(|t| t.elapsed() >= RETRY_OPEN);
            return due;
        }
        false
    }

    /// Opens a new renderer like `old` (same scene catalog and radiosity list); on failure the
    /// old one stays and the renderer keeps counting as failing.
    pub(super) fn restart(&self, old: &Renderer) -> Option<Renderer> {
        if let Ok(mut s) = self.0.lock() {
            s.last_attempt = Some(Instant::now());
        }
        match Renderer::new() {
            Ok(mut fresh) => {
                fresh.set_catalog(old.catalog.clone());
                fresh.share_solves(old.solves());
                if let Ok(mut s) = self.0.lock() {
                    s.restarts += 1;
                    s.in_a_row = 0;
                }
                ::metrics::counter!("fovea_renderer_restarts_total").increment(1);
                tracing::warn!("renderer restarted on {}", fresh.adapter());
                Some(fresh)
            }
            Err(e) => {
                tracing::error!("the renderer could not be restarted: {e}");
                if let Ok(mut s) = self.0.lock() {
                    s.failing = Some(format!("the renderer could not be restarted: {e}"));
                }
                None
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn only_gpu_faults_in_a_row_call_for_a_restart() {
        let h = Health::default();
        let size = RenderError::Size {
            width: 0,
            height: 1,
            max: 8192,
        };
        for _ in 0..10 {
            assert!(!h.frame_failed(&size, false));
        }
        assert_eq!(h.failing(), None);
        let gpu = RenderError::Gpu("out of memory".into());
        assert!(!h.frame_failed(&gpu, false));
        assert!(!h.frame_failed(&gpu, false));
        h.frame_ok();
        assert!(!h.frame_failed(&gpu, false));
        assert!(!h.frame_failed(&gpu, false));
        assert!(h.frame_failed(&gpu, false));
        assert!(h.failing().is_some_and(|r| r.contains("out of memory")));
        h.frame_ok();
        assert_eq!(h.failing(), None);
        // A lost device restarts at once, whatever the error said.
        assert!(h.frame_failed(&RenderError::ThreadGone, true));
    }
}
