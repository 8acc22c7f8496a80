//! `fovea bench`: every preset and knob on one cost-vs-error chart against the reference render
//! of the same frame, measured side by side in one run.
//!
//! Configurations are interleaved frame by frame (config A, B, C, A, B, C, …) so the machine's
//! drift and noise fall on all of them alike; reported times are medians with the 10th–90th
//! percentile spread, and speedups are ratios against `full` from the same run.

mod codec_configs;
mod codecs;
mod codecs_report;
mod configs;
mod foveation_cost;
mod gaze_path;
mod ground_truth;
mod report;
mod run;

pub use codec_configs::{codec_configs, CodecConfig};
pub use codecs::{run_codecs, CodecBenchError, CodecOptions, FPS};
pub use codecs_report::{
    at_quality, write_codec_reports, AtQuality, CodecReport, CodecRow, EqualQuality, FloorRow,
    TARGET,
};
pub use configs::{sweep, BenchConfig};
pub use foveation_cost::bound_vs_full;
pub use gaze_path::{gaze_path, gaze_stretches};
pub use ground_truth::{GroundTruth, GroundTruthError};
pub use report::{pareto_front, write_reports, BenchRecord, BenchReport, ReferenceTruth, Spread};
pub use run::{run, BenchOptions, Progress};
