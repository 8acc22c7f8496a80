//! Everything a frame's passes read from the uniform buffer, computed from the request.

use glam::Vec3;

use super::renderer::{FrameRequest, MIN_XI};
use super::targets::FrameTargets;
use super::uniforms::*;
use crate::foveation::rank_map;
use crate::foveation::reprojection::DEFAULT_EPSILON;
use crate::foveation::{Noise, Reconstruction, Rung};
use crate::optics::acuity::{mar_deg, ProbabilityForm, Viewing};
use crate::optics::color::srgb8_to_linear;
use crate::scene::{Camera, Scene};

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

pub(super) fn frame_uniform(
    scene: &Scene,
    camera: &Camera,
    req: &FrameRequest,
    t: &FrameTargets,
    to_light: Vec3,
    pyramid_ready: bool,
) -> FrameUniform {
    let (w, h) = (req.width, req.height);
    let view_proj = camera.view_proj(w, h);
    let eye = Vec3::from(camera.eye);
    let (prev_view_proj, prev_eye, history) = if t.has_history {
        (t.prev_view_proj, t.prev_eye, 1.0)
    } else {
        (view_proj, eye, 0.0)
    };
    let s = &req.settings;
    let fov = &s.foveation;
    let mut mode = 0;
    for (on, bit) in [
        (fov.enabled, MODE_FOVEATED),
        (fov.saliency, MODE_SALIENCY),
        (fov.motion, MODE_MOTION),
        (fov.noise == Noise::White, MODE_WHITE_NOISE),
        (fov.reprojection, MODE_REPROJECTION),
        (fov.reconstruction == Reconstruction::Sibson, MODE_SIBSON),
        (s.dof, MODE_DOF),
        (!s.indirect, MODE_DIRECT_ONLY),
    ] {
        if on {
            mode |= bit;
        }
    }
    let viewing = Viewing {
        width: w,
        height: h,
        width_cm: req.display.width_cm,
        distance_cm: req.display.distance_cm,
    };
    let gaze_px = [
        f64::from(req.gaze[0]) * f64::from(w),
        f64::from(req.gaze[1]) * f64::from(h),
    ];
    let w_min = viewing.pixel_angle_deg();
    let w_far = mar_deg(
        viewing.max_eccentricity_deg(gaze_px),
        f64::from(fov.mar_slope),
        f64::from(fov.mar_w0_deg),
    );
    let lighting = &scene.file.light;
    let light = Vec3::from(lighting.color) * lighting.intensity;
    let photon_radius_mm = super::pass::photons::photon_radius_mm(scene);
    let target_distance = (Vec3::from(camera.target) - eye).length();
    let offset = tile_offset(t.frame_index);
    let overlay = match s.overlay {
        crate::foveation::settings::Overlay::None => 0,
        crate::foveation::settings::Overlay::Samples => 1,
        crate::foveation::settings::Overlay::Probability => 2,
    };
    FrameUniform {
        view_proj: view_proj.to_cols_array_2d(),
        inv_view_proj: view_proj.inverse().to_cols_array_2d(),
        prev_view_proj: prev_view_proj.to_cols_array_2d(),
        eye: eye.extend(scene.metres_per_unit() as f32).to_array(),
        prev_eye: prev_eye.extend(history).to_array(),
        to_light: to_light.extend(0.0).to_array(),
        light: light.extend(0.0).to_array(),
        albedo_ambient: [0.0, 0.0, 0.0, scene.file.ambient],
        background: Vec3::from(scene.file.background_srgb.map(srgb8_to_linear))
            .extend(1.0)
            .to_array(),
        size: [w, h, t.frame_index, mode],
        gaze: [
            gaze_px[0] as f32,
            gaze_px[1] as f32,
            req.pupil_mm,
            target_distance,
        ],
        viewing: [
            (viewing.width_cm / f64::from(w)) as f32,
            viewing.distance_cm as f32,
            w_min as f32,
            w_far as f32,
        ],
        acuity: [
            fov.mar_slope,
            fov.mar_w0_deg,
            // The forced minimum: ξ never drops below one sample per blue-noise tile, so every
            // 64×64 block of the object keeps at least one shaded sample to reconstruct from.
            fov.min_probability.clamp(MIN_XI, 1.0),
            if fov.probability == ProbabilityForm::Density {
                1.0
            } else {
                0.0
            },
        ],
        temporal: [
            fov.max_history_age as f32,
            DEFAULT_EPSILON,
            camera.fov_y_deg.to_radians() / h as f32,
            fov.sibson_max_window() as f32,
        ],
        tile: [offset[0], offset[1], overlay, 0],
        marker: if req.marker {
            let (radius, thickness) = super::pass::output::marker_size(w, h);
            [gaze_px[0] as f32, gaze_px[1] as f32, radius, thickness]
        } else {
            [0.0; 4]
        },
        photon: [
            super::pass::photons::SIDE as f32,
            photon_radius_mm as f32,
            super::pass::photons::START_LEVEL as f32,
            scene.file.mm_per_unit as f32,
        ],
        cut: [
            s.translucency
                .cut_level
                .min(super::pass::photons::START_LEVEL) as f32,
            s.translucency.cut_epsilon.max(0.0),
            match s.translucency.rung {
                Rung::Opaque => 0.0,
                Rung::NormalBlur => 1.0,
                Rung::Screen => 2.0,
                Rung::Hierarchical => 3.0,
                Rung::BruteForce => 4.0,
            },
            if pyramid_ready { 1.0 } else { 0.0 },
        ],
    }
}
