//! Sampling pass: per-pixel sampling probability (MAR, saliency, motion, depth of field), the
//! blue- or white-noise decision, and the reprojection cache test for pixels not chosen.
//! Writes probability, flags, reused colours and the seeds jump flooding starts from.

use crate::render::graph::{read, texture, uniform, write, GraphError, PassDecl, Recorder};

pub const PASS: PassDecl = PassDecl {
    label: "sampling",
    shader: include_str!("../../../shaders/sampling.wgsl"),
    first_binding: 0,
    bindings: &[
        uniform("frame.uniform"),
        texture("gbuffer.normal_distance"),
        texture("gbuffer.albedo"),
        texture("sampling.rank_map"),
        read("history.color"),
        texture("history.normal_distance"),
        write("sampling.probability"),
        write("sampling.flags"),
        write("shade.color"),
        write("sampling.seeds"),
    ],
    attachments: &[],
    entry_points: &["main"],
};

pub fn record(f: &mut Recorder) -> Result<(), GraphError> {
    f.run_frame_pass(&PASS)
}
