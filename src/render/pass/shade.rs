//! Shading pass: the frame's shading where it is needed, either over the compacted list
//! (indirect dispatch, cost ∝ samples) or over the whole frame with a mask.

use crate::render::graph::{
    read, texture, uniform, write, Dispatch, DispatchSize, GraphError, PassDecl, Recorder,
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
        texture("photons.node_texels"),
        read("screen_diffusion.a"),
        texture("gbuffer.irradiance"),
        texture("shadow.depth"),
        read("lights.scene"),
        texture("shadow.atlas"),
        write("shade.coarse"),
        texture("shadow.tile_views"),
    ],
    attachments: &[],
    entry_points: &["shade_list", "shade_grid", "gather_coarse"],
};

/// Bytes of one coarse-lattice sample: the gathered light and its coverage, two vec4.
const COARSE_BYTES: u64 = 32;

/// The coarse lattice: a sample at every other pixel on each axis, (2i, 2j).
pub fn coarse_size(width: u32, height: u32) -> (u32, u32) {
    (width.div_ceil(2), height.div_ceil(2))
}

/// Bytes of the coarse lattice's buffer at this frame size.
pub fn coarse_bytes(width: u32, height: u32) -> u64 {
    let (w, h) = coarse_size(width, height);
    u64::from(w) * u64::from(h) * COARSE_BYTES
}

/// The gathers on the coarse lattice rows that pixel rows `[first, end)` interpolate from:
/// row y reads lattice rows ⌊y/2⌋ and, when odd, the one below.
fn coarse_dispatch(f: &mut Recorder, first: u32, end: u32) -> Result<Dispatch, GraphError> {
    let (w, h) = coarse_size(f.size.0, f.size.1);
    let top = first / 2;
    let bottom = (end.saturating_sub(1) / 2 + 1).min(h.saturating_sub(1));
    let rows = (bottom + 1).saturating_sub(top);
    f.dispatch(
        &PASS,
        "gather_coarse",
        DispatchSize::Groups(w.div_ceil(8), rows.div_ceil(8), 1),
    )
}

/// Shades the listed pixels; the workgroup count comes from `compact.counter[1..4]`.
pub fn record_list(f: &mut Recorder) -> Result<(), GraphError> {
    let counter = f.buffer("compact.counter")?.clone();
    let d = f.dispatch_by(
        &PASS,
        "shade_list",
        DispatchSize::Indirect(counter, 4),
        f.by_scene(),
    )?;
    f.compute(PASS.label, &[d]);
    Ok(())
}

/// Shades every pixel (the flags mask it when foveated without compaction); with `coarse`
/// the photon gathers on the coarse lattice run first.
pub fn record_grid(f: &mut Recorder, coarse: bool) -> Result<(), GraphError> {
    let mut dispatches = Vec::new();
    if coarse {
        dispatches.push(coarse_dispatch(f, 0, f.size.1)?);
    }
    dispatches.push(f.dispatch_by(&PASS, "shade_grid", DispatchSize::Frame, f.by_scene())?);
    f.compute(PASS.label, &dispatches);
    Ok(())
}

/// Shades every pixel of rows `[first, end)`: one slice of a frame split so that other frames
/// can run between its slices. The frame uniform's `shade_rows` must hold the same rows.
pub fn record_rows(f: &mut Recorder, first: u32, end: u32, coarse: bool) -> Result<(), GraphError> {
    let mut dispatches = Vec::new();
    if coarse {
        dispatches.push(coarse_dispatch(f, first, end)?);
    }
    let mut d = f.dispatch_by(&PASS, "shade_grid", DispatchSize::Frame, f.by_scene())?;
    d.size = DispatchSize::Groups(
        f.size.0.div_ceil(8),
        end.saturating_sub(first).div_ceil(8),
        1,
    );
    dispatches.push(d);
    f.compute(PASS.label, &dispatches);
    Ok(())
}
