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
