//! Downloading a session's own gaze recording: `GET /recordings/{id}?key=…` serves the file to
//! whoever holds the key that session's `welcome` carried, and to nobody else. The key is 128
//! random bits, compared in constant time; a wrong or missing key answers 404, like an unknown
//! session, so ids cannot be probed.

use std::collections::hash_map::RandomState;
use std::collections::HashMap;
use std::hash::BuildHasher;
use std::path::PathBuf;
use std::sync::{Arc, Mutex};

use axum::extract::{Path, Query, State};
use axum::http::{header, StatusCode};
use axum::response::{IntoResponse, Response};

use super::access::constant_time_eq;
use super::ServerState;

struct Entry {
    key: String,
    /// Written while the session lives, renamed to `done` when it ends.
    partial: PathBuf,
    done: PathBuf,
}

#[derive(Default)]
pub struct Recordings {
    entries: Mutex<HashMap<u64, Entry>>,
}

impl Recordings {
    /// Registers a session's recording; returns the URL its client may fetch it from.
    pub fn register(&self, session: u64, partial: PathBuf, done: PathBuf) -> String {
        let key = random_key();
        let url = format!("/recordings/{session}?key={key}");
        if let Ok(mut map) = self.entries.lock() {
            map.insert(session, Entry { key, partial, done });
        }
        url
    }

    /// The file to serve for `session` if `key` is its key.
    fn file(&self, session: u64, key: &str) -> Option<PathBuf> {
        let map = self.entries.lock().ok()?;
        let e = map.get(&session)?;
        if !constant_time_eq(e.key.as_bytes(), key.as_bytes()) {
            return None;
        }
        Some(if e.done.exists() {
            e.done.clone()
        } else {
            e.partial.clone()
        })
    }
}

/// 128 bits from two SipHash keys the standard library seeds from the OS.
fn random_key() -> String {
    let a = RandomState::new().hash_one(std::time::SystemTime::now());
    let b = RandomState::new().hash_one(std::process::id());
    format!("{a:016x}{b:016x}")
}

#[derive(serde::Deserialize)]
pub struct KeyQuery {
    #[serde(default)]
    key: String,
}

pub async fn download(
    State(state): State<Arc<ServerState>>,
    Path(session): Path<u64>,
    Query(q): Query<KeyQuery>,
) -> Response {
    let Some(path) = state.recordings.file(session, &q.key) else {
        return (StatusCode::NOT_FOUND, "no such recording\n").into_response();
    };
    match tokio::fs::read(&path).await {
        Ok(bytes) => (
            [
                (header::CONTENT_TYPE, "text/csv; charset=utf-8".to_string()),
                (
                    header::CONTENT_DISPOSITION,
                    format!("attachment; filename=\"fovea-session-{session}.csv\""),
                ),
            ],
            bytes,
        )
            .into_response(),
        Err(e) => (
            StatusCode::INTERNAL_SERVER_ERROR,
            format!("reading the recording: {e}\n"),
        )
            .into_response(),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn only_the_right_key_opens_a_recording() {
        let r = Recordings::default();
        let url = r.register(7, "a.partial".into(), "a.csv".into());
        let key = url.rsplit("key=").next().unwrap();
        assert_eq!(key.len(), 32);
        assert_eq!(r.file(7, key), Some(PathBuf::from("a.partial")));
        assert_eq!(r.file(7, "0".repeat(32).as_str()), None);
        assert_eq!(r.file(7, ""), None);
        assert_eq!(r.file(8, key), None, "a key opens its own session only");
        let other = r.register(8, "b.partial".into(), "b.csv".into());
        assert_ne!(other.rsplit("key=").next().unwrap(), key);
    }
}
