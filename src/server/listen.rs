//! The accept loop. `axum::serve` gives no deadline on a connection's request headers and no cap
//! on connections, so a client that opens sockets and never finishes a request (or an upgrade)
//! could hold file descriptors until the process runs out. Here every HTTP connection has a
//! header deadline (which also ends idle keep-alive connections) and a permit from a fixed pool:
//! at the cap the loop stops accepting and the kernel's backlog holds newcomers until a permit
//! comes back. A WebSocket gives its permit back once upgraded: sessions are counted by their
//! own slots.

use std::sync::Arc;
use std::time::Duration;

use axum::Router;
use hyper_util::rt::{TokioIo, TokioTimer};
use hyper_util::service::TowerToHyperService;
use tokio::net::TcpListener;
use tokio::sync::Semaphore;
use tokio_util::sync::CancellationToken;
use tokio_util::task::TaskTracker;

/// Limits on HTTP connections that have not (yet) become sessions.
#[derive(Debug, Clone, Copy)]
pub struct ConnectionLimits {
    /// A request's headers (the upgrade's included) must arrive within this; an idle
    /// keep-alive connection is closed after it too.
    pub header_timeout: Duration,
    /// HTTP connections open at once, not counting upgraded WebSockets.
    pub max_pending: usize,
}

impl Default for ConnectionLimits {
    fn default() -> Self {
        ConnectionLimits {
            header_timeout: Duration::from_secs(10),
            max_pending: 256,
        }
    }
}

/// Serves `app` on `listener` until `stop` is cancelled, then asks every open connection to
/// finish and returns once they have or `close_wait` passes.
pub async fn serve(
    listener: TcpListener,
    app: Router,
    limits: ConnectionLimits,
    stop: CancellationToken,
    close_wait: Duration,
) -> std::io::Result<()> {
    let permits = Arc::new(Semaphore::new(limits.max_pending.max(1)));
    let connections = TaskTracker::new();
    loop {
        let permit = tokio::select! {
            _ = stop.cancelled() => break,
            p = permits.clone().acquire_owned() => p.map_err(std::io::Error::other)?,
        };
        let (tcp, peer) = tokio::select! {
            _ = stop.cancelled() => break,
            accepted = listener.accept() => match accepted {
                Ok(a) => a,
                Err(e) => {
                    // Out of descriptors, or a connection reset before accept: wait a moment
                    // rather than spinning, and keep serving.
                    tracing::warn!("accept failed: {e}");
                    tokio::time::sleep(Duration::from_millis(50)).await;
                    continue;
                }
            },
        };
        // Frames and gaze samples are small and latency-bound: Nagle's algorithm would hold
        // them back for tens of milliseconds waiting for delayed ACKs.
        if let Err(e) = tcp.set_nodelay(true) {
            tracing::warn!("cannot set TCP_NODELAY: {e}");
        }
        ::metrics::gauge!("fovea_http_connections_pending").increment(1.0);
        let service = TowerToHyperService::new(app.clone());
        let stop = stop.clone();
        connections.spawn(async move {
            let mut http = hyper::server::conn::http1::Builder::new();
            http.timer(TokioTimer::new())
                .header_read_timeout(limits.header_timeout);
            let conn = http
                .serve_connection(TokioIo::new(tcp), service)
                .with_upgrades();
            tokio::pin!(conn);
            let result = tokio::select! {
                r = conn.as_mut() => r,
                _ = stop.cancelled() => {
                    conn.as_mut().graceful_shutdown();
                    conn.await
                }
            };
            if let Err(e) = result {
                if e.is_timeout() {
                    ::metrics::counter!("fovea_http_header_timeouts_total").increment(1);
                }
                tracing::debug!(%peer, "connection ended: {e}");
            }
            ::metrics::gauge!("fovea_http_connections_pending").decrement(1.0);
            drop(permit);
        });
    }
    connections.close();
    // An idle keep-alive connection (a proxy's pool) must not hold the exit past the drain.
    if tokio::time::timeout(close_wait, connections.wait())
        .await
        .is_err()
    {
        tracing::debug!("connections left open at exit");
    }
    Ok(())
}
