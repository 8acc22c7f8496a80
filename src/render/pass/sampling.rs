//! Sampling pass: per-pixel sampling probability (MAR, saliency, motion, depth of field), the
//! blue- or white-noise decision, and the reprojection cache test for pixels not chosen.
//! Writes probability, flags, reused colours and the seeds jump flooding starts from.

use crate::render::graph::{
    read, texture, uniform, write, DispatchSize, GraphError, PassDecl, Recorder,
};

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
        write("sampling.saliency"),
    ],
    attachments: &[],
    entry_points: &["main"],
};

/// One invocation per 2×2 block of pixels (the blocks share their saliency's G-buffer reads,
/// and on a software adapter a pixel's share of an invocation's fixed cost falls by four),
/// 8×8 blocks a workgroup.
pub fn record(f: &mut Recorder) -> Result<(), GraphError> {
    let (w, h) = f.size;
    let groups = DispatchSize::Groups(w.div_ceil(16), h.div_ceil(16), 1);
    let d = f.dispatch_by(&PASS, "main", groups, f.by_mode())?;
    f.compute(PASS.label, &[d]);
    Ok(())
}
