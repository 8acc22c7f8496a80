use std::sync::Arc;

use axum::extract::ws::WebSocketUpgrade;
use axum::extract::State;
use axum::http::{header, StatusCode, Uri};
use axum::response::{IntoResponse, Response};
use axum::routing::get;
use axum::Router;

use super::{assets, session, ServerState, HARD_MESSAGE_LIMIT};

pub fn router(state: Arc<ServerState>) -> Router {
    Router::new()
        .route("/ws", get(websocket))
        .route("/healthz", get(|| async { "ok\n" }))
        .fallback(get(static_file))
        .with_state(state)
}

async fn websocket(State(state): State<Arc<ServerState>>, ws: WebSocketUpgrade) -> Response {
    let id = state.next_session.fetch_add(1, std::sync::atomic::Ordering::Relaxed);
    let token = state.sessions.token();
    ws.max_message_size(HARD_MESSAGE_LIMIT)
        .max_frame_size(HARD_MESSAGE_LIMIT)
        .on_upgrade(move |socket| async move {
            session::run(socket, state, id).await;
            drop(token);
        })
}

async fn static_file(uri: Uri) -> Response {
    match assets::find(uri.path()) {
        Some((mime, body)) => (
            [(header::CONTENT_TYPE, mime), (header::CACHE_CONTROL, "no-cache")],
            body,
        )
            .into_response(),
        None => (StatusCode::NOT_FOUND, format!("no such page: {}\n", uri.path())).into_response(),
    }
}
