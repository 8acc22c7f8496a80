//! Foveation: CPU twins of the sampling, reprojection and reconstruction passes (thesis: seed
//! 003; blue noise: seed 001 #1). Its knobs and presets live in [`crate::settings`].

pub mod pull_push;
pub mod rank_map;
pub mod reconstruct;
pub mod reprojection;
