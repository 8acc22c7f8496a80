//! A Rust client for the protocol: what tests use now, and what `fovea replay` and `fovea load`
//! will drive.

use std::time::Duration;

use futures_util::{SinkExt, StreamExt};
use tokio::net::TcpStream;
use tokio_tungstenite::tungstenite::Message;
use tokio_tungstenite::{MaybeTlsStream, WebSocketStream};

use crate::protocol::{
    decode_frame, Ack, ErrorMessage, FrameHeader, Gaze, Goodbye, Hello, ServerMessage, Welcome,
};

#[derive(Debug, thiserror::Error)]
pub enum ClientError {
    #[error("connecting to {url}: {source}")]
    Connect {
        url: String,
        source: Box<tokio_tungstenite::tungstenite::Error>,
    },
    #[error("socket: {0}")]
    Socket(#[from] Box<tokio_tungstenite::tungstenite::Error>),
    #[error("server sent a message that does not parse: {0}")]
    BadMessage(String),
    #[error("server refused: {0:?}: {1}")]
    Refused(crate::protocol::ErrorCode, String),
    #[error("the server closed the connection")]
    Closed,
    #[error("the server closed the connection: {0} {1}")]
    ClosedWith(u16, String),
    #[error("nothing from the server within {0:?}")]
    Timeout(Duration),
}

/// Something the server said.
#[derive(Debug)]
pub enum Event {
    Welcome(Welcome),
    Error(ErrorMessage),
    Goodbye(Goodbye),
    Frame {
        header: FrameHeader,
        image: Vec<u8>,
    },
    /// The server closed the socket, with its close code and reason if it gave one.
    Closed(Option<(u16, String)>),
}

pub struct Client {
    ws: WebSocketStream<MaybeTlsStream<TcpStream>>,
}

impl Client {
    pub async fn connect(url: &str) -> Result<Client, ClientError> {
        Self::connect_with(url, None).await
    }

    /// Connects with `Authorization: Bearer token`.
    pub async fn connect_with(url: &str, token: Option<&str>) -> Result<Client, ClientError> {
        Ok(Client {
            ws: super::link::connect(url, token).await?,
        })
    }

    /// Sends raw text: for tests that need to send what a well-behaved client never would.
    pub async fn send_text(&mut self, text: &str) -> Result<(), ClientError> {
        self.ws
            .send(Message::Text(text.into()))
            .await
            .map_err(Box::new)?;
        Ok(())
    }

    pub async fn send_binary(&mut self, bytes: Vec<u8>) -> Result<(), ClientError> {
        self.ws
            .send(Message::Binary(bytes.into()))
            .await
            .map_err(Box::new)?;
        Ok(())
    }

    /// Sends `hello` and waits for `welcome`; an `error` reply becomes `ClientError::Refused`.
    pub async fn hello(&mut self, hello: &Hello) -> Result<Welcome, ClientError> {
        let mut v =
            serde_json::to_value(hello).map_err(|e| ClientError::BadMessage(e.to_string()))?;
        v["type"] = "hello".into();
        self.send_text(&v.to_string()).await?;
        loop {
            match self.next_event(Duration::from_secs(30)).await? {
                Event::Welcome(w) => return Ok(w),
                Event::Error(e) => return Err(ClientError::Refused(e.code, e.message)),
                Event::Closed(_) => return Err(ClientError::Closed),
                Event::Frame { .. } | Event::Goodbye(_) => {}
            }
        }
    }

    pub async fn gaze(&mut self, gaze: &Gaze) -> Result<(), ClientError> {
        let mut v =
            serde_json::to_value(gaze).map_err(|e| ClientError::BadMessage(e.to_string()))?;
        v["type"] = "gaze".into();
        self.send_text(&v.to_string()).await
    }

    pub async fn ack(&mut self, ack: &Ack) -> Result<(), ClientError> {
        let mut v =
            serde_json::to_value(ack).map_err(|e| ClientError::BadMessage(e.to_string()))?;
        v["type"] = "ack".into();
        self.send_text(&v.to_string()).await
    }

    /// The next thing the server says, waiting at most `timeout`.
    pub async fn next_event(&mut self, timeout: Duration) -> Result<Event, ClientError> {
        loop {
            let msg = tokio::time::timeout(timeout, self.ws.next())
                .await
                .map_err(|_| ClientError::Timeout(timeout))?;
            let msg = match msg {
                None => return Ok(Event::Closed(None)),
                Some(m) => m.map_err(Box::new)?,
            };
            return Ok(match msg {
                Message::Text(t) => match serde_json::from_str::<ServerMessage>(t.as_str()) {
                    Ok(ServerMessage::Welcome(w)) => Event::Welcome(w),
                    Ok(ServerMessage::Error(e)) => Event::Error(e),
                    Ok(ServerMessage::Goodbye(g)) => Event::Goodbye(g),
                    Err(e) => return Err(ClientError::BadMessage(format!("{e}: {t}"))),
                },
                Message::Binary(b) => {
                    let (header, image) =
                        decode_frame(&b).map_err(|e| ClientError::BadMessage(e.to_string()))?;
                    Event::Frame {
                        header,
                        image: image.to_vec(),
                    }
                }
                Message::Close(frame) => {
                    Event::Closed(frame.map(|f| (u16::from(f.code), f.reason.to_string())))
                }
                Message::Ping(_) | Message::Pong(_) | Message::Frame(_) => continue,
            });
        }
    }
}
