//! The foveated path on the GPU, held to its CPU twins and pushed to its extremes.

mod common;

use common::frames::{foveated, inspect, renderer};
use common::images::{assert_image, IDENTICAL, LAVAPIPE};
use fovea::foveation::rank_map;
use fovea::foveation::reconstruct::{jfa_with_steps, reconstruct, unpack, NO_SEED};
use fovea::optics::acuity::{acuity_probability, mar_deg, ProbabilityForm};
use fovea::render::uniforms::{FLAG_COVERED, FLAG_REUSED, FLAG_SAMPLED};
use fovea::render::{FrameRequest, Inspection, Renderer};
use fovea::scene::Scene;
use fovea::settings::{Noise, Reconstruction};
use fovea::viewing::Viewing;

fn assert_finite(what: &str, img: &Inspection) {
    for (k, v) in img.resolved.iter().enumerate() {
        assert!(
            v.iter().all(|c| c.is_finite()),
            "{what}: resolved pixel {k} is {v:?}"
        );
    }
    assert!(
        img.probability
            .iter()
            .all(|p| p.is_finite() && (0.0..=1.0).contains(p)),
        "{what}: probability"
    );
}

#[test]
fn with_every_pixel_sampled_the_foveated_path_equals_full_shading() {
    let mut r = renderer();
    let (w, h) = (120, 90);
    let mut full = FrameRequest::new("bunny", w, h);
    full.stream = 1;
    let reference = r.render(&full).unwrap();
    let mut all = foveated("balanced", w, h, [0.3, 0.6]);
    all.settings.foveation.min_probability = 1.0;
    all.stream = 2;
    let frame = r.render(&all).unwrap();
    // ξ = 1 must reproduce full shading exactly.
    assert_image(
        "xi_1_equals_full",
        &frame.rgba,
        &reference.rgba,
        w,
        h,
        IDENTICAL,
    );
    let covered = inspect(&r, &all)
        .flags
        .iter()
        .filter(|f| **f & FLAG_COVERED != 0)
        .count();
    assert!(
        (frame.sampled - covered as f64 / f64::from(w * h)).abs() < 1e-9,
        "sampled counts shaded pixels"
    );
    assert_eq!(reference.sampled, 1.0);
}

#[test]
fn sampling_map_matches_the_cpu_acuity_model() {
    let mut r = renderer();
    let (w, h) = (160, 120);
    for (stream, form, gaze) in [
        (1, ProbabilityForm::Density, [0.5, 0.5]),
        (2, ProbabilityForm::Linear, [0.1, 0.9]),
    ] {
        let mut req = foveated("balanced", w, h, gaze);
        req.stream = stream;
        let f = &mut req.settings.foveation;
        f.probability = form;
        f.saliency = false;
        f.motion = false;
        f.min_probability = 0.02;
        let f = req.settings.foveation;
        r.render(&req).unwrap();
        let img = inspect(&r, &req);
        let v = Viewing {
            width: w,
            height: h,
            width_cm: req.display.width_cm,
            distance_cm: req.display.distance_cm,
        };
        let g = [
            f64::from(gaze[0]) * f64::from(w),
            f64::from(gaze[1]) * f64::from(h),
        ];
        let (slope, w0) = (f64::from(f.mar_slope), f64::from(f.mar_w0_deg));
        let w_min = v.pixel_angle_deg();
        let w_far = mar_deg(v.max_eccentricity_deg(g), slope, w0);
        let thresholds = rank_map::thresholds();
        let mut checked = 0;
        for k in 0..(w * h) as usize {
            if img.flags[k] & FLAG_COVERED == 0 {
                continue;
            }
            let px = [(k as u32 % w) as f64 + 0.5, (k as u32 / w) as f64 + 0.5];
            let e = v.eccentricity_deg(g, px);
            let p = acuity_probability(form, mar_deg(e, slope, w0), w_min, w_far).max(0.02);
            let gpu = f64::from(img.probability[k]);
            assert!(
                (gpu - p).abs() < 1e-4,
                "{form:?} pixel {k}: GPU {gpu}, CPU {p} (bound 1e-4, from {LAVAPIPE})"
            );
            // First frame of a stream: tile offset (0, 0).
            let t =
                f64::from(thresholds[((k as u32 / w) % 64 * 64 + (k as u32 % w) % 64) as usize]);
            if (t - p).abs() > 1e-4 {
                assert_eq!(
                    img.flags[k] & FLAG_SAMPLED != 0,
                    t < p,
                    "{form:?} pixel {k}: threshold {t}, p {p}"
                );
            }
            checked += 1;
        }
        assert!(checked > 2000, "the bunny covers the frame: {checked}");
    }
}

#[test]
fn gpu_jump_flooding_and_resolve_match_the_cpu_twins() {
    let mut r = renderer();
    let (w, h) = (128, 96);
    for reconstruction in [Reconstruction::Nearest, Reconstruction::Sibson] {
        let mut req = foveated("fast", w, h, [0.45, 0.35]);
        req.settings.foveation.reconstruction = reconstruction;
        req.stream = 7;
        r.render(&req).unwrap();
        let img = inspect(&r, &req);
        let steps = fovea::foveation::reconstruct::frame_jfa_steps(
            w,
            h,
            req.settings.foveation.min_probability,
            fovea::render::MIN_XI,
        );
        let cpu_nearest = jfa_with_steps(w, h, &img.seeds, &steps);
        assert_eq!(img.nearest, cpu_nearest, "JFA: GPU and CPU differ");
        let covered: Vec<bool> = img.flags.iter().map(|f| f & FLAG_COVERED != 0).collect();
        let window = (reconstruction == Reconstruction::Sibson)
            .then(|| req.settings.foveation.sibson_max_window());
        let cpu = reconstruct(w, h, &img.nearest, &covered, &img.color, &img.color, window);
        let mut worst = 0.0f32;
        for k in 0..covered.len() {
            if covered[k] && img.nearest[k] != NO_SEED {
                for c in 0..3 {
                    worst = worst.max((cpu[k][c] - img.resolved[k][c]).abs());
                }
            }
        }
        // The GPU stores the result as f16: relative error ≤ 2⁻¹¹ on values ≤ 1.
        assert!(
            worst < 1e-3,
            "{reconstruction:?}: GPU resolve differs from CPU by {worst}"
        );
    }
}

#[test]
fn every_seed_is_a_shaded_or_reused_covered_pixel() {
    let mut r = renderer();
    let req = foveated("balanced", 96, 96, [0.5, 0.5]);
    r.render(&req).unwrap();
    let img = inspect(&r, &req);
    for (k, &s) in img.seeds.iter().enumerate() {
        let f = img.flags[k];
        let is_seed = f & FLAG_COVERED != 0 && f & (FLAG_SAMPLED | FLAG_REUSED) != 0;
        assert_eq!(s != NO_SEED, is_seed, "pixel {k}: flags {f:#b}");
        if s != NO_SEED {
            let (x, y) = unpack(s);
            assert_eq!((y * 96 + x) as usize, k);
        }
    }
}

#[test]
fn compaction_changes_the_cost_not_the_image() {
    let mut r = renderer();
    let mut a = foveated("balanced", 120, 90, [0.6, 0.4]);
    a.stream = 1;
    let mut b = a.clone();
    b.settings.foveation.compaction = false;
    b.stream = 2;
    let fa = r.render(&a).unwrap();
    let fb = r.render(&b).unwrap();
    assert_image(
        "compaction_on_vs_off",
        &fb.rgba,
        &fa.rgba,
        120,
        90,
        IDENTICAL,
    );
    assert!(
        fa.sampled > 0.0 && fa.sampled < 0.5,
        "sampled {}",
        fa.sampled
    );
}

#[test]
fn static_view_reuses_history_and_a_camera_jump_invalidates_all_of_it() {
    let mut r = renderer();
    let mut req = foveated("balanced", 120, 90, [0.5, 0.5]);
    req.stream = 3;
    r.render(&req).unwrap();
    let first = inspect(&r, &req);
    assert_eq!(
        first
            .flags
            .iter()
            .filter(|f| **f & FLAG_REUSED != 0)
            .count(),
        0,
        "nothing to reuse on frame 1"
    );
    r.render(&req).unwrap();
    let second = inspect(&r, &req);
    let covered = second
        .flags
        .iter()
        .filter(|f| **f & FLAG_COVERED != 0)
        .count();
    let sampled = second
        .flags
        .iter()
        .filter(|f| **f & FLAG_SAMPLED != 0)
        .count();
    let reused = second
        .flags
        .iter()
        .filter(|f| **f & FLAG_REUSED != 0)
        .count();
    // Static view: every unsampled pixel that was a seed last frame passes the depth test.
    let was_seed = first
        .seeds
        .iter()
        .zip(&second.flags)
        .filter(|(s, f)| **s != NO_SEED && **f & FLAG_SAMPLED == 0)
        .count();
    assert_eq!(reused, was_seed, "covered {covered}, sampled {sampled}");

    let scene = Scene::builtin("bunny").unwrap();
    let mut cam = scene.file.camera;
    cam.eye = [30.0, 5.0, -10.0];
    req.camera = Some(cam);
    r.render(&req).unwrap();
    let jumped = inspect(&r, &req);
    let reused_after_jump = jumped
        .flags
        .iter()
        .filter(|f| **f & FLAG_REUSED != 0)
        .count();
    assert!(
        reused_after_jump * 100 < covered,
        "after a camera jump {reused_after_jump} pixels reused"
    );
    assert_finite("camera jump", &jumped);
}

#[test]
fn history_age_cap_forces_misses() {
    let mut r = renderer();
    let mut req = foveated("balanced", 96, 72, [0.5, 0.5]);
    req.settings.foveation.max_history_age = 0;
    req.stream = 4;
    r.render(&req).unwrap();
    r.render(&req).unwrap();
    let img = inspect(&r, &req);
    assert_eq!(
        img.flags.iter().filter(|f| **f & FLAG_REUSED != 0).count(),
        0,
        "age cap 0 reuses nothing"
    );
}

#[test]
fn extremes_give_finite_sensible_frames() {
    let mut r = renderer();
    let scene = Scene::builtin("bunny").unwrap();
    let mut cases: Vec<(String, FrameRequest)> = Vec::new();
    for gaze in [[0.0, 0.0], [1.0, 1.0], [0.0, 1.0], [1.0, 0.5], [0.5, 0.5]] {
        for r in [Reconstruction::PullPush, Reconstruction::Nearest] {
            let mut q = foveated("fast", 80, 60, gaze);
            q.settings.foveation.reconstruction = r;
            cases.push((format!("gaze {gaze:?}, {r:?}"), q));
        }
    }
    for xi in [0.0, 1.0] {
        let mut q = foveated("balanced", 80, 60, [0.0, 0.0]);
        q.settings.foveation.min_probability = xi;
        cases.push((format!("ξ = {xi}"), q));
    }
    for pupil in [1.0, 2.0, 8.0, 10.0] {
        let mut q = foveated("balanced", 80, 60, [0.5, 0.4]);
        q.settings.dof = true;
        q.pupil_mm = pupil;
        cases.push((format!("pupil {pupil} mm"), q));
    }
    for (w, h) in [(1, 1), (2, 1), (97, 31), (33, 200)] {
        cases.push((format!("{w}x{h}"), foveated("balanced", w, h, [0.5, 0.5])));
    }
    let mut near = foveated("balanced", 80, 60, [0.5, 0.5]);
    let mut cam = scene.file.camera;
    cam.eye = [0.0, 5.0, 3.0]; // inside the bunny's bounding box: the near plane cuts it
    near.camera = Some(cam);
    cases.push(("near plane".into(), near));
    let mut far = foveated("balanced", 80, 60, [0.5, 0.5]);
    let mut cam = scene.file.camera;
    cam.far = 24.5; // the far plane cuts through the bunny
    far.camera = Some(cam);
    cases.push(("far plane".into(), far));
    let mut white = foveated("fast", 80, 60, [0.3, 0.3]);
    white.settings.foveation.noise = Noise::White;
    cases.push(("white noise".into(), white));
    for (i, (what, mut q)) in cases.into_iter().enumerate() {
        q.stream = 100 + i as u64;
        let frame = r.render(&q).unwrap_or_else(|e| panic!("{what}: {e}"));
        assert_eq!(
            frame.rgba.len(),
            (q.width * q.height * 4) as usize,
            "{what}"
        );
        assert!(
            frame.sampled.is_finite() && (0.0..=1.0).contains(&frame.sampled),
            "{what}: sampled {}",
            frame.sampled
        );
        assert_finite(&what, &inspect(&r, &q));
    }
}

#[test]
fn with_xi_zero_and_gaze_off_the_object_only_the_forced_minimum_is_shaded() {
    let mut r = renderer();
    let (w, h) = (256, 192);
    let mut q = foveated("fast", w, h, [0.0, 0.0]);
    let f = &mut q.settings.foveation;
    f.min_probability = 0.0;
    f.mar_slope = 1.0; // acuity collapses a few pixels from the gaze
    f.saliency = false;
    q.stream = 9;
    let frame = r.render(&q).unwrap();
    let img = inspect(&r, &q);
    let covered = img.flags.iter().filter(|f| **f & FLAG_COVERED != 0).count();
    let sampled = img.flags.iter().filter(|f| **f & FLAG_SAMPLED != 0).count();
    // One shaded pixel per 64×64 tile at least, and hardly more.
    assert!(
        sampled >= 1 && sampled * 500 < covered,
        "{sampled} of {covered} covered pixels sampled"
    );
    assert!(frame.sampled > 0.0);
    assert_finite("forced minimum", &img);
}

#[test]
fn saliency_in_the_sampling_map_matches_the_cpu_twin() {
    // The shader decides 2×2 blocks of pixels: an odd size leaves blocks half outside.
    let mut r = renderer();
    for (w, h) in [(120, 90), (121, 91)] {
        saliency_matches_at(&mut r, w, h);
    }
}

fn saliency_matches_at(r: &mut Renderer, w: u32, h: u32) {
    use fovea::optics::saliency::saliency;
    let mut req = foveated("balanced", w, h, [0.0, 0.0]);
    let f = &mut req.settings.foveation;
    f.motion = false;
    f.min_probability = 0.0;
    f.mar_slope = 1.0; // acuity ≈ 0 away from the corner: the map is saliency alone
    req.stream = 5 + u64::from(w % 2);
    let scene = Scene::builtin("bunny").unwrap();
    r.render(&req).unwrap();
    let img = inspect(r, &req);
    let (wi, hi) = (w as i32, h as i32);
    let mut salient = 0;
    for y in 0..hi {
        for x in 0..wi {
            let k = (y * wi + x) as usize;
            // Every pixel is decided, the last column and row of an odd size included.
            let covered = img.normal_distance[k][3] > 0.0;
            assert_eq!(
                img.flags[k] & FLAG_COVERED != 0,
                covered,
                "{w}x{h}: ({x},{y})"
            );
            if !covered || x < 8 || y < 8 {
                continue;
            }
            let mut albedo = [[0.0f32; 3]; 9];
            let mut normal = [[0.0f32; 3]; 9];
            for j in 0..3 {
                for i in 0..3 {
                    let q =
                        ((y + j - 1).clamp(0, hi - 1) * wi + (x + i - 1).clamp(0, wi - 1)) as usize;
                    if img.flags[q] & FLAG_COVERED != 0 {
                        albedo[(j * 3 + i) as usize] =
                            scene.materials[0].1.albedo().map(|a| a as f32);
                        let n = img.normal_distance[q];
                        normal[(j * 3 + i) as usize] = [n[0], n[1], n[2]];
                    }
                }
            }
            let cpu = saliency(&albedo, &normal).max(fovea::render::MIN_XI);
            let gpu = img.probability[k];
            assert!(
                (gpu - cpu).abs() < 2e-3,
                "pixel ({x},{y}): GPU {gpu}, CPU {cpu}"
            );
            if cpu > 0.5 {
                salient += 1;
            }
        }
    }
    assert!(
        salient > 50,
        "silhouettes and creases are salient: {salient} pixels"
    );
}

#[test]
fn depth_of_field_lowers_the_sampling_map_as_the_cpu_model_says() {
    use fovea::optics::acuity::{blur_angle_rad, dof_factor};
    let mut r = renderer();
    let (w, h) = (160, 120);
    let gaze = [0.5f32, 0.55f32];
    let scene = Scene::builtin("bunny").unwrap();
    let mut out_of_focus = Vec::new();
    for pupil in [2.0f32, 8.0] {
        let mut req = foveated("balanced", w, h, gaze);
        req.stream = 40 + pupil as u64;
        req.pupil_mm = pupil;
        req.settings.dof = true;
        let f = &mut req.settings.foveation;
        f.saliency = false;
        f.motion = false;
        f.min_probability = 0.0;
        let f = req.settings.foveation;
        r.render(&req).unwrap();
        let img = inspect(&r, &req);
        let v = Viewing {
            width: w,
            height: h,
            width_cm: req.display.width_cm,
            distance_cm: req.display.distance_cm,
        };
        let g = [
            f64::from(gaze[0]) * f64::from(w),
            f64::from(gaze[1]) * f64::from(h),
        ];
        let (slope, w0) = (f64::from(f.mar_slope), f64::from(f.mar_w0_deg));
        let (w_min, w_far) = (
            v.pixel_angle_deg(),
            mar_deg(v.max_eccentricity_deg(g), slope, w0),
        );
        // Focus: the distance under the gaze pixel; metres per unit and radians per pixel as the renderer sets them.
        let gk = (g[1].floor() as u32 * w + g[0].floor() as u32) as usize;
        let under_gaze = f64::from(img.normal_distance[gk][3]);
        // Off the object the eye focuses at the camera's target distance (as the shader does).
        let cam = scene.file.camera;
        let target = glam::Vec3::from(cam.target).distance(glam::Vec3::from(cam.eye)) as f64;
        let focus_m = if under_gaze > 0.0 { under_gaze } else { target } * scene.metres_per_unit();
        assert!(under_gaze > 0.0, "the gaze is on the bunny");
        let rad_per_px = f64::from(scene.file.camera.fov_y_deg).to_radians() / f64::from(h);
        let (mut checked, mut lowered) = (0, 0);
        for k in 0..(w * h) as usize {
            if img.flags[k] & FLAG_COVERED == 0 {
                continue;
            }
            let px = [(k as u32 % w) as f64 + 0.5, (k as u32 / w) as f64 + 0.5];
            let p = acuity_probability(
                f.probability,
                mar_deg(v.eccentricity_deg(g, px), slope, w0),
                w_min,
                w_far,
            );
            let d_m = f64::from(img.normal_distance[k][3]) * scene.metres_per_unit();
            let blur_px = blur_angle_rad(f64::from(pupil), focus_m, d_m) / rad_per_px;
            let expected = (p * dof_factor(blur_px)).max(f64::from(fovea::render::MIN_XI));
            let gpu = f64::from(img.probability[k]);
            assert!(
                (gpu - expected).abs() < 1e-3 + 2e-3 * expected,
                "pupil {pupil} pixel {k}: GPU {gpu}, CPU {expected}"
            );
            checked += 1;
            lowered += usize::from(dof_factor(blur_px) < 1.0);
        }
        assert!(checked > 2000);
        out_of_focus.push(lowered);
    }
    // A wider pupil narrows the in-focus band: more pixels are blurred and sampled less.
    assert!(
        out_of_focus[1] > 100 && out_of_focus[1] > out_of_focus[0],
        "out of focus at 2 and 8 mm: {out_of_focus:?}"
    );
}
