//! `fovea load`: N concurrent sessions driven by the synthetic eye against a server for a fixed
//! time, each acknowledging frames like a real client, measuring gaze-to-frame-received latency
//! on its own clock and the server's stage breakdown from the headers. Histograms are HDR
//! (microsecond resolution), never averages.

use std::collections::BTreeMap;
use std::sync::{Arc, Mutex};
use std::time::{Duration, Instant};

use hdrhistogram::Histogram;
use serde::Serialize;

use super::link::LinkEvent;
use super::ClientError;

use crate::gaze::synthetic::{degrees_to_frame, SyntheticEye};
use crate::protocol::{Codec, Hello, Trigger};
use crate::viewing::Viewing;

#[derive(Debug, Clone)]
pub struct LoadOptions {
    pub url: String,
    /// Sent as `Authorization: Bearer …`.
    pub token: Option<String>,
    pub sessions: usize,
    pub duration: Duration,
    /// Delay between session starts.
    pub ramp_up: Duration,
    /// Gaze samples per second per session.
    pub rate_hz: f64,
    pub hello: Hello,
    pub seed: u32,
    /// Drive sessions with this recording (looped, each session from a different offset)
    /// instead of the synthetic eye.
    pub recording: Option<std::sync::Arc<Vec<crate::gaze::Sample>>>,
    /// Session i asks for codec i mod n (empty: `hello.codec` for all), so codecs are
    /// compared in one run, on one server, under the same render noise.
    pub codecs: Vec<Codec>,
}

/// One codec's share of a run (`LoadReport::by_codec`).
#[derive(Debug, Clone, Serialize)]
pub struct CodecStats {
    pub sessions: usize,
    pub frames: u64,
    /// Gaze-to-frame-received, client clock.
    pub latency_ms: Percentiles,
    pub render_ms: Percentiles,
    pub encode_ms: Percentiles,
    /// Mean over this codec's sessions.
    pub kbit_s_per_session: f64,
}

#[derive(Debug, Clone, Copy, Serialize, PartialEq)]
pub struct Percentiles {
    pub count: u64,
    pub p50: f64,
    pub p90: f64,
    pub p95: f64,
    pub p99: f64,
    pub max: f64,
}

fn percentiles(h: &Histogram<u64>) -> Percentiles {
    let ms = |v: u64| v as f64 / 1000.0;
    Percentiles {
        count: h.len(),
        p50: ms(h.value_at_quantile(0.5)),
        p90: ms(h.value_at_quantile(0.9)),
        p95: ms(h.value_at_quantile(0.95)),
        p99: ms(h.value_at_quantile(0.99)),
        max: ms(h.max()),
    }
}

#[derive(Debug, Clone, Serialize)]
pub struct LoadReport {
    pub sessions: usize,
    pub seconds: f64,
    pub rate_hz: f64,
    pub frames: u64,
    pub fps_total: f64,
    pub fps_per_session: Vec<f64>,
    /// Image bitrate each session received, kbit/s, and all together.
    pub kbit_s_per_session: Vec<f64>,
    pub kbit_s_total: f64,
    pub fps_min: f64,
    pub fps_max: f64,
    /// Slowest session's fps over the fastest's (1 is perfectly fair).
    pub fairness: f64,
    /// Gaze-to-frame-received, client clock.
    pub latency_ms: Percentiles,
    /// Server stages from the frame headers, and the CDF points for plotting.
    pub stages_ms: BTreeMap<String, Percentiles>,
    pub gaze_sent: u64,
    /// Samples answered by no frame: coalesced into newer ones while frames were made (each is
    /// a frame the client would have wanted and the server skipped).
    pub samples_coalesced: u64,
    pub errors: u64,
    pub connection_failures: u64,
    /// The first connection failure's reason, if any.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub connection_error: Option<String>,
    /// Sessions the server refused (close 1013).
    pub refused: u64,
    /// New sessions opened after a server said goodbye or a connection dropped.
    pub reconnects: u64,
    /// From the last frame of a session to the first of its replacement, ms.
    pub reconnect_gap_ms: Option<Percentiles>,
    /// Sessions that ended before the run did (gave up reconnecting, closed by the server).
    pub sessions_ended_early: u64,
    /// The first such session's reason.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub ended_early_reason: Option<String>,
    /// Frames received per second of the run, all sessions together.
    pub fps_timeline: Vec<u64>,
    /// Per codec: latency, render and encode, bitrate (one entry unless codecs were mixed).
    pub by_codec: BTreeMap<String, CodecStats>,
    #[serde(skip)]
    pub histograms: BTreeMap<String, Histogram<u64>>,
}

#[derive(Default)]
struct SessionResult {
    codec: &'static str,
    frames: u64,
    /// Image bytes received (the frame headers' `bytes`).
    bytes: u64,
    answered: u64,
    active_s: f64,
    gaze_sent: u64,
    errors: u64,
    connect_failed: bool,
    /// Why the connection failed, when it did.
    connect_error: Option<String>,
    refused: bool,
    reconnects: u32,
    gaps_ms: Vec<f64>,
    /// Why the session ended before the run did, if it did.
    ended: Option<String>,
}

fn histogram() -> Histogram<u64> {
    // 1 µs to 60 s, 3 significant digits.
    Histogram::new_with_bounds(1, 60_000_000, 3)
        .unwrap_or_else(|_| Histogram::new(3).expect("valid sigfig"))
}

/// Runs the load and merges every session's measurements.
pub async fn run(
    opts: &LoadOptions,
    progress: impl Fn(usize, f64) + Send + Sync + 'static,
) -> LoadReport {
    let stage_names = ["latency", "queue", "render", "readback", "encode"];
    let hists: Arc<Mutex<BTreeMap<String, Histogram<u64>>>> = Arc::new(Mutex::new(
        stage_names
            .iter()
            .map(|n| (n.to_string(), histogram()))
            .collect(),
    ));
    let timeline = Arc::new(Mutex::new(vec![0u64; opts.duration.as_secs() as usize + 2]));
    let started = Instant::now();
    let deadline = started + opts.duration;
    let progress = Arc::new(progress);
    let mut tasks = Vec::new();
    for i in 0..opts.sessions {
        let mut opts = opts.clone();
        if let Some(c) = opts.codecs.get(i % opts.codecs.len().max(1)) {
            opts.hello.codec = *c;
        }
        let (hists, timeline, progress) = (hists.clone(), timeline.clone(), progress.clone());
        tasks.push(tokio::spawn(async move {
            tokio::time::sleep(opts.ramp_up * i as u32).await;
            session(i, &opts, deadline, started, hists, timeline, progress).await
        }));
    }
    let mut results = Vec::new();
    for t in tasks {
        results.push(t.await.unwrap_or_default());
    }
    let seconds = started.elapsed().as_secs_f64();
    let hists = hists.lock().map(|h| h.clone()).unwrap_or_default();
    let fps: Vec<f64> = results
        .iter()
        .filter(|r| !r.connect_failed && !r.refused)
        .map(|r| r.frames as f64 / r.active_s.max(1e-9))
        .collect();
    let (fps_min, fps_max) = fps
        .iter()
        .fold((f64::INFINITY, 0.0f64), |(a, b), v| (a.min(*v), b.max(*v)));
    let frames: u64 = results.iter().map(|r| r.frames).sum();
    let by_codec = by_codec(&results, &hists);
    let kbit_s: Vec<f64> = results
        .iter()
        .filter(|r| !r.connect_failed && !r.refused)
        .map(|r| r.bytes as f64 * 8.0 / 1000.0 / r.active_s.max(1e-9))
        .collect();
    LoadReport {
        kbit_s_total: results.iter().map(|r| r.bytes).sum::<u64>() as f64 * 8.0
            / 1000.0
            / seconds.max(1e-9),
        kbit_s_per_session: kbit_s,
        sessions: opts.sessions,
        seconds,
        rate_hz: opts.rate_hz,
        frames,
        fps_total: frames as f64 / seconds.max(1e-9),
        fairness: if fps_max > 0.0 {
            fps_min / fps_max
        } else {
            0.0
        },
        fps_min: if fps.is_empty() { 0.0 } else { fps_min },
        fps_max,
        fps_per_session: fps,
        latency_ms: percentiles(&hists["latency"]),
        stages_ms: hists
            .iter()
            .filter(|(k, _)| k.as_str() != "latency" && !k.contains('/'))
            .map(|(k, h)| (k.clone(), percentiles(h)))
            .collect(),
        gaze_sent: results.iter().map(|r| r.gaze_sent).sum(),
        samples_coalesced: results
            .iter()
            .map(|r| r.gaze_sent.saturating_sub(r.answered))
            .sum(),
        errors: results.iter().map(|r| r.errors).sum(),
        connection_failures: results.iter().filter(|r| r.connect_failed).count() as u64,
        connection_error: results.iter().find_map(|r| r.connect_error.clone()),
        refused: results.iter().filter(|r| r.refused).count() as u64,
        reconnects: results.iter().map(|r| u64::from(r.reconnects)).sum(),
        reconnect_gap_ms: {
            let mut h = histogram();
            for g in results.iter().flat_map(|r| &r.gaps_ms) {
                let _ = h.record((g * 1000.0).max(1.0) as u64);
            }
            (!h.is_empty()).then(|| percentiles(&h))
        },
        sessions_ended_early: results.iter().filter(|r| r.ended.is_some()).count() as u64,
        ended_early_reason: results.iter().find_map(|r| r.ended.clone()),
        fps_timeline: timeline.lock().map(|t| t.clone()).unwrap_or_default(),
        by_codec,
        histograms: hists,
    }
}

/// Each codec's sessions and its `codec/stage` histograms.
fn by_codec(
    results: &[SessionResult],
    hists: &BTreeMap<String, Histogram<u64>>,
) -> BTreeMap<String, CodecStats> {
    let mut groups: BTreeMap<&str, Vec<&SessionResult>> = BTreeMap::new();
    for r in results.iter().filter(|r| !r.connect_failed && !r.refused) {
        groups.entry(r.codec).or_default().push(r);
    }
    groups
        .into_iter()
        .map(|(codec, mine)| {
            let stage = |name: &str| {
                hists
                    .get(&format!("{codec}/{name}"))
                    .map_or_else(|| percentiles(&histogram()), percentiles)
            };
            let kbit_s: f64 = mine
                .iter()
                .map(|o| o.bytes as f64 * 8.0 / 1000.0 / o.active_s.max(1e-9))
                .sum();
            let stats = CodecStats {
                sessions: mine.len(),
                frames: mine.iter().map(|o| o.frames).sum(),
                latency_ms: stage("latency"),
                render_ms: stage("render"),
                encode_ms: stage("encode"),
                kbit_s_per_session: kbit_s / mine.len() as f64,
            };
            (codec.to_string(), stats)
        })
        .collect()
}

#[allow(clippy::too_many_arguments)]
async fn session(
    index: usize,
    opts: &LoadOptions,
    deadline: Instant,
    started: Instant,
    hists: Arc<Mutex<BTreeMap<String, Histogram<u64>>>>,
    timeline: Arc<Mutex<Vec<u64>>>,
    progress: Arc<impl Fn(usize, f64) + Send + Sync>,
) -> SessionResult {
    let mut result = SessionResult {
        codec: opts.hello.codec.name(),
        ..SessionResult::default()
    };
    let link = super::link::Link::open(super::link::LinkOptions {
        url: opts.url.clone(),
        token: opts.token.clone(),
        hello: opts.hello.clone(),
        reconnect: true,
    })
    .await;
    let (link, mut events) = match link {
        Ok((link, events, _)) => (link, events),
        Err(ClientError::ClosedWith(1013, _)) => {
            result.refused = true;
            return result;
        }
        Err(ClientError::Refused(..)) => {
            result.errors += 1;
            return result;
        }
        Err(e) => {
            result.connect_failed = true;
            result.connect_error = Some(e.to_string());
            return result;
        }
    };
    let session_start = Instant::now();
    let sent_at: Arc<Mutex<BTreeMap<u64, f64>>> = Arc::new(Mutex::new(BTreeMap::new()));
    let reader = {
        let (sent_at, hists, timeline) = (sent_at.clone(), hists.clone(), timeline.clone());
        tokio::spawn(async move {
            let (mut frames, mut errors, mut answered, mut bytes) = (0u64, 0u64, 0u64, 0u64);
            while let Some(event) = events.recv().await {
                let h = match event {
                    LinkEvent::Frame { header, .. } => header,
                    LinkEvent::Error(_) => {
                        errors += 1;
                        continue;
                    }
                };
                let now = session_start.elapsed().as_secs_f64() * 1e3;
                frames += 1;
                bytes += h.bytes as u64;
                answered += u64::from(h.seq.is_some());
                if let Ok(mut t) = timeline.lock() {
                    let s = started.elapsed().as_secs() as usize;
                    if let Some(slot) = t.get_mut(s) {
                        *slot += 1;
                    }
                }
                // Only a frame that answers a new sample measures gaze latency; one made for
                // the start or a settings change shows an older sample again.
                let answers_gaze = h.trigger == Trigger::Gaze;
                let latency = h
                    .seq
                    .filter(|_| answers_gaze)
                    .and_then(|s| sent_at.lock().ok().and_then(|m| m.get(&s).copied()))
                    .map(|t| now - t);
                if let Ok(mut hs) = hists.lock() {
                    let codec = h.codec.name();
                    let mut rec = |k: &str, ms: f64| {
                        let us = (ms * 1000.0).max(1.0) as u64;
                        if let Some(hh) = hs.get_mut(k) {
                            let _ = hh.record(us);
                        }
                        if matches!(k, "latency" | "render" | "encode") {
                            let per_codec =
                                hs.entry(format!("{codec}/{k}")).or_insert_with(histogram);
                            let _ = per_codec.record(us);
                        }
                    };
                    if let Some(l) = latency {
                        rec("latency", l);
                    }
                    if answers_gaze {
                        rec("queue", h.stages_ms.queue);
                    }
                    rec("render", h.stages_ms.render);
                    rec("readback", h.stages_ms.readback);
                    rec("encode", h.stages_ms.encode);
                }
            }
            (frames, errors, answered, bytes)
        })
    };
    let viewing = Viewing {
        width: opts.hello.width,
        height: opts.hello.height,
        width_cm: opts.hello.display.width_cm,
        distance_cm: opts.hello.display.distance_cm,
    };
    let mut eye = SyntheticEye::new(opts.seed.wrapping_add(index as u32), &viewing);
    let period = Duration::from_secs_f64(1.0 / opts.rate_hz.clamp(1.0, 10_000.0));
    let mut tick = tokio::time::interval(period);
    let mut seq = 0u64;
    // With a recording: loop it, each session starting a different share of the way in.
    let recording = opts.recording.as_ref().filter(|r| r.len() > 1);
    let span = recording
        .and_then(|r| r.last().map(|l| l.t_ms + 1.0))
        .unwrap_or(1.0);
    let offset = span * index as f64 / opts.sessions.max(1) as f64;
    let mut cursor = 0usize;
    while Instant::now() < deadline {
        let t = session_start.elapsed().as_secs_f64() * 1e3;
        let (xy, pupil) = match recording {
            Some(r) => {
                // The next sample at its recorded time (relative to this session's offset).
                let at = (offset + t) % span;
                if cursor >= r.len() || r[cursor].t_ms > at + 1.0 {
                    cursor = r.partition_point(|s| s.t_ms < at);
                }
                let Some(s) = r.get(cursor) else {
                    cursor = 0;
                    continue;
                };
                let wait = (s.t_ms - at).max(0.0);
                tokio::time::sleep(Duration::from_secs_f64(wait / 1000.0)).await;
                cursor += 1;
                (crate::gaze::sendable(s), s.pupil_mm)
            }
            None => {
                tick.tick().await;
                let (deg, pupil) = eye.step(t);
                (
                    deg.map(|d| degrees_to_frame(&viewing, d).map(|v| v.clamp(0.0, 1.0))),
                    pupil,
                )
            }
        };
        let Some([x, y]) = xy else { continue };
        let t = session_start.elapsed().as_secs_f64() * 1e3;
        seq += 1;
        if let Ok(mut m) = sent_at.lock() {
            m.insert(seq, t);
        }
        let pupil = pupil
            .map(|p| format!(r#","pupil_mm":{p}"#))
            .unwrap_or_default();
        if !link.send(format!(
            r#"{{"type":"gaze","seq":{seq},"t_ms":{t},"x":{x},"y":{y}{pupil}}}"#
        )) {
            break;
        }
        result.gaze_sent += 1;
        if index == 0 && seq.is_multiple_of((opts.rate_hz as u64).max(1)) {
            progress(opts.sessions, started.elapsed().as_secs_f64());
        }
    }
    let link = link.close().await;
    result.reconnects = link.reconnects;
    result.gaps_ms = link.gaps_ms;
    result.ended = link.ended;
    if let Ok(Ok((frames, errors, answered, bytes))) =
        tokio::time::timeout(Duration::from_secs(10), reader).await
    {
        result.frames = frames;
        result.bytes = bytes;
        result.errors += errors;
        result.answered = answered;
    }
    result.active_s = session_start.elapsed().as_secs_f64().min(
        deadline
            .saturating_duration_since(session_start)
            .as_secs_f64()
            .max(1e-3),
    );
    result
}
