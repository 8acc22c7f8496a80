//! Admission by cost: a session's frames must fit the per-frame budget at the current load.
//! The render thread shares its time fairly, so with N sessions rendering, each of this
//! session's frames takes about N times its own render time; a `hello` (or a settings change)
//! whose estimate × N passes the budget is refused with the figures and the largest size that
//! would fit, and the session stays as it was.

use super::ServerState;
use crate::protocol::{ErrorCode, ProtocolError};
use crate::render::FrameRequest;

/// Refuses `request` (the session's next frame as it would be) when it would not fit.
pub fn check(
    state: &ServerState,
    request: &FrameRequest,
    preset: &str,
) -> Result<(), ProtocolError> {
    let Some(ms) = state.render.estimate_ms(request) else {
        // Nothing of its kind rendered yet: the first frame teaches the estimate.
        return Ok(());
    };
    let budget = state.limits.frame_budget_ms;
    let sessions = state
        .max_sessions
        .saturating_sub(state.slots.available_permits())
        .max(1);
    let shared = ms * sessions as f64;
    if shared <= budget {
        return Ok(());
    }
    let (w, h) = (request.width, request.height);
    let advice = match largest_fit(state, request, budget / sessions as f64) {
        Some((fw, fh)) => format!("Ask for at most {fw}x{fh} or a faster preset"),
        None => "No size fits at this load: try a faster preset or later".into(),
    };
    Err(ProtocolError::new(
        ErrorCode::OverBudget,
        format!(
            "a {w}x{h} frame at preset {preset} is estimated at {} on this adapter; with \
             {sessions} session(s) sharing it that is {} a frame, over the per-frame budget of \
             {} (serve --frame-budget-s). {advice}",
            duration(ms),
            duration(shared),
            duration(budget),
        ),
    ))
}

/// A duration for the message: milliseconds under a second (a GPU server's budget may be
/// 16 ms, which whole tenths of a second would print as 0.0 s), else seconds. The switch is
/// where milliseconds would round to 1000.
fn duration(ms: f64) -> String {
    if ms < 999.5 {
        format!("{ms:.0} ms")
    } else {
        format!("{:.1} s", ms / 1e3)
    }
}

/// The largest frame of `request`'s shape whose estimate is within `ms` (bisection on the
/// scale; estimates grow with size), or `None` when not even an 8-pixel-high one is.
fn largest_fit(state: &ServerState, request: &FrameRequest, ms: f64) -> Option<(u32, u32)> {
    let sized = |scale: f64| {
        let side = |s: u32| ((f64::from(s) * scale).floor() as u32).max(1);
        FrameRequest {
            width: side(request.width),
            height: side(request.height),
            ..request.clone()
        }
    };
    let fits = |scale: f64| {
        state
            .render
            .estimate_ms(&sized(scale))
            .is_some_and(|e| e <= ms)
    };
    let smallest = 8.0 / f64::from(request.height.max(1));
    if !fits(smallest) {
        return None;
    }
    let (mut lo, mut hi) = (smallest, 1.0);
    for _ in 0..24 {
        let mid = 0.5 * (lo + hi);
        if fits(mid) {
            lo = mid;
        } else {
            hi = mid;
        }
    }
    let r = sized(lo);
    Some((r.width, r.height))
}

#[cfg(test)]
mod tests {
    use super::duration;

    /// A budget of a few milliseconds reads as such, not as "0.0 s".
    #[test]
    fn durations_read_in_milliseconds_under_a_second() {
        assert_eq!(duration(16.0), "16 ms");
        assert_eq!(duration(98.6), "99 ms");
        assert_eq!(duration(999.4), "999 ms");
        assert_eq!(duration(999.6), "1.0 s", "not \"1000 ms\"");
        assert_eq!(duration(1000.0), "1.0 s");
        assert_eq!(duration(10_000.0), "10.0 s");
    }
}
