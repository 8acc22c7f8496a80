//! `fovea replay`: a gaze recording streamed to a server at its recorded timing (scaled by a
//! speed factor, from a start offset, looped), frames acknowledged as they arrive, and one
//! record kept per frame.
//!
//! Samples the protocol cannot carry (track loss, blinks, far off-frame) are not sent; the
//! server keeps rendering for the last valid gaze (see `gaze::sendable`).

use std::sync::{Arc, Mutex};
use std::time::{Duration, Instant};

use serde::Serialize;

use super::link::{Link, LinkEvent, LinkOptions};
use super::ClientError;
use crate::gaze::{sendable, Sample};
use crate::protocol::Hello;

#[derive(Debug, Clone)]
pub struct ReplayOptions {
    pub url: String,
    /// Sent as `Authorization: Bearer …`.
    pub token: Option<String>,
    pub hello: Hello,
    /// 2 plays twice as fast.
    pub speed: f64,
    /// Recording time to start from, ms.
    pub start_ms: f64,
    /// How much of the recording to play (recording time), ms; None: to the end.
    pub duration_ms: Option<f64>,
    /// Play the selection this many times.
    pub loops: u32,
    /// Keep the encoded images of received frames.
    pub keep_images: bool,
    /// Cancelled to stop early (Ctrl-C): sending stops, the frames in flight are collected and
    /// the replay returns what it has, marked `interrupted`.
    pub stop: tokio_util::sync::CancellationToken,
}

/// One frame as the client saw it.
#[derive(Debug, Clone, Serialize)]
pub struct FrameRecord {
    pub frame: u64,
    /// Which session of the replay: 0, then one more per reconnect.
    pub connection: u32,
    pub seq: Option<u64>,
    /// The answered sample's time in the recording, ms.
    pub sample_t_ms: Option<f64>,
    /// When that sample was sent and when the frame arrived, ms since the replay began.
    pub sent_ms: Option<f64>,
    pub received_ms: f64,
    /// Gaze-to-frame-received latency on the client's clock.
    pub latency_ms: Option<f64>,
    pub gaze_x: f64,
    pub gaze_y: f64,
    pub queue_ms: f64,
    pub render_ms: f64,
    pub readback_ms: f64,
    pub encode_ms: f64,
    pub sampled: f64,
    pub bytes: usize,
    /// Gaze samples the server had received when it made this frame.
    pub server_samples: u64,
    /// H.264: whether the frame is a keyframe (the header says; none for other codecs).
    pub keyframe: Option<bool>,
    #[serde(skip)]
    pub image: Option<Vec<u8>>,
    /// What the image bytes are (`saved_frames` writes each as the file it is).
    #[serde(skip)]
    pub codec: crate::protocol::Codec,
    /// Inset frames of JPEG or PNG: the second image's length (the first is the base).
    #[serde(skip)]
    pub inset_bytes: Option<usize>,
}

#[derive(Debug, Clone, Serialize)]
pub struct ReplaySummary {
    pub samples_in_selection: usize,
    pub samples_sent: usize,
    /// Not sent: track loss, blinks, off-frame.
    pub samples_unsendable: usize,
    pub frames: usize,
    /// Samples the server received (from the last frame header, or the close).
    pub server_samples: u64,
    /// Sent but never received by the server (expected: zero).
    pub samples_lost: u64,
    /// Not delivered because no session was up (between a goodbye and the new session).
    pub samples_dropped_reconnecting: u64,
    /// New sessions opened after a goodbye or a dropped connection.
    pub reconnects: u32,
    /// Per reconnect: from the last frame of a session to the first of the next, ms.
    pub reconnect_gaps_ms: Vec<f64>,
    /// Why the replay stopped early, if it did.
    pub ended_early: Option<String>,
    /// Stopped by the user (Ctrl-C) before the selection was sent.
    pub interrupted: bool,
    /// Received but answered by no frame: coalesced into a newer sample (expected: many).
    pub samples_coalesced: u64,
    pub latency_p50_ms: f64,
    pub latency_p95_ms: f64,
    pub latency_p99_ms: f64,
    pub seconds: f64,
    /// Image bytes received, and their rate over the replay, kbit/s.
    pub bytes: u64,
    pub kbit_s: f64,
    /// H.264: the keyframes received and their bytes (of `bytes`); 0 for other codecs.
    pub keyframes: u64,
    pub keyframe_bytes: u64,
    /// What the server granted, for the provenance of the figures.
    pub server: ServerInfo,
}

/// The server side of a replay's provenance, from its welcome.
#[derive(Debug, Clone, Serialize)]
pub struct ServerInfo {
    pub version: String,
    pub adapter: String,
    pub scene: String,
    pub width: u32,
    pub height: u32,
    pub codec: crate::protocol::Codec,
}

/// When each sample is sent (ms after the replay starts) and its index: recording time from
/// `start_ms`, divided by `speed`, the selection repeated `loops` times back to back.
pub fn schedule(
    samples: &[Sample],
    speed: f64,
    start_ms: f64,
    duration_ms: Option<f64>,
    loops: u32,
) -> Vec<(f64, usize)> {
    let speed = sane_speed(speed);
    let end = duration_ms.map(|d| start_ms + d).unwrap_or(f64::INFINITY);
    let selected: Vec<usize> = (0..samples.len())
        .filter(|&i| samples[i].t_ms >= start_ms && samples[i].t_ms < end)
        .collect();
    let Some((&first, &last)) = selected.first().zip(selected.last()) else {
        return Vec::new();
    };
    // One loop lasts from the first selected sample to one sample period past the last.
    let period = if selected.len() > 1 {
        (samples[last].t_ms - samples[first].t_ms) / (selected.len() - 1) as f64
    } else {
        0.0
    };
    let span = samples[last].t_ms - samples[first].t_ms + period;
    let mut out = Vec::with_capacity(selected.len() * loops as usize);
    for l in 0..loops.max(1) {
        for &i in &selected {
            out.push((
                (samples[i].t_ms - samples[first].t_ms + f64::from(l) * span) / speed,
                i,
            ));
        }
    }
    out
}

/// A usable speed factor: a finite positive one, else 1.
fn sane_speed(speed: f64) -> f64 {
    if speed.is_finite() && speed > 0.0 {
        speed
    } else {
        1.0
    }
}

/// Calls `send` for every scheduled sample at its time after `start`, on tokio's clock.
/// Absolute deadlines: a late send does not delay the ones after it.
pub async fn pace(
    start: tokio::time::Instant,
    plan: &[(f64, usize)],
    mut send: impl FnMut(usize, f64) -> bool,
) {
    for &(at_ms, index) in plan {
        // Tokio's timers tick in whole milliseconds and wake at the first tick at or after a
        // deadline: aiming half a tick early sends at the nearest tick instead, at most 0.5 ms
        // off rather than up to 1 ms late. A time no timer can hold (negative, NaN,
        // centuries) ends the replay, never panics.
        let aim = if at_ms >= 0.5 { at_ms - 0.5 } else { at_ms };
        let Ok(at) = Duration::try_from_secs_f64(aim / 1000.0) else {
            break;
        };
        let Some(deadline) = start.checked_add(at) else {
            break;
        };
        tokio::time::sleep_until(deadline).await;
        if !send(index, at_ms) {
            break;
        }
    }
}

fn percentile(v: &mut [f64], q: f64) -> f64 {
    if v.is_empty() {
        return f64::NAN;
    }
    v.sort_by(|a, b| a.total_cmp(b));
    v[((q * (v.len() - 1) as f64).round() as usize).min(v.len() - 1)]
}

/// Streams the samples and collects the frames. `progress(sent, total)` is called as it goes.
pub async fn replay(
    samples: &[Sample],
    opts: &ReplayOptions,
    mut progress: impl FnMut(usize, usize),
) -> Result<(Vec<FrameRecord>, ReplaySummary), ClientError> {
    let plan = schedule(
        samples,
        opts.speed,
        opts.start_ms,
        opts.duration_ms,
        opts.loops,
    );
    let (link, mut events, welcome) = Link::open(LinkOptions {
        url: opts.url.clone(),
        token: opts.token.clone(),
        hello: opts.hello.clone(),
        reconnect: true,
    })
    .await?;
    let clock = Instant::now();
    // Send time (ms since start) of each seq; seq = position in the plan + 1.
    let sent_at: Arc<Mutex<Vec<Option<f64>>>> = Arc::new(Mutex::new(vec![None; plan.len() + 1]));
    let keep = opts.keep_images;
    let reader = {
        let sent_at = sent_at.clone();
        let plan = plan.clone();
        let recorded: Vec<f64> = samples.iter().map(|s| s.t_ms).collect();
        tokio::spawn(async move {
            let mut frames = Vec::new();
            while let Some(event) = events.recv().await {
                let LinkEvent::Frame {
                    header: h,
                    image,
                    connection,
                } = event
                else {
                    continue;
                };
                let received_ms = clock.elapsed().as_secs_f64() * 1e3;
                let sent = h.seq.and_then(|s| {
                    sent_at
                        .lock()
                        .ok()
                        .and_then(|v| v.get(s as usize).copied().flatten())
                });
                frames.push(FrameRecord {
                    frame: h.frame,
                    connection,
                    seq: h.seq,
                    sample_t_ms: h
                        .seq
                        .and_then(|s| plan.get((s as usize).wrapping_sub(1)))
                        .map(|(_, i)| recorded[*i]),
                    sent_ms: sent,
                    received_ms,
                    latency_ms: sent.map(|s| received_ms - s),
                    gaze_x: h.gaze.x,
                    gaze_y: h.gaze.y,
                    queue_ms: h.stages_ms.queue,
                    render_ms: h.stages_ms.render,
                    readback_ms: h.stages_ms.readback,
                    encode_ms: h.stages_ms.encode,
                    sampled: h.sampled,
                    bytes: image.len(),
                    server_samples: h.samples,
                    keyframe: h.keyframe,
                    image: keep.then_some(image),
                    codec: h.codec,
                    inset_bytes: h.inset.map(|i| i.inset_bytes).filter(|n| *n > 0),
                });
            }
            frames
        })
    };
    let start = tokio::time::Instant::now();
    let speed = sane_speed(opts.speed);
    let total = plan.len();
    let mut sent_count = 0usize;
    let mut unsendable = 0usize;
    let mut seq = 0u64;
    let sending = pace(start, &plan, |index, at_ms| {
        seq += 1;
        let s = &samples[index];
        let Some([x, y]) = sendable(s) else {
            unsendable += 1;
            return true;
        };
        let t_ms = clock.elapsed().as_secs_f64() * 1e3;
        if let Ok(mut v) = sent_at.lock() {
            v[seq as usize] = Some(t_ms);
        }
        let pupil = s
            .pupil_mm
            .map(|p| format!(r#","pupil_mm":{p}"#))
            .unwrap_or_default();
        // The sample's own time on the recording's clock (its loop offset included, the speed
        // factor undone), so the server's recording of this session keeps the original timing.
        let sample_t = at_ms * speed;
        let ok = link.send(format!(
            r#"{{"type":"gaze","seq":{seq},"t_ms":{t_ms},"sample_t_ms":{sample_t},"x":{x},"y":{y}{pupil}}}"#
        ));
        sent_count += 1;
        if sent_count.is_multiple_of(200) {
            progress(sent_count + unsendable, total);
        }
        ok
    });
    let interrupted = tokio::select! {
        _ = sending => false,
        _ = opts.stop.cancelled() => true,
    };
    progress(sent_count + unsendable, total);
    // Let the last frames arrive, then close; the reader ends when the server closes too.
    let linger = if interrupted { 500 } else { 1500 };
    tokio::time::sleep(Duration::from_millis(linger)).await;
    let link = link.close().await;
    let frames = tokio::time::timeout(Duration::from_secs(10), reader)
        .await
        .map_err(|_| ClientError::Timeout(Duration::from_secs(10)))?
        .map_err(|e| ClientError::BadMessage(format!("reader task: {e}")))?;
    // Each session counts its own samples: the total is the sum of each one's last count.
    let mut per_connection = std::collections::BTreeMap::new();
    for f in &frames {
        let n = per_connection.entry(f.connection).or_insert(0u64);
        *n = (*n).max(f.server_samples);
    }
    let server_samples: u64 = per_connection.values().sum();
    let delivered = (sent_count as u64).saturating_sub(link.dropped);
    let answered = {
        let mut seqs: Vec<u64> = frames.iter().filter_map(|f| f.seq).collect();
        seqs.sort_unstable();
        seqs.dedup();
        seqs.len() as u64
    };
    let mut latencies: Vec<f64> = frames.iter().filter_map(|f| f.latency_ms).collect();
    let keyframes: Vec<&FrameRecord> = frames.iter().filter(|f| f.keyframe == Some(true)).collect();
    let summary = ReplaySummary {
        samples_in_selection: total,
        samples_sent: sent_count,
        samples_unsendable: unsendable,
        frames: frames.len(),
        server_samples,
        samples_lost: delivered.saturating_sub(server_samples),
        samples_dropped_reconnecting: link.dropped,
        reconnects: link.reconnects,
        reconnect_gaps_ms: link.gaps_ms.clone(),
        ended_early: link.ended.clone(),
        interrupted,
        samples_coalesced: server_samples.saturating_sub(answered),
        latency_p50_ms: percentile(&mut latencies, 0.5),
        latency_p95_ms: percentile(&mut latencies, 0.95),
        latency_p99_ms: percentile(&mut latencies, 0.99),
        seconds: clock.elapsed().as_secs_f64(),
        bytes: frames.iter().map(|f| f.bytes as u64).sum(),
        kbit_s: frames.iter().map(|f| f.bytes as f64).sum::<f64>() * 8.0
            / 1000.0
            / clock.elapsed().as_secs_f64().max(1e-9),
        keyframes: keyframes.len() as u64,
        keyframe_bytes: keyframes.iter().map(|f| f.bytes as u64).sum(),
        server: ServerInfo {
            version: welcome.version,
            adapter: welcome.adapter,
            scene: welcome.scene.name,
            width: welcome.width,
            height: welcome.height,
            codec: welcome.codec,
        },
    };
    Ok((frames, summary))
}

/// frames.csv: one row per frame received.
pub fn frames_csv(frames: &[FrameRecord]) -> String {
    let mut s = String::from("frame,connection,seq,sample_t_ms,sent_ms,received_ms,latency_ms,gaze_x,gaze_y,queue_ms,render_ms,readback_ms,encode_ms,sampled,bytes,server_samples,keyframe\n");
    let opt = |v: Option<f64>| v.map(|x| format!("{x:.3}")).unwrap_or_default();
    for f in frames {
        s.push_str(&format!(
            "{},{},{},{},{},{:.3},{},{:.5},{:.5},{:.3},{:.3},{:.3},{:.3},{:.4},{},{},{}\n",
            f.frame,
            f.connection,
            f.seq.map(|s| s.to_string()).unwrap_or_default(),
            opt(f.sample_t_ms),
            opt(f.sent_ms),
            f.received_ms,
            opt(f.latency_ms),
            f.gaze_x,
            f.gaze_y,
            f.queue_ms,
            f.render_ms,
            f.readback_ms,
            f.encode_ms,
            f.sampled,
            f.bytes,
            f.server_samples,
            f.keyframe
                .map(|k| u8::from(k).to_string())
                .unwrap_or_default()
        ));
    }
    s
}

#[cfg(test)]
mod tests {
    use super::*;

    fn samples(n: usize, step: f64) -> Vec<Sample> {
        (0..n)
            .map(|i| Sample {
                t_ms: i as f64 * step,
                xy: Some([0.5, 0.5]),
                pupil_mm: None,
            })
            .collect()
    }

    #[test]
    fn schedule_scales_offsets_and_loops() {
        let s = samples(5, 2.0); // 0, 2, 4, 6, 8 ms
        assert_eq!(
            schedule(&s, 1.0, 0.0, None, 1)
                .iter()
                .map(|p| p.0)
                .collect::<Vec<_>>(),
            vec![0.0, 2.0, 4.0, 6.0, 8.0]
        );
        assert_eq!(
            schedule(&s, 2.0, 4.0, None, 1),
            vec![(0.0, 2), (1.0, 3), (2.0, 4)]
        );
        let looped = schedule(&s, 1.0, 2.0, Some(4.0), 2);
        assert_eq!(
            looped,
            vec![(0.0, 1), (2.0, 2), (4.0, 1), (6.0, 2)],
            "a loop spans its samples plus one period"
        );
        assert!(schedule(&s, 1.0, 100.0, None, 1).is_empty());
        assert_eq!(
            schedule(&s, 0.0, 0.0, None, 1).len(),
            5,
            "a zero speed falls back to real time"
        );
    }

    #[tokio::test(start_paused = true)]
    async fn pacing_hits_every_deadline_on_a_fake_clock() {
        let s = samples(1000, 1.0);
        let plan = schedule(&s, 1.0, 0.0, None, 1);
        let start = tokio::time::Instant::now();
        let mut sent = Vec::new();
        pace(start, &plan, |i, _| {
            sent.push((i, tokio::time::Instant::now() - start));
            true
        })
        .await;
        assert_eq!(sent.len(), 1000);
        for (i, at) in sent {
            // tokio's timer has millisecond granularity; the paused clock lands on the deadline.
            let expected = Duration::from_millis(i as u64);
            assert!(
                at >= expected && at - expected < Duration::from_millis(1),
                "sample {i} at {at:?}"
            );
        }
    }
}
