//! Logs for machines and for people: `--log-format json` writes one JSON object per line, and
//! text logs carry no colour codes when stderr is not a terminal (here it is a pipe).

fn render(args: &[&str]) -> String {
    let out = std::env::temp_dir().join(format!("fovea-logs-{}.png", std::process::id()));
    let o = std::process::Command::new(env!("CARGO_BIN_EXE_fovea"))
        .args(args)
        .args(["render", "--size", "16x12", "--out"])
        .arg(&out)
        .output()
        .expect("fovea runs");
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    String::from_utf8_lossy(&o.stderr).into_owned()
}

#[test]
fn json_logs_parse_one_object_per_line() {
    let stderr = render(&["--log-format", "json"]);
    let logs: Vec<serde_json::Value> = stderr
        .lines()
        .filter(|l| l.starts_with('{'))
        .map(|l| serde_json::from_str(l).unwrap_or_else(|e| panic!("{e}: {l}")))
        .collect();
    assert!(!logs.is_empty(), "no JSON log lines in:\n{stderr}");
    for l in &logs {
        assert!(
            l["level"].is_string() && l["fields"]["message"].is_string(),
            "{l}"
        );
    }
    assert!(logs
        .iter()
        .any(|l| l["fields"]["message"] == "GPU adapter chosen"));
}

#[test]
fn text_logs_to_a_pipe_have_no_colour_codes() {
    let stderr = render(&[]);
    assert!(stderr.contains("GPU adapter chosen"), "{stderr}");
    assert!(!stderr.contains('\u{1b}'), "ANSI codes in:\n{stderr}");
}

/// A server asked for JSON logs writes nothing else to stderr, even while an H.264 session
/// starts its encoder (openh264 printed a raw warning line per stream before its log level was
/// set ahead of its initialisation).
#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn an_h264_session_leaves_the_json_log_json() {
    use tokio::io::{AsyncBufReadExt, AsyncReadExt, BufReader};
    let mut server = tokio::process::Command::new(env!("CARGO_BIN_EXE_fovea"))
        .args(["--log-format", "json", "serve", "--addr", "127.0.0.1:0"])
        .stdout(std::process::Stdio::piped())
        .stderr(std::process::Stdio::piped())
        .kill_on_drop(true)
        .spawn()
        .expect("fovea runs");
    let mut stdout = BufReader::new(server.stdout.take().unwrap()).lines();
    let line = tokio::time::timeout(std::time::Duration::from_secs(120), stdout.next_line())
        .await
        .expect("listens within 2 min")
        .unwrap()
        .expect("a line");
    let url = line
        .split("http://")
        .nth(1)
        .map(|a| format!("ws://{}ws", a.trim()))
        .unwrap_or_else(|| panic!("no address in {line}"));
    let mut c = fovea::client::Client::connect(&url).await.unwrap();
    c.hello(&fovea::protocol::Hello {
        scene: "bunny".into(),
        width: 64,
        height: 48,
        codec: fovea::protocol::Codec::H264,
        ..Default::default()
    })
    .await
    .unwrap();
    loop {
        match c.next_event(std::time::Duration::from_secs(60)).await {
            Ok(fovea::client::Event::Frame { header, .. }) => {
                assert_eq!(header.keyframe, Some(true));
                break;
            }
            Ok(fovea::client::Event::Error(e)) => panic!("{e:?}"),
            Ok(_) => continue,
            Err(e) => panic!("no frame: {e}"),
        }
    }
    drop(c);
    server.start_kill().unwrap();
    let mut stderr = String::new();
    server
        .stderr
        .take()
        .unwrap()
        .read_to_string(&mut stderr)
        .await
        .unwrap();
    for l in stderr.lines().filter(|l| !l.trim().is_empty()) {
        assert!(
            serde_json::from_str::<serde_json::Value>(l).is_ok(),
            "not JSON: {l}"
        );
    }
    assert!(stderr.contains("GPU adapter chosen"), "{stderr}");
}
