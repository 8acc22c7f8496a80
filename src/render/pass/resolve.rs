//! Resolve pass: background, shaded and reused pixels as they are, the rest reconstructed from
//! the jump-flooding result (nearest sample or windowed approximate Sibson).

use crate::render::graph::{
    read, texture, uint_texture, uniform, write, GraphError, PassDecl, Recorder,
};

pub const PASS: PassDecl = PassDecl {
    label: "resolve",
    shader: include_str!("../../../shaders/resolve.wgsl"),
    first_binding: 0,
    bindings: &[
        uniform("frame.uniform"),
        read("shade.color"),
        uint_texture("jfa.nearest"),
        texture("gbuffer.albedo"),
        write("resolve.color"),
        texture("gbuffer.normal_distance"),
        read("sampling.flags"),
    ],
    attachments: &[],
    entry_points: &["main"],
};

/// Fills the frame; from here on `frame.color` is the resolved colour.
pub fn record(f: &mut Recorder) -> Result<(), GraphError> {
    f.run_frame_pass(&PASS)?;
    f.route("frame.color", "resolve.color");
    f.route(crate::render::frame::RECONSTRUCTED, "resolve.color");
    Ok(())
}
