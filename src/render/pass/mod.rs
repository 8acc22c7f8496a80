//! One file per pass, each beside its WGSL in `shaders/` and each declaring what it reads and
//! writes in a `PASS` ([`crate::render::graph::PassDecl`]). `render/frame.rs` records them in
//! frame order; photons → pyramid run once per static scene.

pub mod compact;
pub mod dof;
pub mod gbuffer;
pub mod i420;
pub mod jfa;
pub mod low_pass;
pub mod output;
pub mod photons;
pub mod pull_push;
pub mod pull_push_tiles;
pub mod pyramid;
pub mod resolve;
pub mod sampling;
pub mod screen_diffusion;
pub mod shade;
pub mod shadow;
