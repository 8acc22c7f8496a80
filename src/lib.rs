//! Fovea: a gaze-streaming rendering service.
//!
//! A client sends gaze samples over one WebSocket; a headless wgpu renderer draws the scene for
//! the newest sample and the server streams encoded frames back. The modules, by concern:
//!
//! - [`protocol`]: wire messages, their validation and the limits a server states (no tokio, no wgpu).
//! - [`scene`]: scene descriptions, PLY meshes, cameras and lights.
//! - [`optics`]: CPU twins of the numbers the shaders compute, for reference tests.
//! - [`render`]: the headless GPU device, one file per pass, and the render thread that owns it.
//! - [`encode`]: JPEG and PNG encoding of read-back frames.
//! - [`server`]: the axum app: static page, `/ws` sessions, health.
//! - [`client`]: a Rust WebSocket client speaking the protocol (tests now, replay and load later).

pub mod bench;
pub mod client;
pub mod encode;
pub mod foveation;
pub mod gaze;
pub mod optics;
pub mod protocol;
pub mod quality;
pub mod radiosity;
pub mod render;
pub mod scene;
pub mod server;
