//! Output pass: linear colour to sRGB bytes, the sampling overlays, and the gaze marker that
//! proves to the viewer the frame answers their gaze (drawn at the position the server used).

use crate::render::graph::{read, uniform, write, GraphError, PassDecl, Recorder};

pub const PASS: PassDecl = PassDecl {
    label: "output",
    shader: include_str!("../../../shaders/output.wgsl"),
    first_binding: 0,
    bindings: &[
        uniform("frame.uniform"),
        read("frame.color"),
        read("sampling.flags"),
        read("sampling.probability"),
        write("output.final"),
    ],
    attachments: &[],
    entry_points: &["main"],
};

pub fn record(f: &mut Recorder) -> Result<(), GraphError> {
    f.run_frame_pass(&PASS)
}

/// Marker ring radius and thickness in pixels: about 3% of the shorter side, never so small
/// that a thumbnail loses it.
pub fn marker_size(width: u32, height: u32) -> (f32, f32) {
    let radius = (0.03 * width.min(height) as f32).max(5.0);
    (radius, (0.22 * radius).max(1.5))
}
