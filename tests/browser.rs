//! The web client in headless Chromium (the system's, driven over the DevTools protocol with
//! `chromiumoxide`: no Node.js) against a real `fovea serve`: frames stream, the marker follows
//! the mouse, scene/size/codec switches keep showing frames, the page reconnects after a
//! restart, a full server says so, and a settings change after idling is not counted as a
//! gaze latency. Screenshots of each state land in `target/browser-artifacts/`.
//!
//! CHROMIUM names the browser (default: the first of chromium, chromium-browser,
//! google-chrome on PATH). Without one the tests fail, naming the package to install.

use std::io::{BufRead, BufReader};
use std::path::PathBuf;
use std::process::{Child, Command, Stdio};
use std::sync::Mutex;
use std::time::{Duration, Instant};

use chromiumoxide::browser::{Browser, BrowserConfig};
use chromiumoxide::handler::viewport::Viewport;
use chromiumoxide::layout::Point;
use chromiumoxide::page::{Page, ScreenshotParams};
use futures_util::StreamExt;
use serde_json::Value;

/// One scenario at a time: each runs a server and a browser, and the machine has two cores.
static ONE_AT_A_TIME: Mutex<()> = Mutex::new(());

fn artifacts() -> PathBuf {
    let dir = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("target/browser-artifacts");
    let _ = std::fs::create_dir_all(&dir);
    dir
}

fn chromium() -> PathBuf {
    if let Some(p) = std::env::var_os("CHROMIUM") {
        return p.into();
    }
    let path = std::env::var_os("PATH").unwrap_or_default();
    for name in [
        "chromium",
        "chromium-browser",
        "google-chrome",
        "google-chrome-stable",
    ] {
        for dir in std::env::split_paths(&path) {
            let p = dir.join(name);
            if p.is_file() {
                return p;
            }
        }
    }
    panic!(
        "browser tests need Chromium: apt-get install chromium (or set CHROMIUM=/path/to/chrome)"
    );
}

struct Server {
    child: Child,
    url: String,
}

impl Server {
    /// Starts `fovea serve` with `args` on `port` (0: any) and waits for its listening line.
    fn start(port: u16, args: &[&str]) -> Server {
        let addr = format!("127.0.0.1:{port}");
        static LOGS: std::sync::atomic::AtomicU32 = std::sync::atomic::AtomicU32::new(0);
        let n = LOGS.fetch_add(1, std::sync::atomic::Ordering::Relaxed);
        let log = std::fs::File::create(
            artifacts().join(format!("server-{}-{n}.log", std::process::id())),
        )
        .expect("server log");
        let mut child = Command::new(env!("CARGO_BIN_EXE_fovea"))
            .args(["serve", "--addr", &addr])
            .args(args)
            .stdout(Stdio::piped())
            .stderr(log)
            .spawn()
            .expect("fovea serve starts");
        let stdout = child.stdout.take().expect("stdout");
        let (tx, rx) = std::sync::mpsc::channel();
        std::thread::spawn(move || {
            for line in BufReader::new(stdout).lines().map_while(Result::ok) {
                if let Some(rest) = line.strip_prefix("fovea listening on ") {
                    let _ = tx.send(rest.trim_end_matches('/').to_string());
                }
            }
        });
        let url = rx
            .recv_timeout(Duration::from_secs(60))
            .expect("fovea serve listens within 60 s");
        Server { child, url }
    }

    fn port(&self) -> u16 {
        self.url
            .rsplit(':')
            .next()
            .and_then(|p| p.parse().ok())
            .expect("a port")
    }

    /// SIGTERM, and the exit status it ends with.
    fn stop(mut self) -> std::process::ExitStatus {
        let _ = Command::new("kill")
            .arg(self.child.id().to_string())
            .status();
        self.child.wait().expect("fovea serve exits")
    }
}

async fn browser() -> (Browser, tokio::task::JoinHandle<()>) {
    let exe = chromium();
    // Playwright's chrome-headless-shell (the Ubuntu 24.04 route) is the old headless mode
    // itself and takes no --headless=new.
    let shell = exe.to_string_lossy().contains("headless");
    let builder = BrowserConfig::builder().chrome_executable(exe);
    let builder = if shell {
        builder
    } else {
        builder.new_headless_mode()
    };
    let config = builder
        .no_sandbox()
        .window_size(1280, 800)
        .viewport(Viewport {
            width: 1280,
            height: 800,
            ..Default::default()
        })
        .args([
            "--disable-gpu",
            "--disable-quic",
            "--no-first-run",
            "--disable-background-networking",
            "--disable-component-update",
            "--disable-sync",
        ])
        .build()
        .expect("browser config");
    let (browser, mut handler) = Browser::launch(config).await.expect("Chromium starts");
    let events = tokio::spawn(async move { while handler.next().await.is_some() {} });
    (browser, events)
}

async fn open(browser: &Browser, url: &str) -> Page {
    let page = browser.new_page(url).await.expect("page opens");
    wait_for(&page, "window.fovea && window.fovea.framesShown >= 1", 60).await;
    page
}

async fn eval(page: &Page, js: &str) -> Value {
    page.evaluate(js)
        .await
        .unwrap_or_else(|e| panic!("evaluating {js}: {e}"))
        .into_value()
        .unwrap_or(Value::Null)
}

/// Polls `js` until it is truthy; returns its value.
async fn wait_for(page: &Page, js: &str, seconds: u64) -> Value {
    let deadline = Instant::now() + Duration::from_secs(seconds);
    loop {
        let v = eval(page, js).await;
        if !matches!(v, Value::Null | Value::Bool(false)) && v != Value::from(0) {
            return v;
        }
        if Instant::now() > deadline {
            let state = eval(page, "JSON.stringify({status: document.getElementById('status').textContent, banner: document.getElementById('banner').textContent, frames: window.fovea?.framesShown, errors: window.fovea?.errors})").await;
            panic!("not true within {seconds} s: {js}\npage: {state}");
        }
        tokio::time::sleep(Duration::from_millis(100)).await;
    }
}

async fn screenshot(page: &Page, name: &str) {
    let path = artifacts().join(format!("{name}.png"));
    page.save_screenshot(ScreenshotParams::builder().build(), &path)
        .await
        .unwrap_or_else(|e| panic!("screenshot {name}: {e}"));
}

/// Distinct colours (5 bits per channel) on the canvas: a blank or flat frame has a handful.
const COLOURS: &str = "(() => { const c = document.getElementById('view'); const d = c.getContext('2d').getImageData(0, 0, c.width, c.height).data; const s = new Set(); for (let i = 0; i < d.length; i += 4) s.add((d[i] >> 3) << 10 | (d[i + 1] >> 3) << 5 | (d[i + 2] >> 3)); return s.size; })()";

/// Centroid of the server-drawn marker's magenta pixels, in canvas pixels.
const MARKER: &str = "(() => { const c = document.getElementById('view'); const d = c.getContext('2d').getImageData(0, 0, c.width, c.height).data; let sx = 0, sy = 0, n = 0; for (let i = 0; i < d.length; i += 4) if (d[i] > 190 && d[i + 1] < 130 && d[i + 2] > 140) { const k = i / 4; sx += k % c.width + 0.5; sy += Math.floor(k / c.width) + 0.5; n++; } return n ? {x: sx / n, y: sy / n, w: c.width, h: c.height} : null; })()";

async fn gaze_at(page: &Page, fx: f64, fy: f64) {
    let b = eval(page, "(() => { const r = document.getElementById('view').getBoundingClientRect(); return [r.x, r.y, r.width, r.height]; })()").await;
    let b: Vec<f64> = serde_json::from_value(b).expect("a rectangle");
    for step in 1..=4 {
        let t = f64::from(step) / 4.0;
        let p = Point::new(
            b[0] + (0.5 + t * (fx - 0.5)) * b[2],
            b[1] + (0.5 + t * (fy - 0.5)) * b[3],
        );
        page.move_mouse(p).await.expect("mouse moves");
    }
    let js = format!("(() => {{ const h = window.fovea.lastHeader; return h && h.trigger === 'gaze' && Math.abs(h.gaze.x - {fx}) < 0.01 && Math.abs(h.gaze.y - {fy}) < 0.01; }})()");
    wait_for(page, &js, 30).await;
}

async fn press(page: &Page, key: &str) {
    page.find_element("body")
        .await
        .expect("body")
        .press_key(key)
        .await
        .expect("key press");
}

fn lock() -> std::sync::MutexGuard<'static, ()> {
    ONE_AT_A_TIME.lock().unwrap_or_else(|p| p.into_inner())
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn the_page_streams_frames_and_the_marker_follows_the_mouse() {
    let _one = lock();
    let server = Server::start(
        0,
        &[
            "--record-dir",
            artifacts().join("recordings").to_str().unwrap(),
        ],
    );
    let (browser, events) = browser().await;
    let page = open(&browser, &server.url).await;
    let colours: u64 = serde_json::from_value(eval(&page, COLOURS).await).unwrap();
    assert!(
        colours > 50,
        "the frame is shaded, not flat ({colours} colours)"
    );

    gaze_at(&page, 0.25, 0.3).await;
    let m: Value = eval(&page, MARKER).await;
    let (x, y, w, h) = (
        m["x"].as_f64().unwrap(),
        m["y"].as_f64().unwrap(),
        m["w"].as_f64().unwrap(),
        m["h"].as_f64().unwrap(),
    );
    assert!(
        (x - 0.25 * w).abs() < 3.0 && (y - 0.3 * h).abs() < 3.0,
        "marker at ({x}, {y}) for gaze (0.25, 0.3)"
    );
    gaze_at(&page, 0.75, 0.7).await;
    let m2: Value = eval(&page, MARKER).await;
    assert!(
        m2["x"].as_f64().unwrap() - x > 0.4 * w,
        "the marker moved with the mouse"
    );
    wait_for(
        &page,
        "/gaze→display p50\\s+\\d/.test(document.getElementById('overlay').textContent)",
        10,
    )
    .await;
    screenshot(&page, "normal").await;

    // The stats panel hides and shows; the overlay and the fovea ring show on demand.
    press(&page, "s").await;
    assert_eq!(
        eval(&page, "document.getElementById('stats').hidden").await,
        Value::Bool(true)
    );
    press(&page, "o").await;
    press(&page, "v").await;
    wait_for(
        &page,
        "window.fovea.lastHeader && document.getElementById('overlay-mode').value === 'samples'",
        10,
    )
    .await;
    tokio::time::sleep(Duration::from_millis(1500)).await;
    screenshot(&page, "overlay-and-fovea").await;
    press(&page, "s").await;
    press(&page, "?").await;
    assert_eq!(
        eval(&page, "document.getElementById('help').open").await,
        Value::Bool(true)
    );
    screenshot(&page, "help").await;

    // The session's own recording downloads with its key, and not without it.
    let link = eval(&page, "window.fovea.welcome.recording").await;
    let link = link
        .as_str()
        .expect("a recording link when the server records")
        .to_string();
    let ok = eval(&page, &format!("fetch('{link}').then(r => r.text())")).await;
    assert!(
        ok.as_str().unwrap_or("").starts_with("t_ms,x,y,pupil_mm"),
        "{ok}"
    );
    let other = link.replace("/recordings/1", "/recordings/2");
    let status = eval(
        &page,
        &format!(
            "fetch('{}').then(r => r.status)",
            other.split('?').next().unwrap()
        ),
    )
    .await;
    assert_eq!(status, Value::from(404));
    assert!(eval(&page, "window.fovea.errors.length").await == Value::from(0));
    drop(page);
    drop(browser);
    events.abort();
    let status = server.stop();
    assert!(
        status.success(),
        "fovea serve exits cleanly on SIGTERM: {status}"
    );
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn switching_scene_size_and_codec_keeps_showing_frames() {
    let _one = lock();
    let server = Server::start(0, &[]);
    let (browser, events) = browser().await;
    let page = open(&browser, &server.url).await;
    for (control, value, name) in [
        ("scene", "opaque", "switch-scene"),
        ("size", "960x540", "switch-size"),
        ("codec", "png", "switch-codec"),
        ("scene", "bunny-marble", "switch-back"),
    ] {
        let connects = eval(&page, "window.fovea.connects").await.as_u64().unwrap();
        eval(&page, &format!("(() => {{ const s = document.getElementById('{control}'); s.value = '{value}'; s.dispatchEvent(new Event('change')); return true; }})()")).await;
        wait_for(
            &page,
            &format!("window.fovea.connects > {connects} && window.fovea.framesShown >= 1"),
            20,
        )
        .await;
        let colours: u64 = serde_json::from_value(eval(&page, COLOURS).await).unwrap();
        assert!(
            colours > 20,
            "{control} = {value}: the canvas shows a frame ({colours} colours)"
        );
        screenshot(&page, name).await;
    }
    let size = eval(
        &page,
        "[document.getElementById('view').width, window.fovea.lastHeader.codec]",
    )
    .await;
    assert_eq!(
        size,
        serde_json::json!([960, "png"]),
        "bunny-marble again, at 960x540 in PNG"
    );
    drop(page);
    drop(browser);
    events.abort();
    server.stop();
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn the_page_reconnects_after_the_server_restarts() {
    let _one = lock();
    let server = Server::start(0, &[]);
    let port = server.port();
    let (browser, events) = browser().await;
    let page = open(&browser, &server.url).await;
    let connects = eval(&page, "window.fovea.connects").await.as_u64().unwrap();
    let status = server.stop();
    assert!(
        status.success(),
        "fovea serve exits cleanly on SIGTERM: {status}"
    );
    wait_for(
        &page,
        "/reconnecting in \\d+ s/.test(document.getElementById('banner').textContent)",
        20,
    )
    .await;
    screenshot(&page, "reconnecting").await;
    let server = Server::start(port, &[]);
    wait_for(&page, &format!("window.fovea.connects > {connects} && window.fovea.welcome && window.fovea.framesShown >= 1"), 30).await;
    assert_eq!(
        eval(&page, "document.getElementById('banner').hidden").await,
        Value::Bool(true)
    );
    screenshot(&page, "reconnected").await;
    drop(page);
    drop(browser);
    events.abort();
    server.stop();
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn a_second_page_at_capacity_is_told_the_server_is_full() {
    let _one = lock();
    let server = Server::start(0, &["--max-sessions", "1"]);
    let (browser, events) = browser().await;
    let first = open(&browser, &server.url).await;
    let second = browser
        .new_page(server.url.as_str())
        .await
        .expect("page opens");
    wait_for(
        &second,
        "/server full, retrying in \\d+ s/.test(document.getElementById('banner').textContent)",
        20,
    )
    .await;
    screenshot(&second, "server-full").await;
    // When the first leaves, the second gets in on a retry.
    first.close().await.expect("page closes");
    wait_for(&second, "window.fovea.framesShown >= 1", 40).await;
    drop(second);
    drop(browser);
    events.abort();
    server.stop();
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn a_settings_change_after_idling_is_not_a_gaze_latency() {
    let _one = lock();
    let server = Server::start(0, &[]);
    let (browser, events) = browser().await;
    let page = open(&browser, &server.url).await;
    gaze_at(&page, 0.4, 0.5).await;
    let latencies = eval(&page, "window.fovea.stats.latencies.length").await;
    tokio::time::sleep(Duration::from_secs(15)).await;
    let frame = eval(&page, "window.fovea.lastHeader.frame")
        .await
        .as_u64()
        .unwrap();
    eval(&page, "(() => { const s = document.getElementById('overlay-mode'); s.value = 'probability'; s.dispatchEvent(new Event('change')); return true; })()").await;
    let h = wait_for(
        &page,
        &format!("window.fovea.lastHeader.frame > {frame} && window.fovea.lastHeader"),
        20,
    )
    .await;
    assert_eq!(h["trigger"], "settings", "{h}");
    let s = &h["stages_ms"];
    let work: f64 = ["render", "readback", "encode"]
        .iter()
        .map(|k| s[k].as_f64().unwrap())
        .sum();
    let queue = s["queue"].as_f64().unwrap();
    assert!(queue < work + 100.0, "queue {queue} ms after 15 s idle: timed from the change, not from the last sample (frame work {work} ms)");
    assert_eq!(
        eval(&page, "window.fovea.stats.latencies.length").await,
        latencies,
        "a settings frame adds no gaze latency"
    );
    let p95 = eval(&page, "window.fovea.stats.percentile(95)")
        .await
        .as_f64()
        .unwrap();
    assert!(p95 < 5000.0, "gaze→display p95 {p95} ms");
    drop(page);
    drop(browser);
    events.abort();
    server.stop();
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn auto_gaze_drives_the_frames_and_fullscreen_and_fit_work() {
    let _one = lock();
    let server = Server::start(0, &[]);
    let (browser, events) = browser().await;
    let page = open(&browser, &server.url).await;
    press(&page, "a").await;
    let js = "(async () => { const seen = new Set(); const until = performance.now() + 8000; while (performance.now() < until && seen.size < 4) { const h = window.fovea.lastHeader; if (h && h.trigger === 'gaze') seen.add(h.gaze.x.toFixed(3) + ',' + h.gaze.y.toFixed(3)); await new Promise(r => setTimeout(r, 100)); } return seen.size; })()";
    let seen = eval(&page, js).await.as_u64().unwrap_or(0);
    assert!(
        seen >= 4,
        "the synthetic eye moved the gaze ({seen} positions)"
    );
    press(&page, "w").await;
    assert_eq!(
        eval(&page, "document.body.classList.contains('fit')").await,
        Value::Bool(true)
    );
    screenshot(&page, "fit").await;
    press(&page, "f").await;
    wait_for(
        &page,
        "document.fullscreenElement && document.fullscreenElement.id === 'stage'",
        10,
    )
    .await;
    tokio::time::sleep(Duration::from_millis(800)).await;
    screenshot(&page, "fullscreen").await;
    assert_eq!(
        eval(&page, "window.fovea.errors.length").await,
        Value::from(0)
    );
    drop(page);
    drop(browser);
    events.abort();
    server.stop();
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn the_cornell_scene_streams_its_radiosity_preview_until_it_converges() {
    let _one = lock();
    let server = Server::start(0, &[]);
    let (browser, events) = browser().await;
    let page = open(&browser, &server.url).await;
    eval(&page, "(() => { const s = document.getElementById('scene'); s.value = 'cornell'; s.dispatchEvent(new Event('change')); document.getElementById('auto-gaze').click(); return true; })()").await;
    let early = wait_for(&page, "window.fovea.lastHeader?.radiosity", 60).await;
    let late = wait_for(
        &page,
        "window.fovea.lastHeader?.radiosity?.converged && window.fovea.lastHeader.radiosity",
        180,
    )
    .await;
    let (u0, u1) = (
        early["unshot"].as_f64().unwrap(),
        late["unshot"].as_f64().unwrap(),
    );
    assert!(u1 < 0.001 && u1 < u0, "unshot {u0} → {u1}");
    screenshot(&page, "cornell").await;
    drop(page);
    drop(browser);
    events.abort();
    server.stop();
}
