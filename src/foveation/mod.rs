//! Foveation: the knobs and presets, and CPU twins of the sampling, reprojection and
//! reconstruction passes (thesis: seed 003; blue noise: seed 001 #1).

pub mod rank_map;
pub mod reconstruct;
pub mod reprojection;
pub mod settings;

pub use settings::{Foveation, Noise, Reconstruction, Rung, Settings, Translucency, PRESETS};
