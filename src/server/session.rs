//! One WebSocket session: `hello` → `welcome`, then gaze in and frames out, paced by credits.
//!
//! Only the newest gaze sample matters: samples that arrive while a frame is being made are
//! coalesced into the next one, never queued. A frame is made when there is something new to
//! show and the client has a free credit (`max_in_flight` minus frames not yet acknowledged),
//! so a slow client simply gets fewer frames.

use std::collections::BTreeSet;
use std::future::Future;
use std::pin::Pin;
use std::sync::Arc;
use std::time::Instant;

use axum::extract::ws::{CloseFrame, Message, WebSocket};
use futures_util::{SinkExt, StreamExt};

use super::recorder::Recorder;
use super::ServerState;
use crate::encode;
use crate::gaze::prediction::Predictor;
use crate::protocol::{
    encode_frame, parse_client_message, ClientMessage, ErrorCode, FrameHeader, Gaze, GazeUsed,
    Hello, ProtocolError, ServerMessage, SolveProgress, StageTimes, Welcome, PROTOCOL_VERSION,
};
use crate::render::FrameRequest;
use crate::settings::{Preset, Settings};
use crate::viewing::Viewing;

/// A frame being made: everything needed to render it and to write its header.
struct FrameJob {
    frame: u64,
    gaze: Option<Gaze>,
    /// The sample's own position when prediction moved the gaze.
    raw: Option<[f32; 2]>,
    samples: u64,
    /// When the gaze sample (or the hello, for the first frame) arrived.
    arrived: Instant,
    request: FrameRequest,
    hello: Hello,
}

/// The frame's bytes and when its gaze sample arrived.
type Making = Pin<Box<dyn Future<Output = Result<(Vec<u8>, Instant), ProtocolError>> + Send>>;

#[derive(Default)]
struct Session {
    hello: Option<Hello>,
    settings: Settings,
    /// Last pupil diameter a sample carried.
    pupil_mm: Option<f64>,
    /// Newest gaze sample not yet rendered, with its arrival time.
    latest: Option<(Gaze, Instant)>,
    /// The last sample rendered (kept so a new frame can be made without a new sample).
    shown: Option<Gaze>,
    /// Something changed since the last frame started (a new sample, or the session began).
    dirty: bool,
    hello_at: Option<Instant>,
    frames_made: u64,
    /// Frames sent (or being made) and not yet acknowledged: each holds one credit.
    unacked: BTreeSet<u64>,
    samples: u64,
    coalesced: u64,
    predictor: Option<Predictor>,
    /// Gaze-to-frame-sent latency, smoothed: the prediction horizon when none is set.
    latency_ms: Option<f64>,
    recorder: Option<Recorder>,
}

pub async fn run(socket: WebSocket, state: Arc<ServerState>, id: u64) {
    tracing::info!(session = id, "session opened");
    let (mut tx, mut rx) = socket.split();
    let mut s = Session::default();
    if let Some(dir) = &state.record_dir {
        match Recorder::create(dir, id) {
            Ok(r) => s.recorder = Some(r),
            Err(e) => tracing::warn!(session = id, "cannot record gaze to {}: {e}", dir.display()),
        }
    }
    let mut making: Option<Making> = None;
    let mut sent = 0u64;
    // Last sign of life while frames are outstanding (an ack, or sending a frame).
    let mut last_progress = Instant::now();
    let close = loop {
        if making.is_none() {
            if let Some(job) = s.next_job(id) {
                making = Some(Box::pin(make_frame(state.clone(), job)));
            }
        }
        let mut replies: Vec<Message> = Vec::new();
        let stalled = !s.unacked.is_empty() && making.is_none();
        let stall_at = tokio::time::Instant::from_std(last_progress + state.stall_timeout);
        tokio::select! {
            _ = state.shutdown.cancelled() => {
                break Some(CloseFrame { code: 1001, reason: "server shutting down".into() });
            }
            _ = tokio::time::sleep_until(stall_at), if stalled => {
                ::metrics::counter!("fovea_sessions_stalled_total").increment(1);
                tracing::info!(session = id, "disconnecting a stalled client");
                let reason = format!("no frame acknowledged for {} s: disconnected", state.stall_timeout.as_secs());
                break Some(CloseFrame { code: 1008, reason: reason.into() });
            }
            msg = rx.next() => match msg {
                None => break None,
                Some(Err(e)) => {
                    tracing::debug!(session = id, "socket error: {e}");
                    break None;
                }
                Some(Ok(Message::Close(_))) => break None,
                Some(Ok(Message::Text(text))) => {
                    let unacked = s.unacked.len();
                    if let Some(reply) = s.on_text(text.as_str(), &state, id) {
                        if let ServerMessage::Error(e) = &reply {
                            let code = serde_json::to_value(e.code).ok().and_then(|v| v.as_str().map(str::to_string)).unwrap_or_default();
                            ::metrics::counter!("fovea_errors_total", "code" => code).increment(1);
                        }
                        replies.push(Message::Text(reply.to_json().into()));
                    }
                    if s.unacked.len() < unacked {
                        last_progress = Instant::now();
                    }
                }
                Some(Ok(Message::Binary(_))) => {
                    let e = ProtocolError::new(ErrorCode::UnexpectedBinary, "clients send JSON text messages only");
                    replies.push(Message::Text(ServerMessage::from(e).to_json().into()));
                }
                Some(Ok(Message::Ping(_) | Message::Pong(_))) => {}
            },
            made = async { making.as_mut().expect("guarded by the select condition").await }, if making.is_some() => {
                making = None;
                match made {
                    Ok((bytes, arrived)) => {
                        sent += 1;
                        replies.push(Message::Binary(bytes.into()));
                        let ms = arrived.elapsed().as_secs_f64() * 1e3;
                        s.latency_ms = Some(s.latency_ms.map_or(ms, |l| 0.8 * l + 0.2 * ms));
                        last_progress = Instant::now();
                    }
                    Err(e) => {
                        // The frame is gone: give its credit back so the session does not stall.
                        if let Some(last) = s.unacked.last().copied() {
                            s.unacked.remove(&last);
                        }
                        tracing::warn!(session = id, "frame failed: {}", e.message);
                        ::metrics::counter!("fovea_frames_failed_total").increment(1);
                        replies.push(Message::Text(ServerMessage::from(e).to_json().into()));
                    }
                }
            }
        }
        for reply in replies {
            let frame = matches!(reply, Message::Binary(_));
            let started = Instant::now();
            // A client that stops reading fills its socket; it may not hold the session forever.
            let send = tokio::time::timeout(state.stall_timeout, tx.send(reply));
            let sent_ok = matches!(
                tracing::Instrument::instrument(
                    send,
                    tracing::debug_span!("send", session = id, frame)
                )
                .await,
                Ok(Ok(()))
            );
            if frame && sent_ok {
                ::metrics::counter!("fovea_frames_sent_total").increment(1);
                super::metrics::stage("send", started.elapsed().as_secs_f64() * 1e3);
            }
            if !sent_ok {
                tracing::debug!(session = id, "client went away while we were sending");
                s.finish_recording(id);
                state.render.release(id);
                return;
            }
        }
    };
    if let Some(frame) = close {
        let _ = tx.send(Message::Close(Some(frame))).await;
    }
    s.finish_recording(id);
    state.render.release(id);
    tracing::info!(
        session = id,
        frames = sent,
        samples = s.samples,
        coalesced = s.coalesced,
        "session closed"
    );
}

impl Session {
    /// Handles one text message; returns the reply to send, if any.
    fn on_text(&mut self, text: &str, state: &ServerState, id: u64) -> Option<ServerMessage> {
        let msg = match parse_client_message(text, &state.limits) {
            Ok(m) => m,
            Err(e) => {
                tracing::debug!(session = id, code = ?e.code, "bad message: {}", e.message);
                return Some(e.into());
            }
        };
        match msg {
            ClientMessage::Hello(hello) => Some(self.on_hello(hello, state, id)),
            ClientMessage::Gaze(gaze) => {
                if self.hello.is_none() {
                    return Some(no_hello("gaze"));
                }
                self.samples += 1;
                ::metrics::counter!("fovea_gaze_samples_total").increment(1);
                if self.latest.is_some() {
                    self.coalesced += 1;
                    ::metrics::counter!("fovea_gaze_coalesced_total").increment(1);
                    let max = self
                        .hello
                        .as_ref()
                        .map(|h| h.max_in_flight as usize)
                        .unwrap_or(0);
                    if self.unacked.len() >= max {
                        // The client has no credit: this sample's frame is skipped, not queued.
                        ::metrics::counter!("fovea_frames_skipped_total").increment(1);
                    }
                }
                self.latest = Some((gaze, Instant::now()));
                if gaze.pupil_mm.is_some() {
                    self.pupil_mm = gaze.pupil_mm;
                }
                if let Some(p) = self.predictor.as_mut() {
                    p.push(gaze.t_ms, [gaze.x, gaze.y]);
                }
                if let Some(r) = self.recorder.as_mut() {
                    r.write(&gaze);
                }
                self.dirty = true;
                None
            }
            ClientMessage::Settings(patch) => {
                if self.hello.is_none() {
                    return Some(no_hello("settings"));
                }
                if let Err(e) = self.settings.apply(&patch) {
                    let code = match e {
                        crate::settings::KnobError::UnknownPreset(_) => ErrorCode::UnknownPreset,
                        crate::settings::KnobError::NotFinite { .. } => ErrorCode::NotFinite,
                        crate::settings::KnobError::OutOfRange { .. } => ErrorCode::OutOfRange,
                    };
                    return Some(ProtocolError::new(code, e.to_string()).into());
                }
                tracing::debug!(session = id, preset = %self.settings.label(), "settings changed");
                self.dirty = true;
                None
            }
            ClientMessage::Ack(ack) => {
                if self.hello.is_none() {
                    return Some(no_hello("ack"));
                }
                if self.unacked.remove(&ack.frame) {
                    None
                } else {
                    Some(
                        ProtocolError::new(
                            ErrorCode::BadAck,
                            format!(
                                "frame {} is not awaiting an ack (sent so far: {})",
                                ack.frame, self.frames_made
                            ),
                        )
                        .into(),
                    )
                }
            }
        }
    }

    fn on_hello(&mut self, hello: Hello, state: &ServerState, id: u64) -> ServerMessage {
        if self.hello.is_some() {
            return ProtocolError::new(
                ErrorCode::AlreadyStarted,
                "this session already said hello; open a new socket to start over",
            )
            .into();
        }
        let Some(scene) = state.scenes.iter().find(|s| s.name == hello.scene) else {
            let names: Vec<&str> = state.scenes.iter().map(|s| s.name.as_str()).collect();
            return ProtocolError::new(
                ErrorCode::UnknownScene,
                format!(
                    "unknown scene {:?}; available: {}",
                    hello.scene,
                    names.join(", ")
                ),
            )
            .into();
        };
        let Some(preset) = Preset::from_name(&hello.preset) else {
            return unknown_preset(&hello.preset);
        };
        let settings = Settings::of(preset);
        tracing::info!(session = id, scene = %hello.scene, w = hello.width, h = hello.height, codec = ?hello.codec, "session started");
        let welcome = Welcome {
            v: PROTOCOL_VERSION,
            session: id,
            scene: scene.clone(),
            scenes: state.scenes.iter().map(|s| s.name.clone()).collect(),
            presets: Preset::ALL.iter().map(|p| p.to_string()).collect(),
            width: hello.width,
            height: hello.height,
            codec: hello.codec,
            max_in_flight: hello.max_in_flight,
            limits: state.limits.clone(),
            adapter: state.render.adapter().to_string(),
        };
        let viewing = Viewing::new(hello.display, hello.width, hello.height);
        self.predictor = Some(Predictor::new(viewing.field_of_view_deg()));
        self.hello = Some(hello);
        self.settings = settings;
        self.hello_at = Some(Instant::now());
        self.dirty = true; // the first frame shows the scene before any gaze arrives
        ServerMessage::Welcome(welcome)
    }

    /// The next frame to make, if there is something new and a credit to spend on it.
    fn next_job(&mut self, stream: u64) -> Option<FrameJob> {
        let hello = self.hello.as_ref()?;
        if !self.dirty || self.unacked.len() >= hello.max_in_flight as usize {
            return None;
        }
        let (gaze, arrived) = match self.latest.take() {
            Some((g, at)) => (Some(g), at),
            None => (self.shown, self.hello_at.unwrap_or_else(Instant::now)),
        };
        self.shown = gaze;
        self.dirty = false;
        self.frames_made += 1;
        self.unacked.insert(self.frames_made);
        let mut request = FrameRequest::new(&hello.scene, hello.width, hello.height);
        let raw = gaze.map(|g| [g.x as f32, g.y as f32]).unwrap_or([0.5, 0.5]);
        request.gaze = raw;
        let mut predicted = false;
        if self.settings.session.prediction && gaze.is_some() {
            let horizon = match self.settings.session.prediction_horizon_ms {
                h if h > 0.0 => f64::from(h),
                _ => self.latency_ms.unwrap_or(0.0),
            };
            if let Some([x, y]) = self.predictor.as_ref().and_then(|p| p.predict(horizon)) {
                // The frame is drawn for where the eye will be, within the frame.
                request.gaze = [x.clamp(0.0, 1.0) as f32, y.clamp(0.0, 1.0) as f32];
                predicted = request.gaze != raw;
            }
        }
        request.marker = true;
        request.pupil_mm = self
            .pupil_mm
            .map(|p| p as f32)
            .unwrap_or(crate::render::DEFAULT_PUPIL_MM);
        request.display = hello.display;
        request.settings = self.settings.render.clone();
        request.stream = stream;
        request.time_s = self
            .hello_at
            .map(|t| t.elapsed().as_secs_f64())
            .unwrap_or(0.0);
        Some(FrameJob {
            frame: self.frames_made,
            gaze,
            raw: predicted.then_some(raw),
            samples: self.samples,
            arrived,
            request,
            hello: hello.clone(),
        })
    }
}

impl Session {
    fn finish_recording(&mut self, id: u64) {
        if let Some(r) = self.recorder.take() {
            match r.finish() {
                Ok(path) => tracing::info!(session = id, "gaze recorded to {}", path.display()),
                Err(e) => tracing::warn!(session = id, "gaze recording failed: {e}"),
            }
        }
    }
}

fn unknown_preset(name: &str) -> ServerMessage {
    ProtocolError::new(
        ErrorCode::UnknownPreset,
        format!("unknown preset {name:?}; available: {}", Preset::names()),
    )
    .into()
}

fn no_hello(what: &str) -> ServerMessage {
    ProtocolError::new(ErrorCode::NoHello, format!("send hello before {what}")).into()
}

/// Renders on the render thread, encodes on the blocking pool, and packs the binary message.
async fn make_frame(
    state: Arc<ServerState>,
    job: FrameJob,
) -> Result<(Vec<u8>, Instant), ProtocolError> {
    let failed = |what: &str, e: &dyn std::fmt::Display| {
        ProtocolError::new(
            ErrorCode::RenderFailed,
            format!("frame {}: {what}: {e}", job.frame),
        )
    };
    let before_queue = Instant::now();
    let rendered = state
        .render
        .render(job.request.clone())
        .await
        .map_err(|e| failed("render", &e))?;
    ::metrics::counter!("fovea_frames_rendered_total").increment(1);
    let queue = (before_queue - job.arrived).as_secs_f64() * 1e3 + rendered.queue_ms;
    let frame = rendered.frame;
    let (codec, quality) = (job.hello.codec, job.hello.quality);
    let (w, h) = (frame.width, frame.height);
    let (render_ms, readback_ms, sampled) = (frame.render_ms, frame.readback_ms, frame.sampled);
    let passes_ms = frame.passes_ms;
    let radiosity = frame.radiosity.map(|p| SolveProgress {
        shots: p.shots,
        elements: p.elements,
        unshot: p.unshot,
        converged: p.converged,
    });
    let rgba = frame.rgba;
    let frame_no = job.frame;
    let encoded = tokio::task::spawn_blocking(move || {
        let _span = tracing::debug_span!("encode", frame = frame_no).entered();
        let started = Instant::now();
        encode::encode(&rgba, w, h, codec, quality).map(|bytes| (bytes, started.elapsed()))
    })
    .await
    .map_err(|e| failed("encoder task", &e))?;
    let (image, encode_time) = encoded.map_err(|e| failed("encode", &e))?;
    let [x, y] = job.request.gaze;
    super::metrics::stage("queue", queue);
    super::metrics::stage("render", render_ms);
    super::metrics::stage("readback", readback_ms);
    super::metrics::stage("encode", encode_time.as_secs_f64() * 1e3);
    let header = FrameHeader {
        frame: job.frame,
        seq: job.gaze.map(|g| g.seq),
        t_ms: job.gaze.map(|g| g.t_ms),
        gaze: GazeUsed {
            x: f64::from(x),
            y: f64::from(y),
        },
        raw_gaze: job.raw.map(|[x, y]| GazeUsed {
            x: f64::from(x),
            y: f64::from(y),
        }),
        width: w,
        height: h,
        codec,
        sampled,
        samples: job.samples,
        stages_ms: StageTimes {
            queue,
            render: render_ms,
            readback: readback_ms,
            encode: encode_time.as_secs_f64() * 1e3,
        },
        passes_ms,
        radiosity,
    };
    Ok((encode_frame(&header, &image), job.arrived))
}
