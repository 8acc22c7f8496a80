//! Shading pass: the frame's shading where it is needed, either over the compacted list
//! (indirect dispatch, cost ∝ samples) or over the whole frame with a mask.

use crate::render::graph::{
    read, texture, uniform, write, DispatchSize, GraphError, PassDecl, Recorder,
};

pub const PASS: PassDecl = PassDecl {
    label: "shade",
    shader: include_str!("../../../shaders/shade.wgsl"),
    first_binding: 0,
    bindings: &[
        uniform("frame.uniform"),
        texture("gbuffer.normal_distance"),
        texture("gbuffer.albedo"),
        read("sampling.flags"),
        read("compact.list"),
        read("compact.counter"),
        write("shade.color"),
        read("materials.planned"),
        texture("gbuffer.blurred_normal"),
        read("photons.nodes"),
        read("screen_diffusion.a"),
        texture("gbuffer.irradiance"),
        texture("shadow.depth"),
        read("lights.scene"),
        texture("shadow.atlas"),
    ],
    attachments: &[],
    entry_points: &["shade_list", "shade_grid"],
};

/// Shades the listed pixels; the workgroup count comes from `compact.counter[1..4]`.
pub fn record_list(f: &mut Recorder) -> Result<(), GraphError> {
    let counter = f.buffer("compact.counter")?.clone();
    let d = f.dispatch(&PASS, "shade_list", DispatchSize::Indirect(counter, 4))?;
    f.compute(PASS.label, &[d]);
    Ok(())
}

/// Shades every pixel (the flags mask it when foveated without compaction).
pub fn record_grid(f: &mut Recorder) -> Result<(), GraphError> {
    let d = f.frame_dispatch(&PASS, "shade_grid")?;
    f.compute(PASS.label, &[d]);
    Ok(())
}

/// Shades every pixel of rows `[first, end)`: one slice of a frame split so that other frames
/// can run between its slices. The frame uniform's `shade_rows` must hold the same rows.
pub fn record_rows(f: &mut Recorder, first: u32, end: u32) -> Result<(), GraphError> {
    let mut d = f.frame_dispatch(&PASS, "shade_grid")?;
    d.size = DispatchSize::Groups(
        f.size.0.div_ceil(8),
        end.saturating_sub(first).div_ceil(8),
        1,
    );
    f.compute(PASS.label, &[d]);
    Ok(())
}
