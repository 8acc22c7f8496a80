//! A client that breaks the WebSocket rules is closed with the code that names what it broke
//! (RFC 6455 §7.4.1) and a reason, not dropped: 1009 for a message over the limit, 1007 for text
//! that is not UTF-8, 1002 for a malformed frame.

mod common;

use std::time::Duration;

use fovea::client::{Client, Event};
use fovea::server::ServerOptions;
use futures_util::{SinkExt, StreamExt};
use tokio_tungstenite::tungstenite::protocol::frame::coding::{Data, OpCode};
use tokio_tungstenite::tungstenite::protocol::frame::Frame;
use tokio_tungstenite::tungstenite::Message;

const WAIT: Duration = Duration::from_secs(30);

/// Sends `message` on a fresh socket and returns the close frame the server answers with.
async fn close_after(url: &str, message: Message) -> Option<(u16, String)> {
    let (mut ws, _) = tokio_tungstenite::connect_async(url).await.unwrap();
    ws.send(message).await.unwrap();
    loop {
        match tokio::time::timeout(WAIT, ws.next())
            .await
            .expect("an answer")
        {
            Some(Ok(Message::Close(f))) => {
                return f.map(|f| (u16::from(f.code), f.reason.to_string()))
            }
            Some(Ok(_)) => continue,
            Some(Err(e)) => panic!("the socket failed instead of closing: {e}"),
            None => panic!("the socket ended without a close frame"),
        }
    }
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn violations_close_with_their_codes() {
    let (addr, server) = common::start(ServerOptions::default()).await;
    let url = format!("ws://{addr}/ws");

    let huge = format!(r#"{{"type":"gaze","pad":"{}"}}"#, "x".repeat(200_000));
    let (code, reason) = close_after(&url, Message::Text(huge.into())).await.unwrap();
    assert_eq!(code, 1009, "{reason}");
    assert!(
        reason.contains("65536"),
        "the reason names the limit: {reason}"
    );

    let not_utf8 = Frame::message(vec![b'{', 0xff, 0xfe, b'}'], OpCode::Data(Data::Text), true);
    let (code, reason) = close_after(&url, Message::Frame(not_utf8)).await.unwrap();
    assert_eq!(code, 1007, "{reason}");

    let mut reserved = Frame::message(b"{}".to_vec(), OpCode::Data(Data::Text), true);
    reserved.header_mut().rsv2 = true;
    let (code, reason) = close_after(&url, Message::Frame(reserved)).await.unwrap();
    assert_eq!(code, 1002, "{reason}");

    // Below the hard limit, an over-long message is an error reply and the session goes on.
    let mut c = Client::connect(&url).await.unwrap();
    let long = format!(r#"{{"type":"gaze","pad":"{}"}}"#, "x".repeat(40_000));
    c.send_text(&long).await.unwrap();
    match c.next_event(WAIT).await.unwrap() {
        Event::Error(e) => assert_eq!(e.code, fovea::protocol::ErrorCode::TooLarge),
        other => panic!("expected an error reply, got {other:?}"),
    }
    drop(c);
    server.stop().await;
}
