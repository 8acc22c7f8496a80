//! The frame's uniforms: the Rust twin of `struct Frame` in `shaders/common.wgsl`, with named
//! integer and enum fields, and the one source of the constants both sides share (modes, pixel
//! flags, rung, overlay and probability-form ids): [`wgsl_constants`] writes them into the WGSL
//! prelude, so no shader carries a hand copy. `tests/shaders.rs` compares every field offset
//! and every constant with what naga reads from the shaders.

use bytemuck::{Pod, Zeroable};

use crate::optics::acuity::ProbabilityForm;
use crate::settings::{Overlay, Rung};

pub const MODE_FOVEATED: u32 = 1;
pub const MODE_SALIENCY: u32 = 2;
pub const MODE_MOTION: u32 = 4;
pub const MODE_WHITE_NOISE: u32 = 8;
pub const MODE_REPROJECTION: u32 = 16;
pub const MODE_SIBSON: u32 = 32;
pub const MODE_DOF: u32 = 64;
/// Radiosity's direct light only (the interreflected part left out, for comparison).
pub const MODE_DIRECT_ONLY: u32 = 128;
/// The key light's shadow map is not consulted.
pub const MODE_NO_SHADOWS: u32 = 256;
/// No specular lobe and no interface losses.
pub const MODE_NO_SPECULAR: u32 = 512;
/// Reconstruction works on colour divided by what the G-buffer predicts (pull-push), so albedo
/// edges need no extra samples: saliency looks at normals only.
pub const MODE_DEMODULATED: u32 = 1024;
/// Saliency raises the probability to S·√p rather than S (edges sampled at the MAR along them,
/// p the acuity `optics::acuity::EDGE_MARGIN_DEG` nearer the gaze).
pub const MODE_EDGES_AT_MAR: u32 = 2048;
/// The photon rungs gather on the coarse lattice and interpolate (`shade.wgsl`, `gather_coarse`).
pub const MODE_COARSE_GATHER: u32 = 4096;
/// The camera has not moved since the last frame (and there is one): the scene's geometry is
/// static, so every pixel reprojects onto itself and the reprojection is skipped.
pub const MODE_STILL_CAMERA: u32 = 8192;
/// Still camera, same settings as the last frame: the G-buffer is the last frame's, so the
/// sampling pass reads the saliency it kept instead of computing it again.
pub const MODE_SALIENCY_CACHED: u32 = 16384;
/// `SPECIALISED_MODE` of a pipeline that reads the mode bits from the frame uniforms.
pub const NOT_SPECIALISED: u32 = u32::MAX;

/// Per-pixel state written by the sampling pass.
pub const FLAG_COVERED: u32 = 1;
pub const FLAG_SAMPLED: u32 = 2;
pub const FLAG_REUSED: u32 = 4;

/// Every integer constant the shaders share with Rust, by its WGSL name.
pub fn constants() -> Vec<(&'static str, u32)> {
    vec![
        ("MODE_FOVEATED", MODE_FOVEATED),
        ("MODE_SALIENCY", MODE_SALIENCY),
        ("MODE_MOTION", MODE_MOTION),
        ("MODE_WHITE_NOISE", MODE_WHITE_NOISE),
        ("MODE_REPROJECTION", MODE_REPROJECTION),
        ("MODE_SIBSON", MODE_SIBSON),
        ("MODE_DOF", MODE_DOF),
        ("MODE_DIRECT_ONLY", MODE_DIRECT_ONLY),
        ("MODE_NO_SHADOWS", MODE_NO_SHADOWS),
        ("MODE_NO_SPECULAR", MODE_NO_SPECULAR),
        ("MODE_DEMODULATED", MODE_DEMODULATED),
        ("MODE_EDGES_AT_MAR", MODE_EDGES_AT_MAR),
        ("MODE_COARSE_GATHER", MODE_COARSE_GATHER),
        ("MODE_STILL_CAMERA", MODE_STILL_CAMERA),
        ("MODE_SALIENCY_CACHED", MODE_SALIENCY_CACHED),
        ("NOT_SPECIALISED", NOT_SPECIALISED),
        ("FLAG_COVERED", FLAG_COVERED),
        ("LOBE_TABLE", crate::optics::specular::ALBEDO_TABLE as u32),
        ("EDGE_MARGIN_DEG", crate::optics::acuity::EDGE_MARGIN_DEG),
        ("FLAG_SAMPLED", FLAG_SAMPLED),
        ("FLAG_REUSED", FLAG_REUSED),
        ("RUNG_OPAQUE", Rung::Opaque.id()),
        ("RUNG_NORMAL_BLUR", Rung::NormalBlur.id()),
        ("RUNG_SCREEN", Rung::Screen.id()),
        ("RUNG_HIERARCHICAL", Rung::Hierarchical.id()),
        ("RUNG_BRUTE_FORCE", Rung::BruteForce.id()),
        ("OVERLAY_NONE", Overlay::None.id()),
        ("OVERLAY_SAMPLES", Overlay::Samples.id()),
        ("OVERLAY_PROBABILITY", Overlay::Probability.id()),
        (
            "PROBABILITY_LINEAR",
            probability_form_id(ProbabilityForm::Linear),
        ),
        (
            "PROBABILITY_DENSITY",
            probability_form_id(ProbabilityForm::Density),
        ),
        ("NO_SEED", crate::foveation::reconstruct::NO_SEED),
        ("KIND_OPAQUE", super::materials::KIND_OPAQUE),
        ("KIND_TRANSLUCENT", super::materials::KIND_TRANSLUCENT),
        ("KIND_EMITTER", super::materials::KIND_EMITTER),
    ]
}

pub fn probability_form_id(form: ProbabilityForm) -> u32 {
    match form {
        ProbabilityForm::Linear => 0,
        ProbabilityForm::Density => 1,
    }
}

/// The shared constants as WGSL declarations, placed in front of every shader.
pub fn wgsl_constants() -> String {
    let mut s = String::from("// Generated from src/render/uniforms.rs: edit there.\n");
    for (name, value) in constants() {
        s.push_str(&format!("const {name}: u32 = {value}u;\n"));
    }
    s
}

/// Declares `FrameUniform` and `FIELDS` (each field's name and byte offset) from one list.
macro_rules! frame_uniform {
    ($( $(#[doc = $doc:literal])* $name:ident : $ty:ty ),* $(,)?) => {
        #[repr(C)]
        #[derive(Clone, Copy, Pod, Zeroable, Debug, Default)]
        pub struct FrameUniform {
            $( $(#[doc = $doc])* pub $name: $ty, )*
        }

        /// Every field of [`FrameUniform`] with its byte offset (padding starts with `_`).
        pub const FIELDS: &[(&str, usize)] = &[
            $( (stringify!($name), std::mem::offset_of!(FrameUniform, $name)), )*
        ];
    };
}

frame_uniform! {
    view_proj: [[f32; 4]; 4],
    inv_view_proj: [[f32; 4]; 4],
    prev_view_proj: [[f32; 4]; 4],
    /// Camera position, scene units.
    eye: [f32; 3],
    metres_per_unit: f32,
    /// Last frame's camera position.
    prev_eye: [f32; 3],
    /// 1 when last frame's buffers are valid history.
    has_history: u32,
    /// Unit vector towards the light.
    to_light: [f32; 3],
    /// Ambient light as a fraction of the key light.
    ambient: f32,
    /// Light colour × intensity.
    light: [f32; 3],
    mm_per_unit: f32,
    /// Background colour, linear.
    background: [f32; 3],
    /// OVERLAY_* id.
    overlay: u32,
    width: u32,
    height: u32,
    frame_index: u32,
    /// MODE_* bits.
    mode: u32,
    /// Gaze in pixels, top-left origin.
    gaze_px: [f32; 2],
    pupil_mm: f32,
    /// Distance to the camera's target, scene units (the focus of depth of field).
    focus_distance: f32,
    /// Display centimetres per pixel.
    cm_per_pixel: f32,
    distance_cm: f32,
    /// The pixel's angle w_min, degrees.
    w_min_deg: f32,
    /// MAR at the frame's farthest point, degrees.
    w_far_deg: f32,
    /// MAR slope m, degrees per degree of eccentricity.
    mar_slope: f32,
    /// MAR at the fovea w0, degrees.
    mar_w0_deg: f32,
    /// Minimum sampling probability ξ.
    min_probability: f32,
    /// PROBABILITY_* id.
    probability_form: u32,
    /// Frames a reused colour may age.
    max_history_age: u32,
    /// Relative depth tolerance ε of the reprojection test.
    depth_epsilon: f32,
    /// Camera radians per pixel.
    radians_per_pixel: f32,
    /// Sibson window bound, pixels.
    sibson_window: u32,
    /// Blue-noise tile offset this frame.
    tile_offset: [u32; 2],
    /// Gaze marker centre, pixels.
    marker_centre: [f32; 2],
    /// Gaze marker ring radius, pixels; 0: no marker.
    marker_radius: f32,
    marker_thickness: f32,
    /// Photon map side.
    photon_side: u32,
    /// A photon's radius, mm (its texel footprint as a disc).
    photon_radius_mm: f32,
    /// Pyramid level traversal starts from.
    photon_start_level: u32,
    /// The finest pyramid level a cluster may come from.
    cut_level: u32,
    /// A cluster is used when its extent < ε × its distance.
    cut_epsilon: f32,
    /// RUNG_* id.
    rung: u32,
    /// 1 when the photon pyramid has been built for this light.
    pyramid_ready: u32,
    /// How many entries of `lights.scene` (extra punctual lights) shade this frame.
    light_count: u32,
    /// Rows [first, end) the shading grid covers: the whole frame, or one slice of a frame
    /// split so other sessions' frames can run between its slices.
    shade_rows: [u32; 2],
    /// World → the key light's shadow map (x, y in NDC, z in 0..1).
    shadow_view_proj: [[f32; 4]; 4],
    /// x: depth bias (shadow-map depth units); y: normal offset (scene units); z: 1 when the
    /// key light casts shadows; w: shadow map side.
    shadow_params: [f32; 4],
}
