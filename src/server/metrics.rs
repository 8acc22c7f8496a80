//! Prometheus metrics (the `metrics` facade with its Prometheus exporter, installed once per
//! process). Names: `fovea_sessions_active`, `fovea_sessions_total`,
//! `fovea_sessions_refused_total`, `fovea_sessions_stalled_total`, `fovea_frames_rendered_total`,
//! `fovea_frames_sent_total`, `fovea_frames_failed_total`, `fovea_frames_skipped_total` (a sample
//! arrived while the client had no credit), `fovea_gaze_samples_total`, `fovea_gaze_coalesced_total`,
//! `fovea_errors_total{code}`, `fovea_sessions_unauthorised_total`,
//! `fovea_sessions_unresponsive_total`, `fovea_protocol_violations_total`,
//! `fovea_frames_abandoned_total`, `fovea_draining`, and `fovea_stage_seconds{stage}` histograms for queue, render,
//! readback, encode and send (queue only for frames that answer a gaze sample), and
//! `fovea_gaze_to_sent_seconds` (a sample's arrival to its frame handed to the socket).
//!
//! Every metric is described (`# HELP`) and registered when the exporter is installed, so
//! `/metrics` lists them all before the first session.

use std::sync::OnceLock;

use metrics_exporter_prometheus::{PrometheusBuilder, PrometheusHandle};

/// Latency buckets in seconds: 0.5 ms to 2 s.
const BUCKETS: &[f64] = &[
    0.0005, 0.001, 0.002, 0.005, 0.01, 0.02, 0.05, 0.1, 0.2, 0.5, 1.0, 2.0,
];

/// The process-wide exporter handle (None if another recorder was installed first).
pub fn handle() -> Option<&'static PrometheusHandle> {
    static HANDLE: OnceLock<Option<PrometheusHandle>> = OnceLock::new();
    HANDLE
        .get_or_init(|| {
            let builder = PrometheusBuilder::new().set_buckets(BUCKETS).ok()?;
            match builder.install_recorder() {
                Ok(h) => {
                    describe();
                    Some(h)
                }
                Err(e) => {
                    tracing::warn!("metrics disabled: {e}");
                    None
                }
            }
        })
        .as_ref()
}

pub fn stage(stage: &'static str, ms: f64) {
    metrics::histogram!("fovea_stage_seconds", "stage" => stage).record(ms / 1e3);
}

/// Names and help texts, registered at zero so scrapers see every series from the start.
fn describe() {
    use metrics::{describe_counter, describe_gauge, describe_histogram, Unit};
    const COUNTERS: &[(&str, &str)] = &[
        (
            "fovea_sessions_total",
            "Sessions admitted since the server started.",
        ),
        (
            "fovea_sessions_refused_total",
            "Sessions refused at capacity (close 1013).",
        ),
        (
            "fovea_sessions_stalled_total",
            "Sessions closed for leaving frames unacknowledged (1008).",
        ),
        ("fovea_frames_rendered_total", "Frames rendered."),
        ("fovea_frames_sent_total", "Frames handed to a socket."),
        (
            "fovea_frames_failed_total",
            "Frames that failed to render or encode.",
        ),
        (
            "fovea_frames_skipped_total",
            "Gaze samples whose frame was skipped: the client had no credit.",
        ),
        (
            "fovea_sessions_unauthorised_total",
            "Handshakes refused for a missing or wrong token or a foreign Origin (401, 403).",
        ),
        (
            "fovea_sessions_unresponsive_total",
            "Sessions let go after three unanswered pings.",
        ),
        (
            "fovea_protocol_violations_total",
            "Sessions closed for breaking the WebSocket rules (1009, 1007, 1002).",
        ),
        (
            "fovea_frames_abandoned_total",
            "Frames not rendered because their session had gone.",
        ),
        ("fovea_gaze_samples_total", "Gaze samples received."),
        (
            "fovea_gaze_coalesced_total",
            "Gaze samples replaced by a newer one before being rendered.",
        ),
    ];
    for (name, help) in COUNTERS {
        describe_counter!(*name, Unit::Count, *help);
        metrics::counter!(*name).absolute(0);
    }
    describe_counter!(
        "fovea_errors_total",
        Unit::Count,
        "Protocol errors sent to clients, by code."
    );
    describe_gauge!("fovea_sessions_active", Unit::Count, "Sessions open now.");
    metrics::gauge!("fovea_sessions_active").set(0.0);
    describe_gauge!(
        "fovea_draining",
        Unit::Count,
        "1 once a drain has begun (SIGTERM, POST /admin/drain)."
    );
    metrics::gauge!("fovea_draining").set(0.0);
    describe_histogram!(
        "fovea_stage_seconds",
        Unit::Seconds,
        "Time per frame stage: queue (gaze frames only), render, readback, encode, send."
    );
    describe_histogram!(
        "fovea_gaze_to_sent_seconds",
        Unit::Seconds,
        "From a gaze sample's arrival to its frame handed to the socket (gaze frames only)."
    );
}
