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

/// A client that neither reads nor sends (a dead peer, a half-open connection) is let go after
/// three unanswered pings, long before the stall timeout; one that reads answers the pings and
/// keeps its session.
#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn pings_let_go_of_a_silent_client_and_keep_a_reading_one() {
    let ping = Duration::from_millis(200);
    let (addr, server) = common::start(ServerOptions {
        max_sessions: 1,
        ping_every: ping,
        stall_timeout: Duration::from_secs(60),
        ..ServerOptions::default()
    })
    .await;
    let url = format!("ws://{addr}/ws");
    let (mut dead, _) = tokio_tungstenite::connect_async(&url).await.unwrap();
    let hello = r#"{"type":"hello","v":1,"width":32,"height":32}"#;
    dead.send(Message::Text(hello.into())).await.unwrap();
    // From here `dead` is never polled again: no pong ever leaves it.
    let began = std::time::Instant::now();
    let mut viewer = loop {
        let mut c = Client::connect(&url).await.unwrap();
        let h = fovea::protocol::Hello {
            width: 32,
            height: 32,
            ..Default::default()
        };
        if c.hello(&h).await.is_ok() {
            break c;
        }
        assert!(
            began.elapsed() < Duration::from_secs(20),
            "the slot was never freed"
        );
        tokio::time::sleep(Duration::from_millis(100)).await;
    };
    let freed = began.elapsed();
    assert!(
        freed >= 3 * ping,
        "let go after {freed:?}, before three pings"
    );
    // The viewer reads (and so answers pings) for ten ping periods and still has its session.
    let until = std::time::Instant::now() + 10 * ping;
    while std::time::Instant::now() < until {
        match viewer.next_event(Duration::from_millis(100)).await {
            Ok(Event::Closed(c)) => panic!("a reading client was closed: {c:?}"),
            Ok(_) | Err(fovea::client::ClientError::Timeout(_)) => {}
            Err(e) => panic!("{e}"),
        }
    }
    let g = fovea::protocol::Gaze {
        seq: 1,
        t_ms: 1.0,
        x: 0.2,
        y: 0.2,
        pupil_mm: None,
        sample_t_ms: None,
    };
    viewer.gaze(&g).await.unwrap();
    loop {
        match viewer.next_event(WAIT).await.unwrap() {
            Event::Frame { header, .. } if header.seq == Some(1) => break,
            Event::Frame { header, .. } => {
                let ack = fovea::protocol::Ack {
                    frame: header.frame,
                    t_ms: None,
                    dropped: false,
                };
                viewer.ack(&ack).await.unwrap();
            }
            Event::Closed(c) => panic!("closed: {c:?}"),
            _ => {}
        }
    }
    drop((dead, viewer));
    server.stop().await;
}
