//! A session that outlives its server instance: what `fovea load` and `fovea replay` drive.
//! One task owns the socket: it sends the caller's messages, acknowledges every frame at once,
//! and hands frames to the caller. When the server says `goodbye` (it is draining) the link
//! waits the asked-for delay, leaves, and opens a new session at the same URL, where the
//! balancer sends it to another instance; a connection that drops, a 1001 close or a full
//! server (1013) is retried with backoff too. What a link went through is in `LinkStats`.

use std::time::{Duration, Instant};

use futures_util::{SinkExt, StreamExt};
use tokio::net::TcpStream;
use tokio::sync::mpsc;
use tokio_tungstenite::tungstenite::client::IntoClientRequest;
use tokio_tungstenite::tungstenite::Message;
use tokio_tungstenite::{MaybeTlsStream, WebSocketStream};
use tokio_util::sync::CancellationToken;

use super::ClientError;
use crate::protocol::{decode_frame, ErrorMessage, FrameHeader, Hello, ServerMessage, Welcome};

type Socket = WebSocketStream<MaybeTlsStream<TcpStream>>;

/// Reconnection gives up after this long without a session.
const GIVE_UP: Duration = Duration::from_secs(30);
const FIRST_BACKOFF: Duration = Duration::from_millis(100);
const MAX_BACKOFF: Duration = Duration::from_secs(2);

#[derive(Debug, Clone)]
pub struct LinkOptions {
    pub url: String,
    /// Sent as `Authorization: Bearer …`.
    pub token: Option<String>,
    pub hello: Hello,
    /// Reconnect after a goodbye or a lost connection (otherwise the link just ends).
    pub reconnect: bool,
}

/// What the link hands its caller.
#[derive(Debug)]
pub enum LinkEvent {
    /// `connection` counts sessions: 0 is the first, each reconnect adds one.
    Frame {
        header: FrameHeader,
        image: Vec<u8>,
        connection: u32,
    },
    Error(ErrorMessage),
}

/// What happened over the link's life.
#[derive(Debug, Default, Clone)]
pub struct LinkStats {
    pub reconnects: u32,
    /// From the last frame of a session to the first of the next, per reconnect.
    pub gaps_ms: Vec<f64>,
    /// Messages the caller sent while no session was up (not delivered).
    pub dropped: u64,
    /// Why the link ended before it was closed, if it did.
    pub ended: Option<String>,
}

pub struct Link {
    out: mpsc::UnboundedSender<String>,
    stop: CancellationToken,
    task: tokio::task::JoinHandle<LinkStats>,
}

impl Link {
    /// Opens the first session; its failure is the caller's error (nothing is retried yet).
    /// Frames and the rest come on the returned receiver, which ends when the link does.
    pub async fn open(
        opts: LinkOptions,
    ) -> Result<(Link, mpsc::UnboundedReceiver<LinkEvent>, Welcome), ClientError> {
        let (ws, welcome) = start(&opts).await?;
        let (out, out_rx) = mpsc::unbounded_channel();
        let (events_tx, events) = mpsc::unbounded_channel();
        let stop = CancellationToken::new();
        let task = tokio::spawn(pump(ws, opts, out_rx, events_tx, stop.clone()));
        Ok((Link { out, stop, task }, events, welcome))
    }

    /// Queues a text message for the current session; false once the link has ended.
    pub fn send(&self, text: String) -> bool {
        self.out.send(text).is_ok()
    }

    /// Closes the session (1000) and returns what the link went through.
    pub async fn close(self) -> LinkStats {
        self.stop.cancel();
        self.task.await.unwrap_or_default()
    }
}

/// Connects (with the token) and says hello; the welcome or why not.
pub async fn start(opts: &LinkOptions) -> Result<(Socket, Welcome), ClientError> {
    let mut ws = connect(&opts.url, opts.token.as_deref()).await?;
    let mut hello =
        serde_json::to_value(&opts.hello).map_err(|e| ClientError::BadMessage(e.to_string()))?;
    hello["type"] = "hello".into();
    ws.send(Message::Text(hello.to_string().into()))
        .await
        .map_err(Box::new)?;
    loop {
        let msg = tokio::time::timeout(Duration::from_secs(30), ws.next())
            .await
            .map_err(|_| ClientError::Timeout(Duration::from_secs(30)))?;
        match msg {
            Some(Ok(Message::Text(t))) => match serde_json::from_str::<ServerMessage>(t.as_str()) {
                Ok(ServerMessage::Welcome(w)) => return Ok((ws, w)),
                Ok(ServerMessage::Error(e)) => return Err(ClientError::Refused(e.code, e.message)),
                Ok(ServerMessage::Goodbye(_)) => continue,
                Err(e) => return Err(ClientError::BadMessage(e.to_string())),
            },
            Some(Ok(Message::Close(Some(f)))) => {
                return Err(ClientError::ClosedWith(
                    u16::from(f.code),
                    f.reason.to_string(),
                ))
            }
            Some(Ok(Message::Close(None))) | None => return Err(ClientError::Closed),
            Some(Ok(_)) => continue,
            Some(Err(e)) => return Err(Box::new(e).into()),
        }
    }
}

/// A WebSocket to `url`, with `Authorization: Bearer token` when a token is given.
pub async fn connect(url: &str, token: Option<&str>) -> Result<Socket, ClientError> {
    let failed = |e| ClientError::Connect {
        url: url.to_string(),
        source: Box::new(e),
    };
    let mut request = url.into_client_request().map_err(failed)?;
    if let Some(t) = token {
        let value = format!("Bearer {t}")
            .parse()
            .map_err(|_| ClientError::BadMessage("the token is not a valid header value".into()))?;
        request.headers_mut().insert("authorization", value);
    }
    // No Nagle: gaze samples and acks are tiny and must leave at once.
    let (ws, _) = tokio_tungstenite::connect_async_with_config(request, None, true)
        .await
        .map_err(failed)?;
    Ok(ws)
}

/// How one session ended.
enum End {
    /// The caller closed the link.
    Stopped,
    /// Worth a new session: goodbye, 1001, 1013, a dropped connection.
    Moved(String),
    /// Not worth retrying (1000, a policy or protocol close).
    Over(String),
}

async fn pump(
    mut ws: Socket,
    opts: LinkOptions,
    mut out: mpsc::UnboundedReceiver<String>,
    events: mpsc::UnboundedSender<LinkEvent>,
    stop: CancellationToken,
) -> LinkStats {
    let mut stats = LinkStats::default();
    let mut connection = 0u32;
    // When the previous session's last frame came, while a reconnect's gap is open.
    let mut gap_from: Option<Instant> = None;
    let mut last_frame = Instant::now();
    loop {
        let end = session(&mut ws, &mut out, &events, connection, &stop, &mut |at| {
            if let Some(from) = gap_from.take() {
                stats
                    .gaps_ms
                    .push(at.duration_since(from).as_secs_f64() * 1e3);
            }
            last_frame = at;
        })
        .await;
        let reason = match end {
            End::Stopped => {
                let _ = ws.close(None).await;
                return stats;
            }
            End::Over(why) => {
                stats.ended = Some(why);
                return stats;
            }
            End::Moved(_) if !opts.reconnect => {
                stats.ended = Some("the server went away".into());
                return stats;
            }
            End::Moved(why) => why,
        };
        let _ = tokio::time::timeout(Duration::from_millis(200), ws.close(None)).await;
        tracing::info!("reconnecting: {reason}");
        match reopen(&opts, &stop, &mut out, &mut stats).await {
            Some(new) => ws = new,
            None => return stats,
        }
        connection += 1;
        stats.reconnects += 1;
        gap_from = Some(last_frame);
        tracing::info!(connection, "reconnected after {reason}");
    }
}

/// New sessions until one says welcome, with exponential backoff; `None` when the caller
/// stopped or `GIVE_UP` passed (the reason is in `stats.ended`).
async fn reopen(
    opts: &LinkOptions,
    stop: &CancellationToken,
    out: &mut mpsc::UnboundedReceiver<String>,
    stats: &mut LinkStats,
) -> Option<Socket> {
    let began = Instant::now();
    let mut backoff = FIRST_BACKOFF;
    loop {
        let attempt = start(opts).await;
        // What the caller sent meanwhile is stale gaze: dropped, and counted.
        while out.try_recv().is_ok() {
            stats.dropped += 1;
        }
        match attempt {
            Ok((ws, _)) => return Some(ws),
            Err(e) if began.elapsed() > GIVE_UP => {
                stats.ended = Some(format!("no new session within {GIVE_UP:?}: {e}"));
                return None;
            }
            Err(e) => tracing::debug!("reconnect failed, retrying in {backoff:?}: {e}"),
        }
        tokio::select! {
            _ = stop.cancelled() => return None,
            _ = tokio::time::sleep(backoff) => {}
        }
        backoff = (backoff * 2).min(MAX_BACKOFF);
    }
}

/// Runs one session until it ends; `on_frame` is told when each frame arrives.
async fn session(
    ws: &mut Socket,
    out: &mut mpsc::UnboundedReceiver<String>,
    events: &mpsc::UnboundedSender<LinkEvent>,
    connection: u32,
    stop: &CancellationToken,
    on_frame: &mut impl FnMut(Instant),
) -> End {
    // Set by a goodbye: leave at this time.
    let mut leave_at: Option<tokio::time::Instant> = None;
    loop {
        let leave = async {
            match leave_at {
                Some(at) => tokio::time::sleep_until(at).await,
                None => std::future::pending().await,
            }
        };
        tokio::select! {
            _ = stop.cancelled() => return End::Stopped,
            _ = leave => return End::Moved("the server is draining".into()),
            text = out.recv() => match text {
                Some(t) => {
                    if ws.send(Message::Text(t.into())).await.is_err() {
                        return End::Moved("the connection dropped".into());
                    }
                }
                None => return End::Stopped,
            },
            msg = ws.next() => match msg {
                Some(Ok(Message::Binary(bytes))) => {
                    let Ok((header, image)) = decode_frame(&bytes) else { continue };
                    on_frame(Instant::now());
                    let ack = format!(r#"{{"type":"ack","frame":{}}}"#, header.frame);
                    if ws.send(Message::Text(ack.into())).await.is_err() {
                        return End::Moved("the connection dropped".into());
                    }
                    let image = image.to_vec();
                    let _ = events.send(LinkEvent::Frame { header, image, connection });
                }
                Some(Ok(Message::Text(t))) => match serde_json::from_str::<ServerMessage>(t.as_str()) {
                    Ok(ServerMessage::Goodbye(g)) => {
                        let wait = Duration::from_millis(g.retry_ms.min(10_000));
                        leave_at = Some(tokio::time::Instant::now() + wait);
                    }
                    Ok(ServerMessage::Error(e)) => {
                        let _ = events.send(LinkEvent::Error(e));
                    }
                    Ok(ServerMessage::Welcome(_)) | Err(_) => {}
                },
                Some(Ok(Message::Close(frame))) => {
                    let (code, reason) = frame
                        .map(|f| (u16::from(f.code), f.reason.to_string()))
                        .unwrap_or((1005, String::new()));
                    return match code {
                        1001 | 1012 | 1013 => End::Moved(format!("closed {code} {reason}")),
                        _ => End::Over(format!("the server closed the session: {code} {reason}")),
                    };
                }
                Some(Ok(_)) => {}
                Some(Err(_)) | None => return End::Moved("the connection dropped".into()),
            },
        }
    }
}
