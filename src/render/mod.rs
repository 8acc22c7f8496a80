//! The headless renderer. [`Gpu`] picks an adapter and opens the device; [`Renderer`] owns the
//! pipelines, per-scene GPU data and per-size targets and turns a [`FrameRequest`] into pixels;
//! [`RenderThread`] runs a `Renderer` on its own thread so nothing async ever waits on the GPU.
//!
//! Passes, one file each beside its shader in `shaders/` (see [`pass`]), each declaring what it
//! reads and writes for the frame graph ([`graph`]); [`frame`] records them in frame order:
//! G-buffer → (screen diffusion) → sampling map → compaction → shading → jump flooding →
//! resolve → (depth of field) → output with the gaze marker. Full and reference modes shade
//! every pixel and skip the foveation passes.
//!
//! This module imports nothing from `protocol` or `server` (`tests/boundaries.rs`).

pub mod binding;
pub mod cost;
pub mod cpu_reference;
mod device;
mod foveation_policy;
pub mod frame;
mod frame_uniform;
mod gi;
pub mod gpu;
pub mod graph;
pub mod health;
mod inspect;
pub mod lights;
pub mod materials;
pub mod pass;
mod pipelines;
mod renderer;
mod request;
mod scene_gpu;
mod scheduler;
mod sliced;
mod targets;
pub mod textures;
mod thread;
pub mod timer;
mod turns;
pub mod uniforms;

pub use device::Gpu;
pub use inspect::PullPushInputs;
pub use renderer::Renderer;
pub use request::{
    FrameRequest, GpuLowPass, Inspection, Readback, RenderedFrame, DEFAULT_PUPIL_MM, MAX_SIDE,
    MIN_XI,
};
pub use scheduler::SLICE_MS;
pub use sliced::{bands, FrameInFlight, Progress};
pub use targets::FrameTargets;
pub use thread::{RenderHandle, RenderThread, Rendered};

#[derive(Debug, thiserror::Error)]
pub enum RenderError {
    #[error(
        "no GPU adapter found ({0}); on Debian/Ubuntu install the software Vulkan driver: \
         apt-get install mesa-vulkan-drivers libvulkan1"
    )]
    NoAdapter(String),
    #[error("could not open the GPU device on {adapter}: {source}")]
    Device {
        adapter: String,
        source: wgpu::RequestDeviceError,
    },
    #[error(transparent)]
    Scene(#[from] crate::scene::SceneError),
    #[error("frame size {width}x{height} is not renderable (1 ..= {max} per side)")]
    Size { width: u32, height: u32, max: u32 },
    #[error("GPU error while rendering: {0}")]
    Gpu(String),
    #[error("reading the frame back from the GPU failed: {0}")]
    Readback(String),
    #[error("frame graph: {0}")]
    Graph(#[from] graph::GraphError),
    #[error("the render thread has stopped")]
    ThreadGone,
}
