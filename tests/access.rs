//! Access control and draining, against a real server on loopback: tokens and origins are
//! checked before the upgrade; a drain says goodbye, stops admitting, closes the rest with 1001
//! after the grace period, exits within it, and leaves every recording whole.

mod common;

use std::net::SocketAddr;
use std::time::{Duration, Instant};

use fovea::client::{Client, ClientError, Event};
use fovea::protocol::{Ack, Gaze, Hello};
use fovea::server::access::{Access, Secret};
use fovea::server::ServerOptions;
use tokio::io::{AsyncReadExt, AsyncWriteExt};
use tokio_tungstenite::tungstenite::client::IntoClientRequest;

const WAIT: Duration = Duration::from_secs(30);

fn hello() -> Hello {
    Hello {
        width: 48,
        height: 32,
        ..Hello::default()
    }
}

/// The HTTP status of a refused handshake, or 101 when it went through.
async fn handshake_status(url: &str, headers: &[(&str, &str)]) -> u16 {
    let mut request = url.into_client_request().unwrap();
    for (k, v) in headers {
        let name: axum::http::HeaderName = k.parse().expect("header name");
        request
            .headers_mut()
            .insert(name, v.parse().expect("header value"));
    }
    match tokio_tungstenite::connect_async(request).await {
        Ok(_) => 101,
        Err(tokio_tungstenite::tungstenite::Error::Http(r)) => r.status().as_u16(),
        Err(e) => panic!("{url}: {e}"),
    }
}

/// A raw HTTP request; returns the status code and the body.
async fn http(addr: SocketAddr, method: &str, path: &str, bearer: Option<&str>) -> (u16, String) {
    let mut s = tokio::net::TcpStream::connect(addr).await.unwrap();
    let auth = bearer
        .map(|t| format!("Authorization: Bearer {t}\r\n"))
        .unwrap_or_default();
    let req = format!(
        "{method} {path} HTTP/1.1\r\nHost: {addr}\r\n{auth}Content-Length: 0\r\nConnection: close\r\n\r\n"
    );
    s.write_all(req.as_bytes()).await.unwrap();
    let mut out = String::new();
    s.read_to_string(&mut out).await.unwrap();
    let code = out.get(9..12).and_then(|c| c.parse().ok()).unwrap_or(0);
    let body = out.split("\r\n\r\n").nth(1).unwrap_or("").to_string();
    (code, body)
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn sessions_need_the_token_and_the_pages_own_origin() {
    let (addr, server) = common::start(ServerOptions {
        access: Access {
            token: Secret::new("viewer-token"),
            allow_origins: vec!["https://lab.example".into()],
            ..Access::default()
        },
        ..ServerOptions::default()
    })
    .await;
    let url = format!("ws://{addr}/ws");
    assert_eq!(handshake_status(&url, &[]).await, 401, "no token");
    let wrong = [("authorization", "Bearer viewer-tokem")];
    assert_eq!(handshake_status(&url, &wrong).await, 401, "wrong token");
    let right = ("authorization", "Bearer viewer-token");
    assert_eq!(handshake_status(&url, &[right]).await, 101, "right token");
    let query = format!("{url}?token=viewer-token");
    assert_eq!(
        handshake_status(&query, &[]).await,
        101,
        "token in the query"
    );

    let own = format!("http://{addr}");
    for (origin, status) in [
        (own.as_str(), 101),
        ("https://lab.example", 101),
        ("http://evil.example", 403),
        ("null", 403),
    ] {
        let got = handshake_status(&url, &[right, ("origin", origin)]).await;
        assert_eq!(got, status, "Origin {origin}");
    }
    // A right token opens a working session through the client tools' path too.
    let mut c = Client::connect_with(&url, Some("viewer-token"))
        .await
        .unwrap();
    c.hello(&hello()).await.unwrap();
    assert!(matches!(
        c.next_event(WAIT).await.unwrap(),
        Event::Frame { .. }
    ));
    match Client::connect_with(&url, Some("nope")).await {
        Err(ClientError::Connect { .. }) => {}
        Err(e) => panic!("expected a refused handshake, got {e}"),
        Ok(_) => panic!("a wrong token opened a socket"),
    }
    server.stop().await;
}

#[tokio::test]
async fn serving_beyond_loopback_without_a_token_is_refused() {
    let open = Access::default();
    let any: SocketAddr = "0.0.0.0:8080".parse().unwrap();
    let err = fovea::server::check_exposure(any, &open, false).unwrap_err();
    assert!(
        err.contains("--token") && err.contains("--insecure-no-auth"),
        "{err}"
    );
    assert!(fovea::server::check_exposure(any, &open, true).is_ok());
    assert!(fovea::server::check_exposure("[::1]:1".parse().unwrap(), &open, false).is_ok());
    let with_token = Access {
        token: Secret::new("t"),
        ..Access::default()
    };
    assert!(fovea::server::check_exposure(any, &with_token, false).is_ok());
    // The command refuses before it opens the GPU, and says how to fix it.
    let out = tokio::process::Command::new(env!("CARGO_BIN_EXE_fovea"))
        .args(["serve", "--addr", "0.0.0.0:0"])
        .env_remove("FOVEA_TOKEN")
        .output()
        .await
        .unwrap();
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(!out.status.success(), "{stderr}");
    assert!(
        stderr.contains("refusing to serve on 0.0.0.0:0 without a token"),
        "{stderr}"
    );
}

/// Reads events until `want` matches one, acknowledging frames on the way.
async fn until(c: &mut Client, mut want: impl FnMut(&Event) -> bool) -> Event {
    loop {
        let e = c.next_event(WAIT).await.unwrap();
        if let Event::Frame { header, .. } = &e {
            let ack = Ack {
                frame: header.frame,
                t_ms: None,
                dropped: false,
            };
            let _ = c.ack(&ack).await;
        }
        if want(&e) {
            return e;
        }
        assert!(!matches!(e, Event::Closed(_)), "closed early: {e:?}");
    }
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn a_drain_says_goodbye_admits_nobody_and_ends_within_its_grace() {
    let dir = std::env::temp_dir().join(format!("fovea-drain-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    let grace = Duration::from_millis(1500);
    let (addr, server) = common::start(ServerOptions {
        drain: grace,
        record_dir: Some(dir.clone()),
        access: Access {
            admin_token: Secret::new("admin-token"),
            ..Access::default()
        },
        ..ServerOptions::default()
    })
    .await;
    let url = format!("ws://{addr}/ws");
    // Two sessions, each with gaze the server has answered (so it has recorded it).
    // Each connects just before its hello: a silent socket is closed after --hello-timeout-s,
    // and the first frame can take seconds while a cold driver compiles the shaders.
    let mut clients = Vec::new();
    for _ in 0..2 {
        let mut c = Client::connect(&url).await.unwrap();
        c.hello(&hello()).await.unwrap();
        for seq in 1..=20u64 {
            let g = Gaze {
                seq,
                t_ms: seq as f64,
                x: 0.3,
                y: 0.6,
                pupil_mm: Some(4.0),
                sample_t_ms: None,
            };
            c.gaze(&g).await.unwrap();
        }
        until(
            &mut c,
            |e| matches!(e, Event::Frame { header, .. } if header.samples == 20),
        )
        .await;
        clients.push(c);
    }
    let (mut leaver, mut stayer) = (clients.remove(0), clients.remove(0));
    assert_eq!(http(addr, "GET", "/readyz", None).await.0, 200);
    assert_eq!(http(addr, "POST", "/admin/drain", None).await.0, 401);
    assert_eq!(
        http(addr, "POST", "/admin/drain", Some("wrong")).await.0,
        401
    );
    let began = Instant::now();
    let (code, body) = http(addr, "POST", "/admin/drain", Some("admin-token")).await;
    assert_eq!(code, 202, "{body}");

    let (code, body) = http(addr, "GET", "/readyz", None).await;
    assert_eq!((code, body.as_str()), (503, "draining\n"));
    assert_eq!(
        handshake_status(&url, &[]).await,
        503,
        "no new sessions while draining"
    );
    for c in [&mut leaver, &mut stayer] {
        match until(c, |e| matches!(e, Event::Goodbye(_))).await {
            Event::Goodbye(g) => {
                assert_eq!(g.reason, "draining");
                assert!(g.retry_ms <= 500 && g.closes_in_ms == 1500, "{g:?}");
            }
            _ => unreachable!(),
        }
    }
    // Frames keep coming after the goodbye, until the client leaves or the grace ends.
    let g = Gaze {
        seq: 21,
        t_ms: 21.0,
        x: 0.7,
        y: 0.2,
        pupil_mm: None,
        sample_t_ms: None,
    };
    stayer.gaze(&g).await.unwrap();
    until(
        &mut stayer,
        |e| matches!(e, Event::Frame { header, .. } if header.seq == Some(21)),
    )
    .await;
    drop(leaver); // moves elsewhere
    let closed = until(&mut stayer, |e| matches!(e, Event::Closed(_))).await;
    let waited = began.elapsed();
    assert!(
        matches!(&closed, Event::Closed(Some((1001, _)))),
        "{closed:?}"
    );
    assert!(
        waited >= grace,
        "closed after {waited:?}, before the grace period"
    );
    server.stop().await;
    assert!(
        began.elapsed() < grace + Duration::from_secs(5),
        "the server exits within its grace period (+ close wait): {:?}",
        began.elapsed()
    );
    // Both recordings are whole: renamed into place, every received sample a complete row.
    let run = common::run_folder(&dir);
    let mut names: Vec<String> = std::fs::read_dir(&run)
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .collect();
    names.sort();
    assert_eq!(
        names,
        ["session-1.csv", "session-2.csv"],
        "no .partial left"
    );
    for n in names {
        let text = std::fs::read_to_string(run.join(&n)).unwrap();
        let rows: Vec<&str> = text.lines().skip(1).collect();
        let want = if n == "session-2.csv" { 21 } else { 20 };
        assert_eq!(rows.len(), want, "{n}: {text}");
        assert!(
            rows.iter().all(|r| r.split(',').count() == 4),
            "{n}: {text}"
        );
    }
    let _ = std::fs::remove_dir_all(&dir);
}
