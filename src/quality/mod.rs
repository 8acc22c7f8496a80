//! Image quality against a reference: PSNR, SSIM and FLIP, over the whole frame, pooled with a
//! weight that falls with eccentricity from the gaze, and within 5° of it.

mod flip;
mod pooling;
mod psnr;
mod ssim;

pub use flip::{flip_map, pixels_per_degree};
pub use pooling::{acuity_weights, foveal_mask, pooled_mean, Weighting};
pub use psnr::{psnr, psnr_weighted, PSNR_CAP_DB};
pub use ssim::ssim_map;

use serde::{Deserialize, Serialize};

/// Every error measure of one test image against its reference.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct Errors {
    /// dB; capped at `PSNR_CAP_DB` for identical images so JSON stays finite.
    pub psnr: f64,
    pub ssim: f64,
    pub flip: f64,
    pub psnr_pooled: f64,
    pub ssim_pooled: f64,
    pub flip_pooled: f64,
    pub psnr_fovea: f64,
    pub ssim_fovea: f64,
    pub flip_fovea: f64,
}

/// All measures of `test` against `reference` (tightly packed sRGB RGBA8 of the same size),
/// with the gaze at `gaze_px` on a display of the given geometry.
pub fn measure(
    reference: &[u8],
    test: &[u8],
    width: u32,
    height: u32,
    viewing: &crate::viewing::Viewing,
    gaze_px: [f64; 2],
    weighting: &Weighting,
) -> Errors {
    let ppd = pixels_per_degree(viewing);
    let flip = flip_map(reference, test, width, height, ppd);
    let ssim = ssim_map(reference, test, width, height);
    let uniform = vec![1.0; (width * height) as usize];
    let pooled = acuity_weights(viewing, gaze_px, weighting);
    let fovea = foveal_mask(viewing, gaze_px, 5.0);
    Errors {
        psnr: psnr(reference, test),
        ssim: pooled_mean(&ssim, &uniform),
        flip: pooled_mean(&flip, &uniform),
        psnr_pooled: psnr_weighted(reference, test, &pooled),
        ssim_pooled: pooled_mean(&ssim, &pooled),
        flip_pooled: pooled_mean(&flip, &pooled),
        psnr_fovea: psnr_weighted(reference, test, &fovea),
        ssim_fovea: pooled_mean(&ssim, &fovea),
        flip_fovea: pooled_mean(&flip, &fovea),
    }
}
