//! Compaction pass: the sampled pixels become one dense list (stream compaction, the thesis's
//! CSR reordering), and the count becomes the indirect dispatch of the shading pass.

use crate::render::graph::{read, uniform, write, DispatchSize, GraphError, PassDecl, Recorder};

pub const PASS: PassDecl = PassDecl {
    label: "compact",
    shader: include_str!("../../../shaders/compact.wgsl"),
    first_binding: 0,
    bindings: &[
        uniform("frame.uniform"),
        read("sampling.flags"),
        write("compact.list"),
        write("compact.counter"),
    ],
    attachments: &[],
    entry_points: &["main", "indirect_args"],
};

/// Zeroes the counter, appends every sampled pixel, then turns the count into workgroups.
pub fn record(f: &mut Recorder) -> Result<(), GraphError> {
    let counter = f.buffer("compact.counter")?.clone();
    f.encoder.clear_buffer(&counter, 0, None);
    let list = f.frame_dispatch(&PASS, "main")?;
    let args = f.dispatch(&PASS, "indirect_args", DispatchSize::Groups(1, 1, 1))?;
    f.compute(PASS.label, &[list, args]);
    Ok(())
}
