//! Depth-of-field pass: blurs each pixel by the eye's blur circle for the current pupil and the
//! depth under the gaze.

use crate::render::graph::{read, texture, uniform, write, GraphError, PassDecl, Recorder};

pub const PASS: PassDecl = PassDecl {
    label: "dof",
    shader: include_str!("../../../shaders/dof.wgsl"),
    first_binding: 0,
    bindings: &[
        uniform("frame.uniform"),
        read("frame.color"),
        texture("gbuffer.normal_distance"),
        write("dof.color"),
    ],
    attachments: &[],
    entry_points: &["main"],
};

/// Blurs the newest colour; from here on `frame.color` is the blurred one.
pub fn record(f: &mut Recorder) -> Result<(), GraphError> {
    f.run_frame_pass(&PASS)?;
    f.route("frame.color", "dof.color");
    Ok(())
}
