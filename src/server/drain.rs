//! Draining: how an instance leaves a fleet without dropping anyone. When a drain is asked for
//! (SIGTERM, `POST /admin/drain`), `/readyz` answers 503 at once and `/ws` refuses new sessions
//! with 503, so the balancer sends newcomers elsewhere; every open session is sent `goodbye`
//! (reason `draining`, with a retry delay) and keeps its frames until its client has opened a
//! session elsewhere and left. Sessions still open when the grace period ends are closed with
//! 1001; their recordings are finished (flushed, synced, renamed) on the way out either way.

use std::sync::Arc;
use std::time::Duration;

use tokio_util::sync::CancellationToken;

use super::ServerState;
use crate::protocol::Goodbye;

/// After the grace period: how long the 1001 close frames (and an idle proxy connection) get
/// before the server returns anyway, so a drain is bounded whatever clients do.
pub const CLOSE_WAIT: Duration = Duration::from_secs(2);

/// Longest delay, ms, a goodbye asks a client to wait before reconnecting.
const MAX_RETRY_MS: u64 = 500;

/// Waits for a drain request, drains, and cancels `stopped` when the server may stop serving.
pub async fn run(state: Arc<ServerState>, stopped: CancellationToken) {
    state.drain_request.cancelled().await;
    let grace = state.drain_grace;
    let open = state.sessions.len();
    tracing::info!(
        sessions = open,
        grace_s = grace.as_secs_f64(),
        "draining: not ready, no new sessions, goodbye sent to every session"
    );
    ::metrics::gauge!("fovea_draining").set(1.0);
    state.sessions.close();
    if tokio::time::timeout(grace, state.sessions.wait())
        .await
        .is_ok()
    {
        tracing::info!("drained: every session has left");
    } else {
        tracing::info!(
            sessions = state.sessions.len(),
            "grace period over: closing the remaining sessions (1001)"
        );
        state.closing.cancel();
        if tokio::time::timeout(CLOSE_WAIT, state.sessions.wait())
            .await
            .is_err()
        {
            tracing::warn!("some sessions did not close within {CLOSE_WAIT:?}");
        }
    }
    state.closing.cancel();
    stopped.cancel();
}

/// The goodbye for session `id`: retry delays spread over [0, MAX_RETRY_MS] (or a quarter of a
/// short grace period) so a fleet is not asked to take every session in the same instant.
pub fn goodbye(id: u64, grace: Duration) -> Goodbye {
    let spread = MAX_RETRY_MS.min(grace.as_millis() as u64 / 4);
    // A multiplicative hash: consecutive ids land far apart in the window.
    let retry_ms = id.wrapping_mul(0x9E37_79B9_7F4A_7C15) >> 32;
    Goodbye {
        reason: "draining".into(),
        retry_ms: if spread == 0 {
            0
        } else {
            retry_ms % (spread + 1)
        },
        closes_in_ms: grace.as_millis() as u64,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn retry_delays_stay_within_the_window_and_spread_out() {
        let grace = Duration::from_secs(10);
        let delays: Vec<u64> = (1..=64).map(|id| goodbye(id, grace).retry_ms).collect();
        // The asked-for delays are numbers the function computes, not times measured.
        assert!(delays.iter().all(|&d| d <= MAX_RETRY_MS));
        let mut distinct = delays.clone();
        distinct.sort_unstable();
        distinct.dedup();
        assert!(distinct.len() > 48, "{delays:?}");
        assert!((1..=8).all(|id| goodbye(id, Duration::from_millis(100)).retry_ms <= 25));
        assert_eq!(goodbye(3, Duration::ZERO).retry_ms, 0);
    }
}
