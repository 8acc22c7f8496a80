use std::sync::Arc;

use axum::extract::ws::{CloseFrame, Message, WebSocketUpgrade};
use axum::extract::{Query, State};
use axum::http::{header, HeaderMap, StatusCode, Uri};
use axum::response::{IntoResponse, Response};
use axum::routing::{get, post};
use axum::Router;

use super::{assets, session, ServerState, HARD_MESSAGE_LIMIT};

pub fn router(state: Arc<ServerState>) -> Router {
    Router::new()
        .route("/ws", get(websocket))
        .route("/healthz", get(|| async { "ok\n" }))
        .route("/readyz", get(readyz))
        .route("/metrics", get(metrics_text))
        .route("/admin/drain", post(admin_drain))
        .route("/recordings/{id}", get(super::recordings::download))
        .fallback(get(static_file))
        .with_state(state)
}

/// Ready while a session slot is free and no drain has begun: load balancers send new viewers
/// elsewhere otherwise. Radiosity solves still refining are listed but do not make the server
/// unready: sessions start on the preview and see it improve.
async fn readyz(State(state): State<Arc<ServerState>>) -> Response {
    if state.drain_request.is_cancelled() {
        return (StatusCode::SERVICE_UNAVAILABLE, "draining\n").into_response();
    }
    if let Some(reason) = state.render.failing() {
        return (
            StatusCode::SERVICE_UNAVAILABLE,
            format!("renderer failing: {reason}\n"),
        )
            .into_response();
    }
    if state.slots.available_permits() > 0 {
        let mut body = String::from("ready\n");
        for solve in state.render.solves() {
            if let Some(p) = solve.latest().map(|s| s.progress()) {
                body.push_str(&format!(
                    "radiosity {}: {} ({} shots, {:.2}% of the emitted power unshot)\n",
                    solve.scene(),
                    if p.converged { "converged" } else { "refining" },
                    p.shots,
                    100.0 * p.unshot
                ));
            }
        }
        (StatusCode::OK, body).into_response()
    } else {
        (
            StatusCode::SERVICE_UNAVAILABLE,
            format!("at capacity: {} sessions\n", state.max_sessions),
        )
            .into_response()
    }
}

/// Starts a drain, as SIGTERM does; answers at once (the drain runs on).
async fn admin_drain(State(state): State<Arc<ServerState>>, headers: HeaderMap) -> Response {
    if let Err(refusal) = state.access.admit_admin(&headers) {
        return refusal.into_response();
    }
    let already = state.drain_request.is_cancelled();
    state.drain_request.cancel();
    let grace = state.drain_grace.as_secs_f64();
    let body = if already {
        "already draining\n".to_string()
    } else {
        tracing::info!("drain asked for over /admin/drain");
        format!("draining: sessions have {grace} s to move, then the server exits\n")
    };
    (StatusCode::ACCEPTED, body).into_response()
}

async fn metrics_text(State(state): State<Arc<ServerState>>, headers: HeaderMap) -> Response {
    if let Err(refusal) = state.access.admit_metrics(&headers) {
        return refusal.into_response();
    }
    match super::metrics::handle() {
        Some(h) => (
            [(header::CONTENT_TYPE, "text/plain; version=0.0.4")],
            h.render(),
        )
            .into_response(),
        None => (
            StatusCode::SERVICE_UNAVAILABLE,
            "metrics are unavailable in this process\n",
        )
            .into_response(),
    }
}

#[derive(serde::Deserialize)]
struct WsQuery {
    token: Option<String>,
}

async fn websocket(
    State(state): State<Arc<ServerState>>,
    headers: HeaderMap,
    Query(query): Query<WsQuery>,
    ws: WebSocketUpgrade,
) -> Response {
    // Before the upgrade: a refused client never holds a slot or a socket task.
    if let Err(refusal) = state.access.admit_session(&headers, query.token.as_deref()) {
        ::metrics::counter!("fovea_sessions_unauthorised_total").increment(1);
        return refusal.into_response();
    }
    if state.drain_request.is_cancelled() {
        // A balancer that retries on 503 (nginx's proxy_next_upstream http_503) sends the
        // client to another instance within the same request.
        return (
            StatusCode::SERVICE_UNAVAILABLE,
            [(header::RETRY_AFTER, "1")],
            "draining: this instance takes no new sessions; reconnect (another instance will)\n",
        )
            .into_response();
    }
    let permit = state.slots.clone().try_acquire_owned().ok();
    let token = state.sessions.token();
    let ws = ws
        .max_message_size(HARD_MESSAGE_LIMIT)
        .max_frame_size(HARD_MESSAGE_LIMIT);
    let Some(permit) = permit else {
        // Refused politely over the socket, so browsers see the reason: 1013 "try again later".
        ::metrics::counter!("fovea_sessions_refused_total").increment(1);
        let max = state.max_sessions;
        return ws.on_upgrade(move |mut socket| async move {
            let reason = format!("server at capacity ({max} sessions); try again later");
            let _ = socket
                .send(Message::Close(Some(CloseFrame {
                    code: 1013,
                    reason: reason.into(),
                })))
                .await;
            drop(token);
        });
    };
    let id = state
        .next_session
        .fetch_add(1, std::sync::atomic::Ordering::Relaxed);
    ws.on_upgrade(move |socket| async move {
        ::metrics::gauge!("fovea_sessions_active").increment(1.0);
        ::metrics::counter!("fovea_sessions_total").increment(1);
        // Every line the session logs, its frames' included, carries its id.
        let span = tracing::info_span!("session", id);
        tracing::Instrument::instrument(session::run(socket, state, id), span).await;
        ::metrics::gauge!("fovea_sessions_active").decrement(1.0);
        drop(permit);
        drop(token);
    })
}

async fn static_file(uri: Uri) -> Response {
    match assets::find(uri.path()) {
        Some((mime, body)) => (
            [
                (header::CONTENT_TYPE, mime),
                (header::CACHE_CONTROL, "no-cache"),
            ],
            body,
        )
            .into_response(),
        None => (
            StatusCode::NOT_FOUND,
            format!("no such page: {}\n", uri.path()),
        )
            .into_response(),
    }
}
