//! RGB → I420 pass (H.264 sessions): the output image converted to BT.601 full-range Y, U
//! and V planes on the GPU, so the readback is 1.5 bytes a pixel instead of 4 and the encoder
//! thread skips the conversion. CPU twin: `encode::yuv::rgba_to_i420` (tests/i420.rs holds the
//! GPU to it).

use crate::render::graph::{read, uniform, write, DispatchSize, GraphError, PassDecl, Recorder};

pub const PASS: PassDecl = PassDecl {
    label: "i420",
    shader: include_str!("../../../shaders/i420.wgsl"),
    first_binding: 0,
    bindings: &[
        uniform("frame.uniform"),
        read("output.final"),
        write("output.i420"),
    ],
    attachments: &[],
    entry_points: &["main"],
};

/// Words in `output.i420` for a `width`×`height` frame (both even): the Y plane, then U and V
/// each padded to whole words.
pub fn words(width: u32, height: u32) -> u64 {
    let pixels = u64::from(width) * u64::from(height);
    pixels / 4 + 2 * (pixels / 4).div_ceil(4)
}

/// The tight I420 picture (Y, U, V) out of the pass's padded planes.
pub fn unpad(padded: &[u8], width: u32, height: u32) -> Vec<u8> {
    let pixels = (width as usize) * (height as usize);
    let chroma = pixels / 4;
    let padded_chroma = chroma.div_ceil(4) * 4;
    let mut out = Vec::with_capacity(pixels + 2 * chroma);
    out.extend_from_slice(&padded[..pixels]);
    out.extend_from_slice(&padded[pixels..pixels + chroma]);
    out.extend_from_slice(&padded[pixels + padded_chroma..pixels + padded_chroma + chroma]);
    out
}

pub fn record(f: &mut Recorder) -> Result<(), GraphError> {
    let (w, h) = f.size;
    let groups = ((u64::from(w) * u64::from(h) / 4).div_ceil(64)) as u32;
    let d = f.dispatch(&PASS, "main", DispatchSize::Groups(groups, 1, 1))?;
    f.compute(PASS.label, &[d]);
    Ok(())
}
