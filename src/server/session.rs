//! One WebSocket session: `hello` → `welcome`, then gaze in and frames out. Three parts:
//! [`Pacer`] decides when a frame is made (credits, coalescing, stalls; pure and unit-tested),
//! [`Connection`] reads and writes the socket on its own tasks, and [`frame_maker`] renders,
//! encodes and packs a frame. This file holds the session's own state (settings, prediction,
//! recording) and the loop that ties the three together.

use std::future::Future;
use std::pin::Pin;
use std::sync::Arc;
use std::time::{Duration, Instant};

use axum::extract::ws::{CloseFrame, WebSocket};

use super::connection::{Connection, Gone, Incoming, Outgoing};
use super::frame_maker::{self, FrameFailed, FrameJob, MadeFrame};
use super::pacing::Pacer;
use super::recorder::Recorder;
use super::timing::FrameTimes;
use super::ServerState;
use crate::encode::h264::{H264Config, H264Stream};
use crate::gaze::prediction::Predictor;
use crate::protocol::{
    ClientMessage, ErrorCode, Gaze, Hello, ProtocolError, ServerMessage, Welcome, PROTOCOL_VERSION,
};
use crate::render::FrameRequest;
use crate::settings::{KnobError, Preset, Settings};
use crate::viewing::Viewing;

type Making = Pin<Box<dyn Future<Output = Result<MadeFrame, FrameFailed>> + Send>>;

/// Far enough away to mean "never" for a disabled deadline.
const NEVER: Duration = Duration::from_secs(365 * 24 * 3600);

struct Session {
    id: u64,
    state: Arc<ServerState>,
    hello: Option<Hello>,
    settings: Settings,
    /// Last pupil diameter a sample carried.
    pupil_mm: Option<f64>,
    /// Exists from `hello` on.
    pacer: Option<Pacer>,
    started: Option<Instant>,
    predictor: Option<Predictor>,
    /// Gaze-to-frame-sent latency, smoothed: the prediction horizon when none is set.
    latency_ms: Option<f64>,
    recorder: Option<Recorder>,
    /// The camera as `camera` messages moved it; `None`: the scene's own.
    camera: Option<crate::scene::Camera>,
    /// Kinds of frame failure the client has been told of.
    failures_told: std::collections::HashSet<String>,
    /// The H.264 stream of an `h264` session: frames are encoded in order, one at a time.
    h264: Option<Arc<std::sync::Mutex<H264Stream>>>,
}

pub async fn run(socket: WebSocket, state: Arc<ServerState>, id: u64) {
    tracing::info!(session = id, "session opened");
    let mut conn = Connection::open(
        socket,
        state.limits.clone(),
        state.stall_timeout,
        state.ping_every,
        id,
    );
    let mut s = Session::new(id, state.clone());
    let mut making: Option<Making> = None;
    let mut sent = 0u64;
    let hello_by = tokio::time::Instant::now() + state.hello_timeout;
    let mut told_goodbye = false;
    let mut flush = tokio::time::interval(Duration::from_secs(1));
    let close = loop {
        if making.is_none() {
            if let Some(job) = s.next_job() {
                making = Some(Box::pin(frame_maker::make(state.render.clone(), job)));
            }
        }
        let stall = s
            .pacer
            .as_ref()
            .and_then(|p| p.stall_deadline(making.is_some()));
        let stall_at = tokio::time::Instant::from_std(stall.unwrap_or(Instant::now() + NEVER));
        let replies = tokio::select! {
            _ = state.closing.cancelled() => break Some(close_frame(1001, "server shutting down".into())),
            _ = state.drain_request.cancelled(), if !told_goodbye => {
                told_goodbye = true;
                let bye = super::drain::goodbye(id, state.drain_grace);
                vec![Outgoing::Text(ServerMessage::Goodbye(bye))]
            }
            _ = tokio::time::sleep_until(stall_at), if stall.is_some() => {
                ::metrics::counter!("fovea_sessions_stalled_total").increment(1);
                tracing::info!(session = id, "disconnecting a stalled client");
                let secs = state.stall_timeout.as_secs();
                break Some(close_frame(1008, format!("no frame acknowledged for {secs} s: disconnected")));
            }
            _ = tokio::time::sleep_until(hello_by), if s.hello.is_none() => {
                tracing::info!(session = id, "closing a socket that never said hello");
                let secs = state.hello_timeout.as_secs_f64();
                break Some(close_frame(1008, format!("no hello within {secs} s")));
            }
            _ = conn.gone.cancelled() => break None,
            _ = flush.tick(), if s.recorder.is_some() => {
                if let Some(r) = s.recorder.as_mut() {
                    r.flush();
                }
                Vec::new()
            }
            incoming = conn.incoming.recv() => match incoming {
                None => break None,
                Some(Incoming::Invalid(e)) => vec![Outgoing::Text(e.into())],
                Some(Incoming::Violation(code, reason)) => {
                    ::metrics::counter!("fovea_protocol_violations_total").increment(1);
                    break Some(close_frame(code, reason));
                }
                Some(Incoming::Message(m)) => s.on_message(m).map(Outgoing::Text).into_iter().collect(),
            },
            Some(times) = conn.sent.recv() => {
                sent += 1;
                s.frame_sent(&times);
                Vec::new()
            }
            made = async {
                match making.as_mut() {
                    Some(f) => f.await,
                    None => std::future::pending().await,
                }
            }, if making.is_some() => {
                making = None;
                s.frame_made(made)
            }
        };
        if send_all(&conn, replies).is_err() {
            tracing::debug!(session = id, "client is not reading: closing");
            break None;
        }
    };
    s.finish_recording();
    state.render.release(id);
    conn.close(close).await;
    let (samples, coalesced) = s
        .pacer
        .as_ref()
        .map_or((0, 0), |p| (p.samples, p.coalesced));
    tracing::info!(
        session = id,
        frames = sent,
        samples,
        coalesced,
        "session closed"
    );
}

fn close_frame(code: u16, reason: String) -> CloseFrame {
    CloseFrame {
        code,
        reason: reason.into(),
    }
}

/// Queues the replies; counts the errors among them.
fn send_all(conn: &Connection, replies: Vec<Outgoing>) -> Result<(), Gone> {
    for reply in replies {
        if let Outgoing::Text(ServerMessage::Error(e)) = &reply {
            let code = serde_json::to_value(e.code)
                .ok()
                .and_then(|v| v.as_str().map(str::to_string))
                .unwrap_or_default();
            ::metrics::counter!("fovea_errors_total", "code" => code).increment(1);
        }
        conn.send(reply)?;
    }
    Ok(())
}

impl Session {
    fn new(id: u64, state: Arc<ServerState>) -> Session {
        let recorder = state.record_dir.as_ref().and_then(|dir| {
            Recorder::create(dir, id, state.record_max_bytes, state.record_quota.clone())
                .map_err(|e| {
                    tracing::warn!(session = id, "cannot record gaze to {}: {e}", dir.display())
                })
                .ok()
        });
        Session {
            id,
            state,
            hello: None,
            settings: Settings::default(),
            pupil_mm: None,
            pacer: None,
            started: None,
            predictor: None,
            latency_ms: None,
            recorder,
            camera: None,
            failures_told: Default::default(),
            h264: None,
        }
    }

    /// Handles one client message; returns the reply to send, if any.
    fn on_message(&mut self, msg: ClientMessage) -> Option<ServerMessage> {
        let now = Instant::now();
        if let ClientMessage::Hello(hello) = msg {
            return Some(self.on_hello(hello, now));
        }
        let Some(pacer) = self.pacer.as_mut() else {
            let what = match msg {
                ClientMessage::Gaze(_) => "gaze",
                ClientMessage::Settings(_) => "settings",
                ClientMessage::Camera(_) => "camera",
                _ => "ack",
            };
            return Some(error(
                ErrorCode::NoHello,
                format!("send hello before {what}"),
            ));
        };
        let before = self.settings.clone();
        match msg {
            ClientMessage::Hello(_) => None,
            ClientMessage::Gaze(gaze) => {
                let o = pacer.on_gaze(gaze, now);
                ::metrics::counter!("fovea_gaze_samples_total").increment(1);
                if o.coalesced {
                    ::metrics::counter!("fovea_gaze_coalesced_total").increment(1);
                }
                if o.skipped {
                    ::metrics::counter!("fovea_frames_skipped_total").increment(1);
                }
                self.on_gaze(&gaze)
            }
            ClientMessage::Settings(patch) => match self.settings.apply(&patch) {
                Ok(()) => {
                    let hello = self.hello.as_ref()?;
                    let probe = cost_probe(hello, &self.settings, self.id);
                    let label = self.settings.label();
                    if let Err(e) = super::admission::check(&self.state, &probe, &label) {
                        // Refused: the session goes on as it was.
                        self.settings = before;
                        return Some(error(e.code, e.message));
                    }
                    pacer.on_settings(now);
                    let preset = self.settings.label();
                    tracing::debug!(session = self.id, %preset, "settings changed");
                    None
                }
                Err(e) => Some(knob_error(e)),
            },
            ClientMessage::Keyframe => {
                // Every JPEG or PNG frame is a keyframe already. The new frame shows the last
                // gaze again, as after a settings change.
                if let Some(Ok(mut stream)) = self.h264.as_ref().map(|s| s.lock()) {
                    stream.ask_keyframe();
                    pacer.on_settings(now);
                }
                None
            }
            ClientMessage::Camera(m) => {
                let scene = self.hello.as_ref().map(|h| h.scene.as_str()).unwrap_or("");
                let base = self.state.cameras.get(scene).copied()?;
                match super::camera::moved(base, self.camera.unwrap_or(base), &m) {
                    Ok(c) => {
                        self.camera = Some(c);
                        pacer.on_settings(now);
                        None
                    }
                    Err(message) => Some(error(ErrorCode::OutOfRange, message)),
                }
            }
            ClientMessage::Ack(ack) => match pacer.on_ack(ack.frame, now) {
                Ok(()) => {
                    tracing::trace!(
                        session = self.id,
                        frame = ack.frame,
                        dropped = ack.dropped,
                        "ack"
                    );
                    None
                }
                Err(made) => Some(error(
                    ErrorCode::BadAck,
                    format!(
                        "frame {} is not awaiting an ack (sent so far: {made})",
                        ack.frame
                    ),
                )),
            },
        }
    }

    /// Keeps the sample for prediction and the recording; an error once the recording stops.
    fn on_gaze(&mut self, gaze: &Gaze) -> Option<ServerMessage> {
        if gaze.pupil_mm.is_some() {
            self.pupil_mm = gaze.pupil_mm;
        }
        if let Some(p) = self.predictor.as_mut() {
            p.push(gaze.t_ms, [gaze.x, gaze.y]);
        }
        use super::recorder::Wrote;
        let why = match self.recorder.as_mut().map(|r| r.write(gaze)) {
            Some(Wrote::LimitReached) => format!(
                "this session's recording reached {} MiB",
                self.state.record_max_bytes / (1024 * 1024)
            ),
            Some(Wrote::FolderFull) => "the server's recording folder is at its limit".into(),
            _ => return None,
        };
        tracing::info!(session = self.id, "recording stopped: {why}");
        Some(error(
            ErrorCode::RecordingStopped,
            format!("{why} and stopped; the session goes on"),
        ))
    }

    fn on_hello(&mut self, hello: Hello, now: Instant) -> ServerMessage {
        if self.hello.is_some() {
            return error(
                ErrorCode::AlreadyStarted,
                "this session already said hello; open a new socket to start over".into(),
            );
        }
        let state = &self.state;
        let Some(scene) = state.scenes.iter().find(|s| s.name == hello.scene) else {
            let names: Vec<&str> = state.scenes.iter().map(|s| s.name.as_str()).collect();
            let message = format!(
                "unknown scene {:?}; available: {}",
                hello.scene,
                names.join(", ")
            );
            return error(ErrorCode::UnknownScene, message);
        };
        let Some(preset) = Preset::from_name(&hello.preset) else {
            return knob_error(KnobError::UnknownPreset(hello.preset.clone()));
        };
        let probe = cost_probe(&hello, &Settings::of(preset), self.id);
        if let Err(e) = super::admission::check(state, &probe, preset.name()) {
            tracing::info!(session = self.id, "hello refused: {}", e.message);
            return error(e.code, e.message);
        }
        tracing::info!(session = self.id, scene = %hello.scene, w = hello.width, h = hello.height, codec = ?hello.codec, "session started");
        let welcome = Welcome {
            v: PROTOCOL_VERSION,
            session: self.id,
            scene: scene.clone(),
            scenes: state.scenes.iter().map(|s| s.name.clone()).collect(),
            presets: Preset::ALL.iter().map(|p| p.to_string()).collect(),
            width: hello.width,
            height: hello.height,
            codec: hello.codec,
            max_in_flight: hello.max_in_flight,
            limits: state.limits.clone(),
            adapter: state.render.adapter().to_string(),
            version: env!("CARGO_PKG_VERSION").to_string(),
            recording: self.recorder.as_ref().map(|r| {
                let (partial, done) = r.paths();
                state.recordings.register(self.id, partial, done)
            }),
        };
        let viewing = Viewing::new(hello.display, hello.width, hello.height);
        self.predictor = Some(Predictor::new(viewing.field_of_view_deg()));
        self.h264 = (hello.codec == crate::protocol::Codec::H264).then(|| {
            let defaults = H264Config::default();
            Arc::new(std::sync::Mutex::new(H264Stream::new(H264Config {
                kbps: hello.bitrate_kbps.unwrap_or(defaults.kbps),
                keyframe_every: hello
                    .keyframe_s
                    .map_or(defaults.keyframe_every, Duration::from_secs_f64),
            })))
        });
        self.pacer = Some(Pacer::new(hello.max_in_flight, state.stall_timeout, now));
        self.settings = Settings::of(preset);
        self.started = Some(now);
        self.hello = Some(hello);
        ServerMessage::Welcome(welcome)
    }

    /// The next frame to make, if the pacer has one: the request for where the eye is (or,
    /// with prediction, will be).
    fn next_job(&mut self) -> Option<FrameJob> {
        let hello = self.hello.as_ref()?;
        let ticket = self.pacer.as_mut()?.next_frame()?;
        let mut request = FrameRequest::new(&hello.scene, hello.width, hello.height);
        let raw = ticket
            .gaze
            .map(|g| [g.x as f32, g.y as f32])
            .unwrap_or([0.5, 0.5]);
        request.gaze = raw;
        let session = self.settings.session;
        if session.prediction && ticket.gaze.is_some() {
            let horizon = match session.prediction_horizon_ms {
                h if h > 0.0 => f64::from(h),
                _ => self.latency_ms.unwrap_or(0.0),
            };
            if let Some([x, y]) = self.predictor.as_ref().and_then(|p| p.predict(horizon)) {
                // The frame is drawn for where the eye will be, within the frame.
                request.gaze = [x.clamp(0.0, 1.0) as f32, y.clamp(0.0, 1.0) as f32];
            }
        }
        request.marker = true;
        request.pupil_mm = self
            .pupil_mm
            .map(|p| p as f32)
            .unwrap_or(crate::render::DEFAULT_PUPIL_MM);
        request.display = hello.display;
        request.settings = self.settings.render.clone();
        request.camera = self.camera;
        request.stream = self.id;
        request.time_s = self.started.map_or(0.0, |t| t.elapsed().as_secs_f64());
        Some(FrameJob::new(
            ticket,
            raw,
            request,
            hello,
            self.h264.clone(),
        ))
    }

    /// A frame is ready (queue it for the socket) or failed (return its credit, tell the client).
    fn frame_made(&mut self, made: Result<MadeFrame, FrameFailed>) -> Vec<Outgoing> {
        match made {
            Ok(f) => {
                if let Some(p) = self.pacer.as_mut() {
                    p.frame_out(Instant::now());
                }
                vec![Outgoing::Frame(f.bytes, f.times)]
            }
            Err(f) => {
                if let Some(p) = self.pacer.as_mut() {
                    p.frame_failed(f.frame);
                }
                ::metrics::counter!("fovea_frames_failed_total").increment(1);
                if !frame_maker::first_of_its_kind(&mut self.failures_told, &f.error.message) {
                    tracing::debug!(session = self.id, "frame failed again: {}", f.error.message);
                    return Vec::new();
                }
                tracing::warn!(session = self.id, "frame failed: {}", f.error.message);
                vec![Outgoing::Text(f.error.into())]
            }
        }
    }

    /// The writer handed a frame to the socket: metrics, logs and the latency estimate all
    /// come from its one timing record.
    fn frame_sent(&mut self, times: &FrameTimes) {
        times.record_metrics();
        let s = times.stages();
        tracing::debug!(
            session = self.id,
            queue_ms = s.queue,
            render_ms = s.render,
            readback_ms = s.readback,
            encode_ms = s.encode,
            send_ms = times.send_ms(),
            "frame sent"
        );
        if let Some(ms) = times.total_ms().filter(|_| times.answers_gaze()) {
            self.latency_ms = Some(self.latency_ms.map_or(ms, |l| 0.8 * l + 0.2 * ms));
        }
        if let (Some(p), Some(at)) = (self.pacer.as_mut(), times.sent) {
            p.frame_out(at);
        }
    }

    fn finish_recording(&mut self) {
        if let Some(r) = self.recorder.take() {
            match r.finish() {
                Ok(path) => {
                    tracing::info!(session = self.id, "gaze recorded to {}", path.display())
                }
                Err(e) => tracing::warn!(session = self.id, "gaze recording failed: {e}"),
            }
        }
    }
}

/// What decides a frame's cost (size, settings), for admission.
fn cost_probe(hello: &Hello, settings: &Settings, id: u64) -> FrameRequest {
    FrameRequest {
        settings: settings.render.clone(),
        stream: id,
        ..FrameRequest::new(&hello.scene, hello.width, hello.height)
    }
}

fn error(code: ErrorCode, message: String) -> ServerMessage {
    ProtocolError::new(code, message).into()
}

fn knob_error(e: KnobError) -> ServerMessage {
    ProtocolError::from(e).into()
}
