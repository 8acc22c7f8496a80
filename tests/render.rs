//! GPU tests on whatever adapter the machine has (the software Vulkan driver in CI). No adapter
//! is a failure: these tests never skip.

mod common;

use common::images::LAVAPIPE;
use fovea::render::cpu_reference::render_reference;
use fovea::render::{FrameRequest, RenderError, Renderer};
use fovea::scene::Scene;
use glam::Vec3;

fn renderer() -> Renderer {
    Renderer::new().unwrap_or_else(|e| panic!("GPU tests need an adapter: {e}"))
}

fn rgb(img: &[u8], w: u32, x: u32, y: u32) -> [u8; 3] {
    let k = ((y * w + x) * 4) as usize;
    [img[k], img[k + 1], img[k + 2]]
}

#[test]
fn bunny_matches_the_cpu_rasteriser_in_coverage_and_shading() {
    let (w, h) = (96, 96);
    let scene = Scene::builtin("bunny").unwrap();
    let reference = render_reference(&scene, w, h, None);
    // The CPU rasteriser casts no shadows.
    let mut req = FrameRequest::new("bunny", w, h);
    req.settings.shadows = false;
    let frame = renderer().render(&req).unwrap();
    let bg = reference.rgba[..3].to_vec();

    let mut gpu_covered = 0;
    let mut mismatched = 0;
    let mut worst_interior = 0u8;
    for y in 0..h {
        for x in 0..w {
            let k = (y * w + x) as usize;
            let g = rgb(&frame.rgba, w, x, y);
            let is_bg = g.iter().zip(&bg).all(|(a, b)| a.abs_diff(*b) <= 1);
            if !is_bg {
                gpu_covered += 1;
            }
            if reference.covered[k] == is_bg {
                mismatched += 1;
            }
            if !reference.covered[k] {
                continue;
            }
            // Compare shading only well inside the silhouette, where both sample one surface.
            let interior = x > 0 && y > 0 && x + 1 < w && y + 1 < h && {
                let around = [(x - 1, y), (x + 1, y), (x, y - 1), (x, y + 1)];
                around
                    .iter()
                    .all(|&(i, j)| reference.covered[(j * w + i) as usize])
            };
            if interior {
                let r = rgb(&reference.rgba, w, x, y);
                let d = g.iter().zip(&r).map(|(a, b)| a.abs_diff(*b)).max().unwrap();
                worst_interior = worst_interior.max(d);
            }
        }
    }
    let cpu_covered = reference.covered.iter().filter(|c| **c).count();
    // The bunny fills a fair share of the frame with the shipped camera.
    assert!(
        cpu_covered > 1500 && cpu_covered < 5000,
        "CPU coverage {cpu_covered} px"
    );
    let share = (gpu_covered as f64 - cpu_covered as f64).abs() / cpu_covered as f64;
    assert!(
        share < 0.01,
        "GPU covers {gpu_covered} px, CPU {cpu_covered} px (bound 1%, from {LAVAPIPE})"
    );
    // Edge pixels may go either way under different tie-breaking rules; nothing else may.
    assert!(
        mismatched <= cpu_covered / 50,
        "{mismatched} pixels disagree on coverage (bound 2% of the covered, edge tie-breaking: any adapter)"
    );
    // Same formula, f32 on both sides; a few steps of 1/255 cover the interpolation order.
    assert!(
        worst_interior <= 3,
        "interior shading differs by up to {worst_interior}/255 (bound 3/255, from {LAVAPIPE})"
    );
}

#[test]
fn background_pixels_equal_the_scene_background() {
    let scene = Scene::builtin("bunny").unwrap();
    let frame = renderer()
        .render(&FrameRequest::new("bunny", 64, 48))
        .unwrap();
    let bg = scene.file.background_srgb;
    for (x, y) in [(0, 0), (63, 0), (0, 47), (63, 47)] {
        let p = rgb(&frame.rgba, 64, x, y);
        for c in 0..3 {
            assert!(
                p[c].abs_diff(bg[c]) <= 1,
                "corner ({x},{y}) is {p:?}, background {bg:?}"
            );
        }
    }
    assert!(
        frame.rgba.chunks_exact(4).all(|p| p[3] == 255),
        "frames are opaque"
    );
}

/// Mean brightness of the bunny's left and right halves (in image space).
fn half_brightness(img: &[u8], covered: &[bool], w: u32) -> (f64, f64) {
    let (mut l, mut nl, mut r, mut nr) = (0.0, 0, 0.0, 0);
    for (k, px) in img.chunks_exact(4).enumerate() {
        if !covered[k] {
            continue;
        }
        let v = f64::from(px[0]) + f64::from(px[1]) + f64::from(px[2]);
        if (k as u32 % w) < w / 2 {
            l += v;
            nl += 1;
        } else {
            r += v;
            nr += 1;
        }
    }
    (l / nl as f64, r / nr as f64)
}

#[test]
fn shading_follows_the_light_direction() {
    let (w, h) = (96, 96);
    let scene = Scene::builtin("bunny").unwrap();
    let covered = render_reference(&scene, w, h, None).covered;
    let mut r = renderer();
    let mut lit_from = |to_light: Vec3| {
        let mut req = FrameRequest::new("bunny", w, h);
        req.to_light = Some(to_light);
        half_brightness(&r.render(&req).unwrap().rgba, &covered, w)
    };
    let from_left = lit_from(Vec3::new(-1.0, 0.2, 0.3));
    let from_right = lit_from(Vec3::new(1.0, 0.2, 0.3));
    assert!(
        from_left.0 > from_left.1 + 20.0,
        "lit from the left: halves {from_left:?}"
    );
    assert!(
        from_right.1 > from_right.0 + 20.0,
        "lit from the right: halves {from_right:?}"
    );
}

#[test]
fn marker_is_drawn_where_the_gaze_is() {
    let (w, h) = (160, 120);
    let mut r = renderer();
    for gaze in [[0.25f32, 0.3f32], [0.8, 0.7], [0.5, 0.5]] {
        let mut req = FrameRequest::new("bunny", w, h);
        req.gaze = gaze;
        req.marker = true;
        let img = r.render(&req).unwrap().rgba;
        let (mut sx, mut sy, mut n) = (0.0, 0.0, 0.0);
        for (k, p) in img.chunks_exact(4).enumerate() {
            // The marker's magenta: strong red and blue, little green; nothing else in the scene is.
            if p[0] > 200 && p[1] < 110 && p[2] > 150 {
                sx += (k as u32 % w) as f64 + 0.5;
                sy += (k as u32 / w) as f64 + 0.5;
                n += 1.0;
            }
        }
        assert!(n > 20.0, "marker at {gaze:?} has only {n} magenta pixels");
        let (cx, cy) = (sx / n, sy / n);
        let (ex, ey) = (
            f64::from(gaze[0]) * f64::from(w),
            f64::from(gaze[1]) * f64::from(h),
        );
        assert!(
            (cx - ex).abs() < 1.0 && (cy - ey).abs() < 1.0,
            "marker centroid ({cx:.1},{cy:.1}), gaze ({ex},{ey})"
        );
    }
}

#[test]
fn tiny_odd_and_non_power_of_two_sizes_render() {
    let mut r = renderer();
    for (w, h) in [(1, 1), (97, 31), (3, 200), (641, 479)] {
        let mut req = FrameRequest::new("bunny", w, h);
        req.gaze = [1.0, 0.0];
        req.marker = true;
        let f = r.render(&req).unwrap_or_else(|e| panic!("{w}x{h}: {e}"));
        assert_eq!(f.rgba.len(), (w * h * 4) as usize, "{w}x{h}");
    }
}

#[test]
fn impossible_sizes_and_scenes_are_errors_not_panics() {
    let mut r = renderer();
    assert!(matches!(
        r.render(&FrameRequest::new("bunny", 0, 10)),
        Err(RenderError::Size { .. })
    ));
    assert!(matches!(
        r.render(&FrameRequest::new("bunny", 10, 100_000)),
        Err(RenderError::Size { .. })
    ));
    assert!(matches!(
        r.render(&FrameRequest::new("teapot", 10, 10)),
        Err(RenderError::Scene(_))
    ));
    // The renderer is still usable afterwards.
    assert!(r.render(&FrameRequest::new("bunny", 8, 8)).is_ok());
}

#[test]
fn depth_of_field_matches_its_cpu_twin() {
    use common::frames::{full, inspect};
    use fovea::optics::color::linear_to_srgb8;
    use fovea::optics::dof::{depth_of_field, Focus};
    // Odd size; the widest pupil and the gaze on the near floor, so the far floor blurs.
    let (w, h) = (255u32, 161u32);
    let mut req = full("gallery", w, h, 9);
    req.settings.dof = true;
    req.pupil_mm = 10.0;
    req.gaze = [0.5, 0.97];
    let mut r = renderer();
    let frame = r.render(&req).unwrap();
    let img = inspect(&r, &req);
    let scene = Scene::builtin("gallery").unwrap();
    let cam = scene.file.camera;
    let at = |v: f32, n: u32| ((v * n as f32).floor() as u32).min(n - 1);
    let under_gaze = img.normal_distance[(at(req.gaze[1], h) * w + at(req.gaze[0], w)) as usize][3];
    assert!(under_gaze > 0.0, "the gaze is on a surface");
    let f = Focus {
        pupil_mm: req.pupil_mm,
        metres_per_unit: scene.metres_per_unit() as f32,
        radians_per_pixel: cam.fov_y_deg.to_radians() / h as f32,
        focus_distance: under_gaze,
    };
    let color: Vec<[f32; 3]> = img.color.iter().map(|c| [c[0], c[1], c[2]]).collect();
    let distance: Vec<f32> = img.normal_distance.iter().map(|n| n[3]).collect();
    let cpu = depth_of_field(&color, &distance, w as usize, h as usize, &f);
    let (mut close, mut blurred) = (0, 0);
    for (k, (c, sharp)) in cpu.iter().zip(&color).enumerate() {
        let want = c.map(linear_to_srgb8);
        let got = &frame.rgba[k * 4..k * 4 + 3];
        let off = (0..3)
            .map(|i| (i32::from(got[i]) - i32::from(want[i])).abs())
            .max();
        close += usize::from(off.unwrap_or(0) <= 1);
        blurred += usize::from(sharp.map(linear_to_srgb8) != want);
    }
    let n = (w * h) as usize;
    // A tap whose offset rounds differently (f32 rotation on the GPU, exact angles here) reads
    // a neighbouring pixel: rare.
    assert!(
        close * 100 >= n * 99,
        "{close} of {n} pixels within one code value"
    );
    eprintln!("{close} of {n} within one code value, {blurred} blurred");
    assert!(
        blurred * 5 >= n,
        "only {blurred} of {n} pixels blurred: the test sees no blur"
    );
}
