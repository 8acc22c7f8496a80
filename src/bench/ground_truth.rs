//! Physical ground truth from outside our own model (`tools/mitsuba_reference.py`): an image
//! of the same scene, camera and size, which `fovea bench --against` compares every
//! configuration (and our own reference rung) with.

use std::path::{Path, PathBuf};

use crate::optics::color::linear_to_srgb8;

#[derive(Debug, thiserror::Error)]
pub enum GroundTruthError {
    #[error("{path}: {source}")]
    Read {
        path: PathBuf,
        source: image::ImageError,
    },
    #[error("{0}: ground truth must be .png (sRGB) or .exr (linear, Fovea's units)")]
    Format(PathBuf),
}

/// An image in the form frames are compared in: sRGB bytes, RGBA, top row first.
#[derive(Debug, Clone)]
pub struct GroundTruth {
    pub path: PathBuf,
    pub width: u32,
    pub height: u32,
    pub rgba: Vec<u8>,
}

impl GroundTruth {
    /// PNG is taken as sRGB as it stands. EXR is linear radiance in Fovea's units (×π, see
    /// the tool), clamped to [0, 1] and sRGB-encoded like a frame.
    pub fn load(path: &Path) -> Result<GroundTruth, GroundTruthError> {
        let ext = path
            .extension()
            .and_then(|e| e.to_str())
            .map(str::to_ascii_lowercase);
        let read = |source| GroundTruthError::Read {
            path: path.to_path_buf(),
            source,
        };
        let img = image::open(path).map_err(read)?;
        let rgba = match ext.as_deref() {
            Some("png") => img.to_rgba8().into_raw(),
            Some("exr") => img
                .to_rgba32f()
                .pixels()
                .flat_map(|p| {
                    let [r, g, b, _] = p.0;
                    [
                        linear_to_srgb8(r),
                        linear_to_srgb8(g),
                        linear_to_srgb8(b),
                        255,
                    ]
                })
                .collect(),
            _ => return Err(GroundTruthError::Format(path.to_path_buf())),
        };
        Ok(GroundTruth {
            path: path.to_path_buf(),
            width: img.width(),
            height: img.height(),
            rgba,
        })
    }
}
