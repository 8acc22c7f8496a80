//! Prometheus metrics (the `metrics` facade with its Prometheus exporter, installed once per
//! process). Names: `fovea_sessions_active`, `fovea_sessions_total`,
//! `fovea_sessions_refused_total`, `fovea_sessions_stalled_total`, `fovea_frames_rendered_total`,
//! `fovea_frames_sent_total`, `fovea_frames_failed_total`, `fovea_frames_skipped_total` (a sample
//! arrived while the client had no credit), `fovea_gaze_samples_total`, `fovea_gaze_coalesced_total`,
//! `fovea_errors_total{code}`, and `fovea_stage_seconds{stage}` histograms for queue, render,
//! readback, encode and send.

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
                Ok(h) => Some(h),
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
