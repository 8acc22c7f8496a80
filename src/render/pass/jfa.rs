//! Jump flooding: one step per jump size, ping-ponging two seed textures, after which every
//! pixel holds its (nearly always exactly) nearest shaded sample. Each step's jump size comes
//! from a uniform slot selected by dynamic offset.

use crate::render::graph::{
    dynamic_uniform, read, uint_texture, uniform, write_uint, GraphError, PassDecl, Recorder,
};

/// Uniform slots must start at multiples of the device's offset alignment (256 by default).
pub const SLOT: u64 = 256;

pub const PASS: PassDecl = PassDecl {
    label: "jfa",
    shader: include_str!("../../../shaders/jfa.wgsl"),
    first_binding: 0,
    bindings: &[
        uniform("frame.uniform"),
        uint_texture("jfa.in"),
        write_uint("jfa.out"),
        dynamic_uniform("jfa.steps", 16),
        read("sampling.seeds"),
    ],
    attachments: &[],
    entry_points: &["first", "main"],
};

pub const PING: &str = "jfa.seeds[ping]";
pub const PONG: &str = "jfa.seeds[pong]";

/// Runs one step per jump size; afterwards `jfa.nearest` names the texture holding the result.
pub fn record(f: &mut Recorder, steps: &[u32]) -> Result<(), GraphError> {
    let mut slots = vec![0u8; steps.len() * SLOT as usize];
    for (i, s) in steps.iter().enumerate() {
        let at = i * SLOT as usize;
        slots[at..at + 4].copy_from_slice(&s.to_le_bytes());
    }
    f.queue.write_buffer(f.buffer("jfa.steps")?, 0, &slots);
    // The first step reads `sampling.seeds`; `jfa.in` is then bound but unread.
    let mut from = PONG;
    let mut dispatches = Vec::with_capacity(steps.len());
    for i in 0..steps.len() {
        let to = if from == PING { PONG } else { PING };
        f.route("jfa.in", from);
        f.route("jfa.out", to);
        let entry = if i == 0 { "first" } else { "main" };
        let mut d = f.frame_dispatch(&PASS, entry)?;
        d.offsets = vec![(i as u64 * SLOT) as u32];
        dispatches.push(d);
        from = to;
    }
    f.compute(PASS.label, &dispatches);
    f.route("jfa.nearest", from);
    Ok(())
}
