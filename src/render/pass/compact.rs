//! Compaction pass: the sampled pixels become one dense list (stream compaction, the thesis's
//! CSR reordering), and the count becomes the indirect dispatch of the shading pass. A frame in
//! parts lists each band of rows before shading it, so each band shades only its own samples.

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
    entry_points: &["band_start", "main", "indirect_args"],
};

/// Empties the list: before the frame's first band.
pub fn clear(f: &mut Recorder) -> Result<(), GraphError> {
    let counter = f.buffer("compact.counter")?.clone();
    f.encoder.clear_buffer(&counter, 0, None);
    Ok(())
}

/// Appends the sampled pixels of rows `[first, end)` (the frame uniform's `shade_rows`) and
/// turns their count into the workgroups of the band's shading.
pub fn record_rows(f: &mut Recorder, first: u32, end: u32) -> Result<(), GraphError> {
    let start = f.dispatch(&PASS, "band_start", DispatchSize::Groups(1, 1, 1))?;
    let mut list = f.frame_dispatch(&PASS, "main")?;
    let rows = end.saturating_sub(first);
    // An invocation lists an 8×8 tile, a workgroup 8×8 tiles.
    list.size = DispatchSize::Groups(f.size.0.div_ceil(64), rows.div_ceil(64), 1);
    let args = f.dispatch(&PASS, "indirect_args", DispatchSize::Groups(1, 1, 1))?;
    f.compute(PASS.label, &[start, list, args]);
    Ok(())
}
