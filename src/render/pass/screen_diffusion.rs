//! Screen-space diffusion passes (the middle translucency rung): irradiance, then a separable
//! blur by the dipole profile. The result ends in `screen_diffusion.a`, which shading reads.

use crate::render::graph::{read, texture, uniform, write, GraphError, PassDecl, Recorder};

pub const PASS: PassDecl = PassDecl {
    label: "screen_diffusion",
    shader: include_str!("../../../shaders/screen_diffusion.wgsl"),
    first_binding: 0,
    bindings: &[
        uniform("frame.uniform"),
        texture("gbuffer.normal_distance"),
        texture("gbuffer.albedo"),
        read("materials.planned"),
        read("scene.reach"),
        read("screen_diffusion.in"),
        write("screen_diffusion.out"),
        texture("shadow.depth"),
    ],
    attachments: &[],
    entry_points: &["irradiance", "blur_horizontal", "blur_vertical"],
};

const A: &str = "screen_diffusion.a";
const B: &str = "screen_diffusion.b";

/// Irradiance → a, a → b (horizontal), b → a (vertical).
pub fn record(f: &mut Recorder) -> Result<(), GraphError> {
    let mut steps = Vec::new();
    for (entry, from, to) in [
        ("irradiance", B, A),
        ("blur_horizontal", A, B),
        ("blur_vertical", B, A),
    ] {
        f.route("screen_diffusion.in", from);
        f.route("screen_diffusion.out", to);
        steps.push(f.frame_dispatch(&PASS, entry)?);
    }
    f.compute(PASS.label, &steps);
    Ok(())
}
