//! A session's WebSocket as two tasks: a reader that parses client messages into a channel and
//! a writer that sends the session's messages with a deadline. A slow send therefore never stops
//! the session from reading (acks, gaze, settings keep flowing), and a client that stops
//! reading is noticed: its send times out, or its outgoing queue fills. The writer also pings
//! every `ping_every`; a peer from which nothing (not even a pong) has come for three pings is
//! gone (a half-open connection, a client that neither reads nor sends).

use std::sync::atomic::{AtomicU64, Ordering};
use std::sync::Arc;
use std::time::{Duration, Instant};

use axum::extract::ws::{CloseFrame, Message, WebSocket};
use futures_util::{SinkExt, StreamExt};
use tokio::sync::mpsc;
use tokio::task::JoinHandle;
use tokio_util::sync::CancellationToken;

use super::timing::FrameTimes;
use crate::protocol::{
    parse_client_message, ClientMessage, ErrorCode, Limits, ProtocolError, ServerMessage,
};

/// Messages waiting for the socket. Frames are bounded by the client's credits; the rest is
/// room for replies. A client that lets this fill is not reading.
const OUTGOING: usize = 32;
/// Parsed messages waiting for the session; the reader waits when it is full.
const INCOMING: usize = 64;

/// What the reader hands the session.
#[derive(Debug)]
pub enum Incoming {
    Message(ClientMessage),
    /// A text message that did not parse or validate: the client gets this error.
    Invalid(ProtocolError),
    /// The client broke the WebSocket rules: the session closes with this code and reason.
    Violation(u16, String),
}

/// What the session hands the writer.
#[derive(Debug)]
pub enum Outgoing {
    Text(ServerMessage),
    /// A frame's binary message and its timing record (the writer stamps `sent`).
    Frame(Vec<u8>, FrameTimes),
    Close(CloseFrame),
    /// A WebSocket ping (the writer's own keepalive).
    Ping,
}

/// The outgoing queue is full or the writer has stopped: the client is not reading.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Gone;

/// The session selects on these three at once, so they are fields, not methods.
pub struct Connection {
    /// Client messages; `None` once the client has closed or the socket failed.
    pub incoming: mpsc::Receiver<Incoming>,
    /// The timing record of each frame the writer handed to the socket.
    pub sent: mpsc::UnboundedReceiver<FrameTimes>,
    /// Cancelled when a send fails or times out.
    pub gone: CancellationToken,
    outgoing: mpsc::Sender<Outgoing>,
    reader: JoinHandle<()>,
    writer: JoinHandle<()>,
    send_timeout: Duration,
}

impl Connection {
    pub fn open(
        socket: WebSocket,
        limits: Limits,
        send_timeout: Duration,
        ping_every: Duration,
        id: u64,
    ) -> Self {
        let (sink, stream) = socket.split();
        let (in_tx, incoming) = mpsc::channel(INCOMING);
        let (outgoing, out_rx) = mpsc::channel(OUTGOING);
        let (sent_tx, sent) = mpsc::unbounded_channel();
        let gone = CancellationToken::new();
        let opened = Instant::now();
        let heard = Arc::new(AtomicU64::new(0));
        let reader = tokio::spawn(read(stream, in_tx, limits, (opened, heard.clone()), id));
        let writer = tokio::spawn(write(
            sink,
            out_rx,
            sent_tx,
            gone.clone(),
            (send_timeout, ping_every),
            (opened, heard),
            id,
        ));
        Connection {
            incoming,
            outgoing,
            sent,
            gone,
            reader,
            writer,
            send_timeout,
        }
    }

    /// Queues a message without waiting, so the session never blocks on a slow client.
    pub fn send(&self, message: Outgoing) -> Result<(), Gone> {
        self.outgoing.try_send(message).map_err(|_| Gone)
    }

    /// Sends `close` (if any) after what is queued, waits for the writer for at most one send
    /// timeout, and stops both tasks.
    pub async fn close(self, close: Option<CloseFrame>) {
        if let Some(frame) = close {
            let _ = self.outgoing.try_send(Outgoing::Close(frame));
        }
        drop(self.outgoing);
        let mut writer = self.writer;
        if tokio::time::timeout(self.send_timeout, &mut writer)
            .await
            .is_err()
        {
            writer.abort();
        }
        self.reader.abort();
    }
}

/// When the connection opened, and when the client was last heard from (ms after that).
type Heard = (Instant, Arc<AtomicU64>);

async fn read(
    mut stream: futures_util::stream::SplitStream<WebSocket>,
    incoming: mpsc::Sender<Incoming>,
    limits: Limits,
    (opened, heard): Heard,
    id: u64,
) {
    while let Some(msg) = stream.next().await {
        heard.store(opened.elapsed().as_millis() as u64, Ordering::Relaxed);
        let parsed = match msg {
            Err(e) => {
                tracing::debug!(session = id, "socket error: {e}");
                if let Some((code, reason)) = violation(&e) {
                    let _ = incoming.send(Incoming::Violation(code, reason)).await;
                }
                break;
            }
            Ok(Message::Close(_)) => break,
            Ok(Message::Ping(_) | Message::Pong(_)) => continue,
            Ok(Message::Binary(_)) => Incoming::Invalid(ProtocolError::new(
                ErrorCode::UnexpectedBinary,
                "clients send JSON text messages only",
            )),
            Ok(Message::Text(text)) => match parse_client_message(text.as_str(), &limits) {
                Ok(m) => Incoming::Message(m),
                Err(e) => {
                    tracing::debug!(session = id, code = ?e.code, "bad message: {}", e.message);
                    Incoming::Invalid(e)
                }
            },
        };
        if incoming.send(parsed).await.is_err() {
            break; // the session has ended
        }
    }
}

/// The close code for a read error that is the client's fault (RFC 6455 §7.4.1), with a
/// reason; `None` for a connection that merely failed (reset, closed without a frame).
/// The transport's errors reach us boxed in `axum::Error`, so they are told apart by the
/// transport's own wording; `tests/close_codes.rs` holds each to its code.
fn violation(e: &axum::Error) -> Option<(u16, String)> {
    let text = e.to_string();
    let code = if text.contains("Space limit exceeded") || text.contains("too long") {
        return Some((
            1009,
            format!("message over {} bytes", super::HARD_MESSAGE_LIMIT),
        ));
    } else if text.contains("UTF-8") {
        1007
    } else if text.contains("protocol error") {
        1002
    } else {
        return None;
    };
    // Close reasons are at most 123 bytes.
    let reason: String = text.chars().take(100).collect();
    Some((code, reason))
}

async fn write(
    mut sink: futures_util::stream::SplitSink<WebSocket, Message>,
    mut outgoing: mpsc::Receiver<Outgoing>,
    sent: mpsc::UnboundedSender<FrameTimes>,
    gone: CancellationToken,
    (send_timeout, ping_every): (Duration, Duration),
    (opened, heard): Heard,
    id: u64,
) {
    let mut ping = tokio::time::interval_at(tokio::time::Instant::now() + ping_every, ping_every);
    loop {
        let message = tokio::select! {
            m = outgoing.recv() => match m {
                Some(m) => m,
                None => return,
            },
            _ = ping.tick() => {
                let silent = opened.elapsed().saturating_sub(Duration::from_millis(heard.load(Ordering::Relaxed)));
                if silent > 3 * ping_every {
                    ::metrics::counter!("fovea_sessions_unresponsive_total").increment(1);
                    tracing::info!(session = id, "nothing from the client for {silent:?}, not even a pong: closing");
                    gone.cancel();
                    return;
                }
                Outgoing::Ping
            }
        };
        let (msg, times, closing) = match message {
            Outgoing::Ping => (Message::Ping(Vec::new().into()), None, false),
            Outgoing::Text(m) => (Message::Text(m.to_json().into()), None, false),
            Outgoing::Frame(bytes, times) => (Message::Binary(bytes.into()), Some(times), false),
            Outgoing::Close(frame) => (Message::Close(Some(frame)), None, true),
        };
        // A client that stops reading fills its socket; it may not hold the session forever.
        let send = tokio::time::timeout(send_timeout, sink.send(msg));
        let span = tracing::debug_span!("send", session = id, frame = times.is_some());
        if !matches!(
            tracing::Instrument::instrument(send, span).await,
            Ok(Ok(()))
        ) {
            tracing::debug!(session = id, "client went away while we were sending");
            gone.cancel();
            return;
        }
        if let Some(mut t) = times {
            // Counted here, as the bytes leave: a session that ends with a timing record
            // still queued would otherwise not count a frame its client received.
            ::metrics::counter!("fovea_frames_sent_total").increment(1);
            t.sent = Some(Instant::now());
            let _ = sent.send(t);
        }
        if closing {
            return;
        }
    }
}
