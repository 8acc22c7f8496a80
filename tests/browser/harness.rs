//! The browser tests' harness: a `fovea serve` child process, a headless Chromium driven over
//! the DevTools protocol, and small page helpers.

use std::io::{BufRead, BufReader};
use std::path::PathBuf;
use std::process::{Child, Command, Stdio};
use std::sync::{Mutex, MutexGuard};
use std::time::{Duration, Instant};

use chromiumoxide::browser::{Browser, BrowserConfig};
use chromiumoxide::handler::viewport::Viewport;
use chromiumoxide::layout::Point;
use chromiumoxide::page::{Page, ScreenshotParams};
use futures_util::StreamExt;
use serde_json::Value;

/// One scenario at a time: each runs a server and a browser, and the machine has two cores.
static ONE_AT_A_TIME: Mutex<()> = Mutex::new(());

pub fn artifacts() -> PathBuf {
    let dir = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("target/browser-artifacts");
    let _ = std::fs::create_dir_all(&dir);
    dir
}

pub fn chromium() -> PathBuf {
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

pub struct Server {
    child: Child,
    pub url: String,
}

/// A test that fails (panics) still ends its server: a live one would slow every test after
/// it (in one suite run, four browser tests' servers outlived them and later tests timed out).
impl Drop for Server {
    fn drop(&mut self) {
        let _ = self.child.kill();
        let _ = self.child.wait();
    }
}

impl Server {
    /// Starts `fovea serve` with `args` on `port` (0: any) and waits for its listening line.
    pub fn start(port: u16, args: &[&str]) -> Server {
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
        // Held as a Server before it listens, so one that never does is ended by Drop.
        let mut server = Server {
            child,
            url: String::new(),
        };
        server.url = rx
            .recv_timeout(Duration::from_secs(60))
            .expect("fovea serve listens within 60 s");
        server
    }

    pub fn port(&self) -> u16 {
        self.url
            .rsplit(':')
            .next()
            .and_then(|p| p.parse().ok())
            .expect("a port")
    }

    /// SIGTERM, and the exit status it ends with.
    pub fn stop(&mut self) -> std::process::ExitStatus {
        let _ = Command::new("kill")
            .arg(self.child.id().to_string())
            .status();
        self.child.wait().expect("fovea serve exits")
    }
}

pub async fn browser() -> (Browser, tokio::task::JoinHandle<()>) {
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

pub async fn open(browser: &Browser, url: &str) -> Page {
    let page = browser.new_page(url).await.expect("page opens");
    wait_for(&page, "window.fovea && window.fovea.framesShown >= 1", 60).await;
    page
}

pub async fn eval(page: &Page, js: &str) -> Value {
    page.evaluate(js)
        .await
        .unwrap_or_else(|e| panic!("evaluating {js}: {e}"))
        .into_value()
        .unwrap_or(Value::Null)
}

/// The page was sent no error message; on failure, the errors themselves (code and message).
pub async fn assert_no_server_errors(page: &Page) {
    let errors = eval(page, "window.fovea.errors").await;
    assert_eq!(errors, Value::Array(vec![]), "the server refused something");
}

/// A script for `Fixture::page_after` that delays every call of the async browser function
/// `owner.name` by `ms` and counts the calls under way in `window.<counter>`, so that a test
/// can act while one is in flight.
pub fn slowed(owner: &str, name: &str, ms: u32, counter: &str) -> String {
    format!(
        "(() => {{ const o = {owner}; const real = o.{name}.bind(o); window.{counter} = 0; \
         o.{name} = async (...a) => {{ window.{counter} += 1; \
           try {{ await new Promise((r) => setTimeout(r, {ms})); return await real(...a); }} \
           finally {{ window.{counter} -= 1; }} }}; }})();"
    )
}

/// Polls `js` until it is truthy; returns its value.
pub async fn wait_for(page: &Page, js: &str, seconds: u64) -> Value {
    let deadline = Instant::now() + Duration::from_secs(seconds);
    loop {
        let v = eval(page, js).await;
        if !matches!(v, Value::Null | Value::Bool(false)) && v != 0 {
            return v;
        }
        if Instant::now() > deadline {
            let state = eval(page, "JSON.stringify({status: document.getElementById('status').textContent, banner: document.getElementById('banner').textContent, frames: window.fovea?.framesShown, errors: window.fovea?.errors})").await;
            panic!("not true within {seconds} s: {js}\npage: {state}");
        }
        tokio::time::sleep(Duration::from_millis(100)).await;
    }
}

pub async fn screenshot(page: &Page, name: &str) {
    let path = artifacts().join(format!("{name}.png"));
    page.save_screenshot(ScreenshotParams::builder().build(), &path)
        .await
        .unwrap_or_else(|e| panic!("screenshot {name}: {e}"));
}

/// Distinct colours (5 bits per channel) on the canvas: a blank or flat frame has a handful.
pub const COLOURS: &str = "(() => { const c = document.getElementById('view'); const d = c.getContext('2d').getImageData(0, 0, c.width, c.height).data; const s = new Set(); for (let i = 0; i < d.length; i += 4) s.add((d[i] >> 3) << 10 | (d[i + 1] >> 3) << 5 | (d[i + 2] >> 3)); return s.size; })()";

/// Mean RGB of the canvas's top-left 40×40 corner (background, far from the gaze marker).
pub const CORNER: &str = "(() => { const c = document.getElementById('view'); const d = c.getContext('2d').getImageData(0, 0, 40, 40).data; const m = [0, 0, 0]; for (let i = 0; i < d.length; i += 4) for (let k = 0; k < 3; k++) m[k] += d[i + k] / 1600; return m; })()";

/// Centroid of the server-drawn marker's magenta pixels, in canvas pixels.
pub const MARKER: &str = "(() => { const c = document.getElementById('view'); const d = c.getContext('2d').getImageData(0, 0, c.width, c.height).data; let sx = 0, sy = 0, n = 0; for (let i = 0; i < d.length; i += 4) if (d[i] > 190 && d[i + 1] < 130 && d[i + 2] > 140) { const k = i / 4; sx += k % c.width + 0.5; sy += Math.floor(k / c.width) + 0.5; n++; } return n ? {x: sx / n, y: sy / n, w: c.width, h: c.height} : null; })()";

pub async fn gaze_at(page: &Page, fx: f64, fy: f64) {
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

/// A mouse move over the canvas at `fx` across, mid-height (the page sends it as gaze);
/// unlike `gaze_at`, it does not wait for a frame.
pub async fn mouse_at(page: &Page, fx: f64) {
    let js = format!("(() => {{ const c = document.getElementById('view'); const r = c.getBoundingClientRect(); c.dispatchEvent(new MouseEvent('mousemove', {{clientX: r.x + {fx} * r.width, clientY: r.y + r.height / 2, bubbles: true}})); return true; }})()");
    eval(page, &js).await;
}

/// Moves the gaze to (fx, fy) and waits until a frame answering it is drawn on the canvas.
pub async fn gaze_and_frame(page: &Page, fx: f64, fy: f64) {
    let shown = eval(page, "window.fovea.framesShown").await.as_u64();
    let shown = shown.expect("a frame count");
    gaze_at(page, fx, fy).await;
    wait_for(page, &format!("window.fovea.framesShown > {shown}"), 20).await;
}

pub async fn press(page: &Page, key: &str) {
    page.find_element("body")
        .await
        .expect("body")
        .press_key(key)
        .await
        .expect("key press");
}

/// One scenario's server and browser, run one scenario at a time.
pub struct Fixture {
    _one: MutexGuard<'static, ()>,
    pub server: Server,
    pub browser: Browser,
    events: tokio::task::JoinHandle<()>,
}

impl Fixture {
    /// Starts `fovea serve` with `args` and a headless Chromium.
    pub async fn start(args: &[&str]) -> Fixture {
        let one = ONE_AT_A_TIME.lock().unwrap_or_else(|p| p.into_inner());
        let server = Server::start(0, args);
        let (browser, events) = browser().await;
        Fixture {
            _one: one,
            server,
            browser,
            events,
        }
    }

    /// A page of the server, once it shows its first frame.
    pub async fn page(&self) -> Page {
        open(&self.browser, &self.server.url).await
    }

    /// A page of the server opened with `query` (as a shared link preselects the menus, e.g.
    /// `codec=jpeg`), once it shows its first frame.
    pub async fn page_with(&self, query: &str) -> Page {
        open(&self.browser, &format!("{}/?{query}", self.server.url)).await
    }

    /// A page of the server with `script` run before the page's own (to change what the
    /// browser offers), once it shows its first frame.
    pub async fn page_after(&self, script: &str) -> Page {
        let page = self
            .browser
            .new_page("about:blank")
            .await
            .expect("page opens");
        page.evaluate_on_new_document(script)
            .await
            .expect("script registered");
        page.goto(self.server.url.as_str())
            .await
            .expect("page loads");
        wait_for(&page, "window.fovea && window.fovea.framesShown >= 1", 60).await;
        page
    }

    /// Closes the browser, then stops the server; the server's exit status.
    pub fn finish(mut self) -> std::process::ExitStatus {
        self.events.abort();
        drop(self.browser);
        self.server.stop()
    }
}

/// Sets an element's value (`set`, with the element as `e`) and fires its change event, as a
/// viewer's click does.
pub fn change(id: &str, set: &str) -> String {
    format!("(() => {{ const e = document.getElementById('{id}'); {set}; e.dispatchEvent(new Event('change')); return true; }})()")
}

/// Sets menu `id` to `value` as a viewer does, and waits up to `seconds` until the session it
/// opens shows a frame.
pub async fn choose(page: &Page, id: &str, value: &str, seconds: u64) {
    let connects = eval(page, "window.fovea.connects").await.as_u64();
    let connects = connects.expect("a connection count");
    eval(page, &change(id, &format!("e.value = '{value}'"))).await;
    let shown = format!("window.fovea.connects > {connects} && window.fovea.framesShown >= 1");
    wait_for(page, &shown, seconds).await;
}

/// Chooses H.264 in the codec menu (and `encoding` in the encoding menu, if any), waits until
/// an H.264 frame with `ready` true has arrived, and checks the page did not fall back to JPEG.
pub async fn choose_h264(page: &Page, encoding: Option<&str>, ready: &str) {
    eval(page, &change("codec", "e.value = 'h264'")).await;
    if let Some(encoding) = encoding {
        eval(
            page,
            &change("encoding", &format!("e.value = '{encoding}'")),
        )
        .await;
    }
    let js =
        format!("window.fovea.lastHeader && window.fovea.lastHeader.codec === 'h264' && ({ready})");
    wait_for(page, &js, 30).await;
    assert_eq!(
        eval(page, "window.fovea.codecNote").await,
        Value::Null,
        "no fallback to JPEG"
    );
}
