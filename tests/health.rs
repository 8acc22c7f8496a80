//! An adapter that cannot run Fovea is refused at start, in one line that names the fix,
//! instead of a server that answers /readyz 200 and fails every frame. Forcing wgpu's GL
//! backend gives such an adapter here (Mesa's GL has no float render targets; where no GL
//! driver is installed there is no adapter at all, which is refused the same way).

use std::process::{Command, Stdio};
use std::time::{Duration, Instant};

#[test]
fn serve_refuses_an_adapter_that_cannot_render() {
    let mut child = Command::new(env!("CARGO_BIN_EXE_fovea"))
        .args(["serve", "--addr", "127.0.0.1:0"])
        .env("WGPU_BACKEND", "gl")
        .env("RUST_BACKTRACE", "0")
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .expect("fovea runs");
    let began = Instant::now();
    let status = loop {
        if let Some(status) = child.try_wait().unwrap() {
            break status;
        }
        if began.elapsed() > Duration::from_secs(120) {
            let _ = child.kill();
            panic!("fovea serve kept running on the GL backend");
        }
        std::thread::sleep(Duration::from_millis(100));
    };
    let out = child.wait_with_output().unwrap();
    let stdout = String::from_utf8_lossy(&out.stdout);
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(!status.success(), "{stderr}");
    assert!(!stdout.contains("listening"), "it never listened: {stdout}");
    let last = stderr
        .lines()
        .rev()
        .find(|l| l.starts_with("Error:"))
        .unwrap_or("");
    assert!(
        last.contains("mesa-vulkan-drivers") && last.contains("WGPU_BACKEND"),
        "one line that names the fix: {stderr}"
    );
}

/// A lost device (a driver reset; here the device destroyed on purpose) is replaced by the
/// render thread: the frame in the way fails, the renderer counts as failing meanwhile, and
/// frames render again on the new device without anyone restarting the server.
#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn a_lost_device_is_replaced_and_frames_go_on() {
    use fovea::render::{FrameRequest, RenderThread, Renderer};
    let renderer = Renderer::new().unwrap_or_else(|e| panic!("GPU tests need an adapter: {e}"));
    let (render, thread) = RenderThread::spawn(renderer).unwrap();
    let request = FrameRequest {
        stream: 1,
        ..FrameRequest::new("gallery", 64, 48)
    };
    let before = render.render(request.clone()).await.unwrap().frame.rgba;
    assert_eq!(render.restarts(), 0);
    render.lose_device().await.unwrap();
    let mut failures = Vec::new();
    let after = loop {
        match render.render(request.clone()).await {
            Ok(r) => break r.frame.rgba,
            Err(e) => failures.push(e.to_string()),
        }
        assert!(failures.len() < 10, "never recovered: {failures:?}");
    };
    assert!(
        !failures.is_empty(),
        "the frame on the lost device did not fail"
    );
    assert_eq!(render.restarts(), 1, "{failures:?}");
    assert_eq!(
        render.failing(),
        None,
        "healthy again after a frame rendered"
    );
    assert_eq!(before.len(), after.len());
    let diff = before
        .iter()
        .zip(&after)
        .filter(|(a, b)| a.abs_diff(**b) > 2)
        .count();
    assert!(
        diff < before.len() / 100,
        "the new device renders the same frame ({diff} px differ)"
    );
    drop(render);
    let _ = tokio::task::spawn_blocking(move || thread.join()).await;
}
