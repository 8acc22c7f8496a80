//! Everything a frame's passes read from the uniform buffer, computed from the request.

use glam::Vec3;

use super::pass::photons;
use super::request::{FrameRequest, MIN_XI};
use super::targets::FrameTargets;
use super::uniforms::*;
use crate::foveation::rank_map;
use crate::foveation::reprojection::DEFAULT_EPSILON;
use crate::optics::acuity::mar_deg;
use crate::optics::color::srgb8_to_linear;
use crate::scene::{Camera, Scene};
use crate::settings::{Noise, Reconstruction};
use crate::viewing::Viewing;

/// The R2 low-discrepancy sequence: tile offsets that cover the tile evenly over frames.
fn tile_offset(frame: u32) -> [u32; 2] {
    const G: f64 = 1.324_717_957_244_746;
    let n = f64::from(frame);
    let side = f64::from(rank_map::TILE);
    [
        ((n / G).fract() * side) as u32,
        ((n / (G * G)).fract() * side) as u32,
    ]
}

/// The frame's MODE_* bits from its settings.
fn mode_bits(s: &crate::settings::RenderSettings) -> u32 {
    let fov = &s.foveation;
    let mut mode = 0;
    for (on, bit) in [
        (fov.enabled, MODE_FOVEATED),
        (fov.saliency, MODE_SALIENCY),
        (fov.edges_at_mar, MODE_EDGES_AT_MAR),
        (fov.motion, MODE_MOTION),
        (fov.noise == Noise::White, MODE_WHITE_NOISE),
        (fov.reprojection, MODE_REPROJECTION),
        (fov.reconstruction == Reconstruction::Sibson, MODE_SIBSON),
        (
            fov.reconstruction == Reconstruction::PullPush,
            MODE_DEMODULATED,
        ),
        (s.dof, MODE_DOF),
        (!s.indirect, MODE_DIRECT_ONLY),
        (!s.shadows, MODE_NO_SHADOWS),
        (!s.specular, MODE_NO_SPECULAR),
    ] {
        if on {
            mode |= bit;
        }
    }
    mode
}

/// The MODE_* bits that follow from the stream's targets and history rather than the settings
/// alone: the coarse gather (planned per frame size), the still camera, and the kept saliency
/// (still camera and the last frame's settings: the G-buffer is the last frame's).
fn history_bits(s: &crate::settings::RenderSettings, t: &FrameTargets, still: bool) -> u32 {
    let mut mode = 0;
    if super::frame::coarse_gather(s, t.needs_dipole) {
        mode |= MODE_COARSE_GATHER;
    }
    if still {
        mode |= MODE_STILL_CAMERA;
        if s.foveation.saliency && t.prev_settings.as_ref() == Some(s) {
            mode |= MODE_SALIENCY_CACHED;
        }
    }
    mode
}

pub(super) fn frame_uniform(
    scene: &Scene,
    camera: &Camera,
    req: &FrameRequest,
    t: &FrameTargets,
    to_light: Vec3,
    pyramid_ready: bool,
    shadow_ready: bool,
) -> FrameUniform {
    let (w, h) = (req.width, req.height);
    let view_proj = camera.view_proj(w, h);
    let eye = Vec3::from(camera.eye);
    let (prev_view_proj, prev_eye, history) = if t.has_history {
        (t.prev_view_proj, t.prev_eye, true)
    } else {
        (view_proj, eye, false)
    };
    let s = &req.settings;
    let fov = &s.foveation;
    let still = history && prev_view_proj == view_proj && prev_eye == eye;
    let mode = mode_bits(s) | history_bits(s, t, still);
    let viewing = Viewing::new(req.display, w, h);
    let gaze_px = viewing.to_pixels(req.gaze.map(f64::from));
    let w_min = viewing.pixel_angle_deg();
    let w_far = mar_deg(
        viewing.max_eccentricity_deg(gaze_px),
        f64::from(fov.mar_slope),
        f64::from(fov.mar_w0_deg),
    );
    let mut shadow = super::pass::shadow::shadow_view(scene, to_light);
    if !shadow_ready {
        shadow.params[2] = 0.0;
    }
    let lighting = &scene.file.light;
    let light = Vec3::from(lighting.color) * lighting.intensity;
    let target_distance = (Vec3::from(camera.target) - eye).length();
    let marker = if req.marker {
        let (radius, thickness) = super::pass::output::marker_size(w, h);
        ([gaze_px[0] as f32, gaze_px[1] as f32], radius, thickness)
    } else {
        ([0.0; 2], 0.0, 0.0)
    };
    FrameUniform {
        view_proj: view_proj.to_cols_array_2d(),
        inv_view_proj: view_proj.inverse().to_cols_array_2d(),
        prev_view_proj: prev_view_proj.to_cols_array_2d(),
        eye: eye.to_array(),
        metres_per_unit: scene.metres_per_unit() as f32,
        prev_eye: prev_eye.to_array(),
        has_history: u32::from(history),
        to_light: to_light.to_array(),
        ambient: scene.file.ambient,
        light: light.to_array(),
        mm_per_unit: scene.file.mm_per_unit as f32,
        background: scene.file.background_srgb.map(srgb8_to_linear),
        overlay: s.overlay.id(),
        width: w,
        height: h,
        frame_index: t.frame_index,
        mode,
        gaze_px: [gaze_px[0] as f32, gaze_px[1] as f32],
        pupil_mm: req.pupil_mm,
        focus_distance: target_distance,
        cm_per_pixel: (viewing.width_cm / f64::from(w)) as f32,
        distance_cm: viewing.distance_cm as f32,
        w_min_deg: w_min as f32,
        w_far_deg: w_far as f32,
        mar_slope: fov.mar_slope,
        mar_w0_deg: fov.mar_w0_deg,
        // The forced minimum: ξ never drops below one sample per blue-noise tile, so every
        // 64×64 block of the object keeps at least one shaded sample to reconstruct from.
        min_probability: fov.min_probability.clamp(MIN_XI, 1.0),
        probability_form: probability_form_id(fov.probability),
        max_history_age: fov.max_history_age,
        depth_epsilon: DEFAULT_EPSILON,
        radians_per_pixel: camera.fov_y_deg.to_radians() / h as f32,
        sibson_window: fov.sibson_max_window(),
        tile_offset: tile_offset(t.frame_index),
        marker_centre: marker.0,
        marker_radius: marker.1,
        marker_thickness: marker.2,
        photon_side: photons::SIDE,
        photon_radius_mm: photons::photon_radius_mm(scene) as f32,
        photon_start_level: photons::START_LEVEL,
        cut_level: s.translucency.cut_level.min(photons::START_LEVEL),
        cut_epsilon: s.translucency.cut_epsilon.max(0.0),
        rung: s.translucency.rung.id(),
        pyramid_ready: u32::from(pyramid_ready),
        light_count: scene.file.lights.len() as u32,
        shade_rows: [0, h],
        shadow_view_proj: shadow.view_proj.to_cols_array_2d(),
        shadow_params: shadow.params,
    }
}
