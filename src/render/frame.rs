//! One frame, in order. [`record`] reads like the frame itself: each line is a pass (its file
//! in `render/pass/` declares what it reads and writes), and the [`FramePlan`] decides which
//! optional passes run. `frame.color` is the port every colour consumer reads: the shading
//! result, replaced by the resolved and then the blurred colour when those passes run.
//!
//! Adding a pass: a file in `render/pass/` with its `PASS` declaration and `record`, its shader,
//! one line in [`record`] and its entry in [`PASSES`] (which the naga test and the architecture
//! doc read).

use super::graph::{GraphError, PassDecl, Recorder};
use super::pass::gbuffer::MeshBuffers;
use super::pass::{
    compact, dof, gbuffer, i420, jfa, low_pass, output, photons, pull_push, pull_push_tiles,
    pyramid, resolve, sampling, screen_diffusion, shade, shadow,
};
use super::request::MIN_XI;
use crate::foveation::reconstruct::frame_jfa_steps;
use crate::settings::{Reconstruction, RenderSettings, Rung};

/// Every pass the renderer has, in the order a frame meets them (shadow, photons and pyramid run
/// once per static scene, before the frame that first needs them).
pub const PASSES: [&PassDecl; 16] = [
    &shadow::PASS,
    &photons::PASS,
    &pyramid::PASS,
    &gbuffer::PASS,
    &screen_diffusion::PASS,
    &sampling::PASS,
    &compact::PASS,
    &shade::PASS,
    &jfa::PASS,
    &resolve::PASS,
    &pull_push_tiles::PASS,
    &pull_push::PASS,
    &dof::PASS,
    &output::PASS,
    &low_pass::PASS,
    &i420::PASS,
];

/// Which optional passes a frame runs.
#[derive(Debug, Clone, PartialEq)]
pub struct FramePlan {
    /// Screen-space diffusion: the screen rung, and the scene plan gives something a dipole.
    pub screen_diffusion: bool,
    pub foveated: bool,
    /// Shade a compacted list rather than a masked full-frame dispatch.
    pub compaction: bool,
    pub dof: bool,
    /// Reconstruct with pull-push instead of jump flooding + resolve.
    pub pull_push: bool,
    /// Jump sizes of the JFA steps (foveated frames reconstructed from JFA).
    pub jfa_steps: Vec<u32>,
    /// Foveated encoding's low-pass of the output image, before the readback (and before
    /// `i420`, which converts the filtered image).
    pub low_pass: Option<low_pass::Filter>,
    /// Convert the output to I420 planes for the readback (H.264 sessions, even sizes).
    pub i420: bool,
    /// Gather the photons on the coarse lattice before shading a whole frame on a photon rung.
    pub coarse_gather: bool,
}

impl FramePlan {
    pub fn of(s: &RenderSettings, width: u32, height: u32, needs_dipole: bool) -> FramePlan {
        let fov = &s.foveation;
        FramePlan {
            screen_diffusion: s.translucency.rung == Rung::Screen && needs_dipole,
            foveated: fov.enabled,
            compaction: fov.compaction,
            dof: s.dof,
            pull_push: fov.enabled && fov.reconstruction == Reconstruction::PullPush,
            jfa_steps: if fov.enabled && fov.reconstruction != Reconstruction::PullPush {
                frame_jfa_steps(width, height, fov.min_probability, MIN_XI)
            } else {
                Vec::new()
            },
            low_pass: None,
            i420: false,
            coarse_gather: coarse_gather(s, needs_dipole),
        }
    }
}

/// Whether a frame gathers photons on the coarse lattice: asked for, shaded whole, and on a
/// photon rung with something to gather. One answer for the dispatch and the shader's mode.
pub fn coarse_gather(s: &RenderSettings, needs_dipole: bool) -> bool {
    s.translucency.coarse_gather
        && !s.foveation.enabled
        && needs_dipole
        && matches!(s.translucency.rung, Rung::Hierarchical | Rung::BruteForce)
}

/// Records the frame's passes into `f`'s encoder.
pub fn record(f: &mut Recorder, plan: &FramePlan, mesh: &MeshBuffers) -> Result<(), GraphError> {
    record_prefix(f, plan, mesh)?;
    if plan.foveated {
        // One band: every row.
        record_sampling(f)?;
        record_rows(f, plan, 0, f.size.1)?;
        record_reconstruction(f, plan, None)?;
    } else {
        shade::record_grid(f, plan.coarse_gather)?;
    }
    record_suffix(f, plan)
}

/// What comes before shading: the G-buffer and, on the screen rung, its diffusion. A sliced
/// frame records this, then (foveated) [`record_sampling`], [`record_rows`] per slice, then
/// (foveated) [`record_reconstruction`] in parts, then [`record_suffix`], each in its own
/// submission.
pub fn record_prefix(
    f: &mut Recorder,
    plan: &FramePlan,
    mesh: &MeshBuffers,
) -> Result<(), GraphError> {
    gbuffer::record(f, mesh)?;
    if plan.screen_diffusion {
        screen_diffusion::record(f)?;
    }
    f.route("frame.color", "shade.color");
    Ok(())
}

/// Foveated: the sampling map, and an empty list for the bands' samples.
pub fn record_sampling(f: &mut Recorder) -> Result<(), GraphError> {
    sampling::record(f)?;
    compact::clear(f)
}

/// Foveated, after shading: the next frame's colour history (the samples alone), then the
/// reconstruction, whole (`None`) or part `k` of `pull_push::PARTS` (JFA and resolve are
/// one part).
pub fn record_reconstruction(
    f: &mut Recorder,
    plan: &FramePlan,
    part: Option<u32>,
) -> Result<(), GraphError> {
    if part.unwrap_or(0) == 0 {
        // Before reconstruction: pull-push fills `shade.color` in place.
        keep_color_history(f)?;
    }
    if plan.pull_push {
        pull_push::record(f, part)
    } else if part.unwrap_or(0) == 0 {
        jfa::record(f, &plan.jfa_steps)?;
        resolve::record(f)
    } else {
        Ok(())
    }
}

/// The shading of rows `[first, end)`, one slice of a sliced frame (the frame uniform's
/// `shade_rows` holds the same rows): when foveated, those rows' samples listed and shaded,
/// else every pixel of them. The list also counts the samples (the header's `sampled`), so it
/// is built even when shading masks a full-frame dispatch instead of using it.
pub fn record_rows(
    f: &mut Recorder,
    plan: &FramePlan,
    first: u32,
    end: u32,
) -> Result<(), GraphError> {
    if plan.foveated {
        compact::record_rows(f, first, end)?;
    }
    if plan.foveated && plan.compaction {
        shade::record_list(f)
    } else {
        shade::record_rows(f, first, end, plan.coarse_gather)
    }
}

/// What comes last (after a foveated frame's reconstruction): depth of field, the output
/// image (low-passed and converted to I420 when asked), and the next frame's history (its
/// colour already, when foveated).
pub fn record_suffix(f: &mut Recorder, plan: &FramePlan) -> Result<(), GraphError> {
    if plan.dof {
        dof::record(f)?;
    }
    output::record(f)?;
    if let Some(filter) = &plan.low_pass {
        low_pass::record(f, filter)?;
    }
    if plan.i420 {
        i420::record(f)?;
    }
    if !plan.foveated {
        keep_color_history(f)?;
    }
    keep_depth_history(f)
}

/// The port of the reconstructed colour (resolve's or pull-push's), for inspection.
pub const RECONSTRUCTED: &str = "frame.reconstructed";

/// What the next frame reuses: this frame's shaded colour and G-buffer normal + distance.
pub const HISTORY: [(&str, &str); 2] = [
    ("shade.color", "history.color"),
    ("gbuffer.normal_distance", "history.normal_distance"),
];

/// The shaded colour: samples (and what reuse carried) only, never a reconstruction.
fn keep_color_history(f: &mut Recorder) -> Result<(), GraphError> {
    let [(color, history_color), _] = HISTORY;
    let (src, dst) = (f.buffer(color)?.clone(), f.buffer(history_color)?.clone());
    f.encoder
        .copy_buffer_to_buffer(&src, 0, &dst, 0, src.size());
    Ok(())
}

fn keep_depth_history(f: &mut Recorder) -> Result<(), GraphError> {
    let missing = |name| GraphError::Missing {
        pass: "history",
        name,
    };
    let [_, (nd, history_nd)] = HISTORY;
    let src = f.resources.get_texture(nd).ok_or(missing(nd))?.0;
    let dst = f
        .resources
        .get_texture(history_nd)
        .ok_or(missing(history_nd))?
        .0;
    f.encoder.copy_texture_to_texture(
        src.as_image_copy(),
        dst.as_image_copy(),
        wgpu::Extent3d {
            width: src.width(),
            height: src.height(),
            depth_or_array_layers: 1,
        },
    );
    Ok(())
}

/// The passes with what each reads and writes, as `docs/architecture.md` carries it (a test
/// checks the doc against this).
pub fn passes_markdown() -> String {
    let mut s = String::from("| # | pass | reads | writes |\n|---|---|---|---|\n");
    for (i, d) in PASSES.iter().enumerate() {
        let list = |names: Vec<&str>| {
            names
                .iter()
                .map(|n| format!("`{n}`"))
                .collect::<Vec<_>>()
                .join(", ")
        };
        s.push_str(&format!(
            "| {} | {} | {} | {} |\n",
            i + 1,
            d.label,
            list(d.reads()),
            list(d.writes())
        ));
    }
    s
}
