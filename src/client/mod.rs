//! Clients of the protocol: a plain connection (tests, tools), and `replay`, which streams a
//! gaze recording to a server at its recorded timing and records every frame that comes back.

mod connection;
pub mod load;
pub mod replay;

pub use connection::{Client, ClientError, Event};

use futures_util::stream::SplitSink;
use futures_util::SinkExt;
use tokio::net::TcpStream;
use tokio_tungstenite::tungstenite::Message;
use tokio_tungstenite::{MaybeTlsStream, WebSocketStream};

type Sink = SplitSink<WebSocketStream<MaybeTlsStream<TcpStream>>, Message>;

/// Every outgoing message of a split socket goes through one writer task; `None` closes the
/// socket (readers hold senders for their acks, so the channel itself may never close first).
pub(crate) fn spawn_writer(
    mut sink: Sink,
) -> (
    tokio::sync::mpsc::UnboundedSender<Option<String>>,
    tokio::task::JoinHandle<()>,
) {
    let (tx, mut rx) = tokio::sync::mpsc::unbounded_channel::<Option<String>>();
    let task = tokio::spawn(async move {
        while let Some(Some(text)) = rx.recv().await {
            if sink.send(Message::Text(text.into())).await.is_err() {
                break;
            }
        }
        let _ = sink.close().await;
    });
    (tx, task)
}
