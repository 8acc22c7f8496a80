//! `fovea bench`: every preset and knob on one cost-vs-error chart against the reference render
//! of the same frame, measured side by side in one run.
//!
//! Configurations are interleaved frame by frame (config A, B, C, A, B, C, …) so the machine's
//! drift and noise fall on all of them alike; reported times are medians with the 10th–90th
//! percentile spread, and speedups are ratios against `full` from the same run.

mod configs;
mod plot;
mod report;
mod run;

pub use configs::{sweep, BenchConfig};
pub use report::{pareto_front, write_reports, BenchRecord, BenchReport, Spread};
pub use run::{run, BenchOptions, Progress};
