//! Fovea: a gaze-streaming rendering service.
//!
//! A client sends gaze samples over one WebSocket; a headless wgpu renderer draws the scene for
//! the newest sample and the server streams encoded frames back. The modules, by concern:
//!
//! - [`viewing`]: viewing geometry, once: display size and distance, degrees per pixel, field
//!   of view, gaze in pixels. A leaf.
//! - [`settings`]: typed presets, render and session settings, and the knob list declared once
//!   (wire, command line, docs). A leaf.
//! - [`protocol`]: wire messages, their validation and the limits a server states (no tokio, no
//!   wgpu; imports neither foveation, render nor radiosity).
//! - [`scene`]: scene descriptions, PLY meshes, cameras, lights, and the scene plan.
//! - [`optics`]: CPU twins of the numbers the shaders compute, for reference tests.
//! - [`foveation`]: CPU twins of sampling, reprojection and reconstruction; the blue-noise map.
//! - [`radiosity`]: the progressive radiosity solver that runs beside the renderer.
//! - [`render`]: the headless GPU device, the frame graph, one file per pass, and the render
//!   thread that owns it (imports neither protocol nor server).
//! - [`encode`]: JPEG and PNG encoding of read-back frames.
//! - [`quality`]: PSNR, SSIM, FLIP and acuity-weighted pooling of frame errors.
//! - [`gaze`]: eye-tracker recordings, the synthetic eye, prediction and its evaluation.
//! - [`server`]: the axum app: static page, `/ws` sessions, health and metrics.
//! - [`client`]: a Rust WebSocket client speaking the protocol (tests, replay, load).
//! - [`bench`]: the speed/accuracy sweep behind `fovea bench`.
//! - [`plot`]: the bench, load and gaze plots, SVG and PNG from the same code (`plotters`).
//! - [`stats`]: the median the benches and the command line report. A leaf.
//!
//! The arrows between them point one way; `tests/boundaries.rs` fails on a forbidden one and
//! `docs/architecture.md` draws them.

// `!(x > 0.0)` is how this crate refuses NaN along with the out-of-range values: the
// rewrite clippy asks for (`x <= 0.0`) lets NaN through.
#![allow(clippy::neg_cmp_op_on_partial_ord)]

pub mod bench;
pub mod client;
pub mod encode;
pub mod foveation;
pub mod gaze;
pub mod optics;
pub mod plot;
pub mod protocol;
pub mod quality;
pub mod radiosity;
pub mod render;
pub mod scene;
pub mod server;
pub mod settings;
pub mod stats;
pub mod viewing;
