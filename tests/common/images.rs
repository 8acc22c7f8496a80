//! Image assertions for GPU tests that you can look at: on failure the actual image, the
//! expected one and a FLIP difference map are written to a folder the panic message names
//! (under the test target's temporary directory), and every bound states which device it was
//! measured on.

use std::path::PathBuf;

use fovea::quality::{flip_map, pixels_per_degree};
use fovea::viewing::{Display, Viewing};

/// How far an image may be from its expected one.
#[derive(Debug, Clone, Copy)]
pub struct Bound {
    /// Largest per-pixel FLIP allowed; 0 demands identical bytes.
    pub max_flip: f64,
    /// The adapter the bound was measured on and what sets it.
    pub device: &'static str,
}

/// The adapter the GPU tests' numeric bounds were measured on (CI's): Mesa's lavapipe, f32.
/// Bounds that are rounding margins of f32 against f64 twins hold on any adapter; the ones
/// that depend on rasterisation rules name this.
pub const LAVAPIPE: &str = "lavapipe (Mesa 22.3, LLVM 15), f32 against f64 CPU twins";

/// Two routes that must produce the same bytes on any adapter.
pub const IDENTICAL: Bound = Bound {
    max_flip: 0.0,
    device: "any adapter: both routes run the same shaders on the same inputs",
};

/// Where a failing test's images go.
pub fn failure_dir(test: &str) -> PathBuf {
    PathBuf::from(env!("CARGO_TARGET_TMPDIR"))
        .join("image-failures")
        .join(test)
}

fn write_png(path: &PathBuf, rgba: &[u8], w: u32, h: u32) {
    if let Some(img) = image::RgbaImage::from_raw(w, h, rgba.to_vec()) {
        let _ = img.save(path);
    }
}

/// FLIP per pixel as a heat map: black (equal) through red to yellow (FLIP 1).
fn heat(map: &[f64]) -> Vec<u8> {
    map.iter()
        .flat_map(|&e| {
            let e = e.clamp(0.0, 1.0);
            let r = (2.0 * e).min(1.0);
            let g = (2.0 * e - 1.0).max(0.0);
            [(r * 255.0) as u8, (g * 255.0) as u8, 0, 255]
        })
        .collect()
}

/// Passes when `actual` is within `bound` of `expected` (RGBA8, `w`×`h`); otherwise writes
/// `actual.png`, `expected.png` and `flip.png` to [`failure_dir`]`(test)` and panics.
pub fn assert_image(test: &str, actual: &[u8], expected: &[u8], w: u32, h: u32, bound: Bound) {
    assert_eq!(actual.len(), expected.len(), "{test}: image sizes differ");
    if actual == expected {
        return;
    }
    let viewing = Viewing::new(Display::default(), w, h);
    let map = flip_map(expected, actual, w, h, pixels_per_degree(&viewing));
    let worst = map.iter().copied().fold(0.0, f64::max);
    if bound.max_flip > 0.0 && worst <= bound.max_flip {
        return;
    }
    let dir = failure_dir(test);
    let _ = std::fs::create_dir_all(&dir);
    write_png(&dir.join("actual.png"), actual, w, h);
    write_png(&dir.join("expected.png"), expected, w, h);
    write_png(&dir.join("flip.png"), &heat(&map), w, h);
    let differing = actual
        .chunks(4)
        .zip(expected.chunks(4))
        .filter(|(a, b)| a != b)
        .count();
    panic!(
        "{test}: {differing} pixels differ, max FLIP {worst:.4} > {} (bound from {}); \
         actual, expected and FLIP images are in {}",
        bound.max_flip,
        bound.device,
        dir.display()
    );
}
