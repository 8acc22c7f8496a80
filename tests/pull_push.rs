//! Pull-push reconstruction (CPU twin of `shaders/pull_push.wgsl`) at its extremes: constant and
//! linear functions, empty/full/single-sample frames, 1×1, odd and non-power-of-two sizes, and
//! against nearest-sample and Sibson reconstruction on a smooth image; then the GPU pass against
//! the twin, and the sampling rules that go with it (edges at the MAR, material edges).

mod common;

use common::frames::{foveated, inspect, renderer};
use common::images::LAVAPIPE;
use fovea::optics::acuity::{acuity_probability, edge_eccentricity_deg, mar_deg, EDGE_MARGIN_DEG};
use fovea::render::uniforms::FLAG_COVERED;
use fovea::render::Inspection;
use fovea::scene::Scene;
use fovea::settings::Reconstruction;
use fovea::viewing::Viewing;

use fovea::foveation::pull_push::{reconstruct, Key};
use fovea::foveation::reconstruct::{
    jfa_steps, jfa_with_steps, pack, reconstruct as sibson, NO_SEED,
};

/// A deterministic scatter of samples at density `p` (a hash per pixel).
fn mask(w: u32, h: u32, p: f32, salt: u32) -> Vec<bool> {
    (0..w * h)
        .map(|k| {
            let mut x = k.wrapping_mul(0x9E37_79B9) ^ salt.wrapping_mul(0x85EB_CA6B);
            x ^= x >> 15;
            x = x.wrapping_mul(0x2C1B_3C6D);
            x ^= x >> 12;
            (x >> 8) as f32 / 16_777_216.0 < p
        })
        .collect()
}

fn sampled(w: u32, h: u32, m: &[bool], f: impl Fn(f32, f32) -> [f32; 3]) -> Vec<Option<[f32; 3]>> {
    (0..w * h)
        .map(|k| {
            let (x, y) = ((k % w) as f32 + 0.5, (k / w) as f32 + 0.5);
            m[k as usize].then(|| f(x, y))
        })
        .collect()
}

fn max_error(w: u32, out: &[[f32; 3]], f: impl Fn(f32, f32) -> [f32; 3]) -> f32 {
    out.iter()
        .enumerate()
        .map(|(k, c)| {
            let (x, y) = ((k as u32 % w) as f32 + 0.5, (k as u32 / w) as f32 + 0.5);
            let t = f(x, y);
            (0..3).map(|i| (c[i] - t[i]).abs()).fold(0.0, f32::max)
        })
        .fold(0.0, f32::max)
}

/// One surface at one depth: the joint-bilateral weights reduce to bilinear ones.
fn flat(w: u32, h: u32) -> Vec<Key> {
    vec![
        Key {
            depth: 1.0,
            material: 0.0
        };
        (w * h) as usize
    ]
}

fn assert_finite(out: &[[f32; 3]]) {
    assert!(
        out.iter().flatten().all(|v| v.is_finite()),
        "NaN or inf in the output"
    );
}

#[test]
fn constants_are_reproduced_at_every_density_and_size() {
    let c = |_: f32, _: f32| [0.25, 0.5, 0.75];
    for (w, h) in [(1, 1), (2, 1), (7, 5), (33, 17), (64, 64), (97, 61)] {
        for p in [0.01, 0.1, 0.5, 1.0] {
            let m = mask(w, h, p, w * 31 + h);
            if !m.iter().any(|&s| s) {
                continue;
            }
            let out = reconstruct(w, h, &sampled(w, h, &m, c), &flat(w, h));
            assert_finite(&out);
            let e = max_error(w, &out, c);
            assert!(e < 1e-5, "{w}x{h} p={p}: constant off by {e}");
        }
    }
}

#[test]
fn linear_ramps_are_reproduced_away_from_the_border() {
    // Gradients of very different sizes per channel. Pixels nearer the border than twice the
    // mean sample spacing may lie outside the samples' hull, where the output is bounded by the
    // samples' range instead of extrapolated.
    let f = |x: f32, y: f32| [0.01 * x + 0.02 * y, 0.5 - 0.003 * x, 0.2 + 0.001 * (x + y)];
    for (w, h) in [(33, 17), (96, 64), (127, 73)] {
        for p in [0.03f32, 0.1, 0.3] {
            let m = mask(w, h, p, 7 + w);
            let out = reconstruct(w, h, &sampled(w, h, &m, f), &flat(w, h));
            assert_finite(&out);
            let margin = (2.0 / p.sqrt()).ceil() as u32;
            let mut worst = 0.0f32;
            for y in margin..h.saturating_sub(margin) {
                for x in margin..w.saturating_sub(margin) {
                    let t = f(x as f32 + 0.5, y as f32 + 0.5);
                    let c = out[(y * w + x) as usize];
                    worst = (0..3).map(|i| (c[i] - t[i]).abs()).fold(worst, f32::max);
                }
            }
            // f32 rounding on values up to ~2.5: a few ulps per level.
            assert!(worst < 2e-4, "{w}x{h} p={p}: linear ramp off by {worst}");
        }
    }
}

#[test]
fn a_highlight_never_overshoots_its_samples() {
    // A narrow bright peak on a dark surface: planes fitted to its flanks point below zero.
    let (w, h) = (64, 48);
    let f = |x: f32, y: f32| {
        let r2 = ((x - 30.0).powi(2) + (y - 20.0).powi(2)) / 9.0;
        [5.0 * (-r2).exp(), 0.02, 0.0]
    };
    let m = mask(w, h, 0.08, 2);
    let out = reconstruct(w, h, &sampled(w, h, &m, f), &flat(w, h));
    let hi = (0..w * h)
        .filter(|&k| m[k as usize])
        .map(|k| f((k % w) as f32 + 0.5, (k / w) as f32 + 0.5)[0])
        .fold(0.0, f32::max);
    for c in &out {
        assert!(
            c[0] >= 0.0 && c[0] <= hi + 1e-5,
            "{} outside [0, {hi}]",
            c[0]
        );
    }
}

#[test]
fn planes_do_not_reach_across_a_depth_edge() {
    // Left half near (red), right half far (blue): an unsampled near pixel beside the edge
    // takes the near surface's colour, not a blend.
    let (w, h) = (64, 32);
    let near = |x: u32| x < 32;
    let depth: Vec<Key> = (0..w * h)
        .map(|k| Key {
            depth: if near(k % w) { 1.0 } else { 3.0 },
            material: 0.0,
        })
        .collect();
    let m = mask(w, h, 0.05, 9);
    let samples: Vec<Option<[f32; 3]>> = (0..w * h)
        .map(|k| {
            m[k as usize].then(|| {
                if near(k % w) {
                    [1.0, 0.0, 0.0]
                } else {
                    [0.0, 0.0, 1.0]
                }
            })
        })
        .collect();
    let out = reconstruct(w, h, &samples, &depth);
    let bilinear = reconstruct(w, h, &samples, &flat(w, h));
    let leak = |img: &[[f32; 3]]| {
        (0..w * h)
            .filter(|&k| near(k % w) && !m[k as usize])
            .map(|k| img[k as usize][2])
            .fold(0.0, f32::max)
    };
    let (with_depth, without) = (leak(&out), leak(&bilinear));
    eprintln!("blue leaking into the near half: {with_depth:.3} with depth, {without:.3} without");
    // A cell whose samples mix both surfaces still carries a little of the far one.
    assert!(with_depth < 0.2 && with_depth < 0.5 * without);
}

#[test]
fn samples_keep_their_values_and_full_frames_pass_through() {
    let f = |x: f32, y: f32| [(x * 0.37).sin(), (y * 0.11).cos(), x * y * 1e-3];
    let (w, h) = (41, 29);
    let all = vec![true; (w * h) as usize];
    let out = reconstruct(w, h, &sampled(w, h, &all, f), &flat(w, h));
    assert!(
        max_error(w, &out, f) < 1e-5,
        "every pixel sampled must pass through"
    );
    let m = mask(w, h, 0.2, 3);
    let out = reconstruct(w, h, &sampled(w, h, &m, f), &flat(w, h));
    for (k, c) in out.iter().enumerate() {
        if m[k] {
            let (x, y) = ((k as u32 % w) as f32 + 0.5, (k as u32 / w) as f32 + 0.5);
            let t = f(x, y);
            assert!(
                (0..3).all(|i| (c[i] - t[i]).abs() < 1e-5),
                "sample {k} moved"
            );
        }
    }
}

#[test]
fn no_samples_gives_zero_and_one_sample_fills_the_frame() {
    let (w, h) = (19, 23);
    let none = vec![None; (w * h) as usize];
    let out = reconstruct(w, h, &none, &flat(w, h));
    assert!(
        out.iter().flatten().all(|v| *v == 0.0),
        "an empty frame stays zero"
    );
    let mut one = none.clone();
    one[(11 * w + 4) as usize] = Some([0.9, 0.1, 0.4]);
    let out = reconstruct(w, h, &one, &flat(w, h));
    assert_finite(&out);
    assert!(out
        .iter()
        .all(|c| (c[0] - 0.9).abs() < 1e-5 && (c[2] - 0.4).abs() < 1e-5));
    // A frame whose samples all lie on one row: still finite, exact along the row's values.
    let row: Vec<Option<[f32; 3]>> = (0..w * h)
        .map(|k| (k / w == 5).then(|| [(k % w) as f32 * 0.1, 0.0, 0.0]))
        .collect();
    let out = reconstruct(w, h, &row, &flat(w, h));
    assert_finite(&out);
    for x in 0..w {
        let top = out[x as usize][0];
        assert!((top - x as f32 * 0.1).abs() < 1e-3, "column {x}: {top}");
    }
}

#[test]
fn an_empty_tile_is_filled_from_its_neighbours() {
    // A 16×16 hole in a ramp: filled by the ramp, not by zero or a constant.
    let (w, h) = (64, 64);
    let f = |x: f32, y: f32| [0.01 * x, 0.005 * y, 0.3];
    let mut m = mask(w, h, 0.25, 11);
    for y in 24..40 {
        for x in 24..40 {
            m[(y * w + x) as usize] = false;
        }
    }
    let out = reconstruct(w, h, &sampled(w, h, &m, f), &flat(w, h));
    assert!(max_error(w, &out, f) < 2e-4);
}

#[test]
fn on_a_smooth_image_it_is_closer_than_nearest_and_near_sibson() {
    let (w, h) = (96, 72);
    let f = |x: f32, y: f32| {
        let (u, v) = (x / 96.0, y / 72.0);
        [
            (6.0 * u).sin() * 0.5 + 0.5,
            (4.0 * v + 2.0 * u).cos() * 0.5 + 0.5,
            u * v,
        ]
    };
    let m = mask(w, h, 0.06, 5);
    let pp = reconstruct(w, h, &sampled(w, h, &m, f), &flat(w, h));
    let seeds: Vec<u32> = (0..w * h)
        .map(|k| {
            if m[k as usize] {
                pack(k % w, k / w)
            } else {
                NO_SEED
            }
        })
        .collect();
    let nearest = jfa_with_steps(w, h, &seeds, &jfa_steps(w, h));
    let values: Vec<[f32; 4]> = (0..w * h)
        .map(|k| {
            let c = f((k % w) as f32 + 0.5, (k / w) as f32 + 0.5);
            [c[0], c[1], c[2], 1.0]
        })
        .collect();
    let covered = vec![true; (w * h) as usize];
    let rms = |out: &dyn Fn(usize) -> [f32; 3]| {
        let mut s = 0.0f64;
        for k in 0..(w * h) as usize {
            let t = f((k as u32 % w) as f32 + 0.5, (k as u32 / w) as f32 + 0.5);
            let c = out(k);
            s += (0..3).map(|i| f64::from(c[i] - t[i]).powi(2)).sum::<f64>();
        }
        (s / f64::from(w * h * 3)).sqrt()
    };
    let near = sibson(w, h, &nearest, &covered, &values, &values, None);
    let sib = sibson(w, h, &nearest, &covered, &values, &values, Some(8));
    let (e_pp, e_near, e_sib) = (
        rms(&|k| pp[k]),
        rms(&|k| [near[k][0], near[k][1], near[k][2]]),
        rms(&|k| [sib[k][0], sib[k][1], sib[k][2]]),
    );
    eprintln!("rms: pull-push {e_pp:.5}, nearest {e_near:.5}, Sibson {e_sib:.5}");
    assert!(
        e_pp < 0.5 * e_near,
        "pull-push {e_pp:.4} vs nearest {e_near:.4}"
    );
    assert!(
        e_pp < 0.6 * e_sib,
        "pull-push {e_pp:.4} vs Sibson {e_sib:.4}"
    );
}

#[test]
fn planes_do_not_reach_across_a_material_boundary() {
    // One flat surface, two materials whose ratios differ 40-fold (a lamp in a ceiling): the
    // ceiling beside the lamp keeps the ceiling's ratio.
    let (w, h) = (64, 32);
    let lamp = |x: u32| (24..40).contains(&x);
    let keys: Vec<Key> = (0..w * h)
        .map(|k| Key {
            depth: 1.0,
            material: if lamp(k % w) { 2.0 } else { 1.0 },
        })
        .collect();
    let m = mask(w, h, 0.05, 4);
    let samples: Vec<Option<[f32; 3]>> = (0..w * h)
        .map(|k| m[k as usize].then(|| if lamp(k % w) { [20.0; 3] } else { [0.5; 3] }))
        .collect();
    let worst = |keys: &[Key]| {
        let out = reconstruct(w, h, &samples, keys);
        let errors: Vec<f32> = (0..w * h)
            .filter(|&k| !lamp(k % w) && !m[k as usize])
            .map(|k| (out[k as usize][0] - 0.5).abs())
            .collect();
        let mean = errors.iter().sum::<f32>() / errors.len() as f32;
        (mean, errors.into_iter().fold(0.0, f32::max))
    };
    let (with, without) = (worst(&keys), worst(&flat(w, h)));
    eprintln!("ceiling error (mean, max): {with:?} with materials, {without:?} without");
    assert!(with.0 < 0.5 * without.0 && with.1 < 0.5 * without.1);
}

#[test]
fn pull_push_on_the_gpu_matches_its_cpu_twin() {
    use fovea::foveation::pull_push;
    let mut r = renderer();
    // Odd, non-power-of-two sizes, the gaze off centre, and a frame of a single pixel; inside
    // the Cornell box no background: every cell of every level counts. The last frame's fill
    // skips its tiles of background (pull_push_tiles).
    for (stream, name, (w, h), gaze) in [
        (1, "bunny", (97, 61), [0.3, 0.4]),
        (2, "bunny", (64, 48), [0.9, 0.1]),
        (3, "bunny", (1, 1), [0.5, 0.5]),
        (4, "cornell", (150, 113), [0.9, 0.85]),
        (5, "bunny", (333, 250), [0.2, 0.7]),
    ] {
        let scene = Scene::builtin(name).unwrap();
        let mut req = foveated("balanced", w, h, gaze);
        req.scene = name.to_string();
        req.stream = stream;
        if name == "cornell" {
            // Narrowed to the inside of the box: no background.
            let mut camera = scene.file.camera;
            camera.fov_y_deg = 12.0;
            req.camera = Some(camera);
        }
        req.settings.foveation.reconstruction = Reconstruction::PullPush;
        let frame = r.render(&req).unwrap();
        let img = inspect(&r, &req);
        assert!(
            img.resolved.iter().flatten().all(|v| v.is_finite()),
            "NaN or inf"
        );
        let n = (w * h) as usize;
        let inputs = img.pull_push_inputs(&scene, req.light_direction(&scene));
        let cpu = pull_push::reconstruct(w, h, &inputs.samples, &inputs.keys);
        let mut worst = 0.0f32;
        for k in 0..n {
            if img.flags[k] & FLAG_COVERED == 0 {
                continue;
            }
            let a = inputs.proxy[k];
            for c in 0..3 {
                let want = (cpu[k][c] * a[c]).max(0.0);
                let got = img.resolved[k][c];
                worst = worst.max((got - want).abs() / want.abs().max(0.05));
            }
        }
        // f32 with the GPU's fused multiply-adds against the CPU's separate ones, over ~10 levels.
        assert!(
            worst < 1e-3,
            "{w}x{h}: GPU and CPU differ by {worst} (relative, from {LAVAPIPE})"
        );

        assert!(frame.sampled > 0.0 || w * h == 1);
        let covered = img.flags.iter().filter(|f| *f & FLAG_COVERED != 0).count();
        assert!(
            name != "cornell" || covered == n,
            "{covered} of {n} pixels covered"
        );
    }
}

#[test]
fn edges_at_the_mar_ask_for_sqrt_p_and_only_material_changes_count_when_demodulated() {
    // The same frame three ways: eq. 3 (an edge asks for 1), edges at the MAR (S·√p, p the
    // acuity EDGE_MARGIN_DEG nearer the gaze), and pull-push (albedo edges within a material ask
    // for nothing). Saliency only ever raises the acuity probability, and by no more than each
    // rule allows.
    let mut r = renderer();
    let (w, h) = (160, 120);
    // A display small enough that a pixel (~0.08°) is finer than the eye a few degrees out, so
    // the probability falls inside the margin too (on the default display it is 1 there).
    const DISPLAY_CM: f64 = 13.4;
    let mut maps = Vec::new();
    for (stream, at_mar, reconstruction) in [
        (11, false, Reconstruction::Sibson),
        (12, true, Reconstruction::Sibson),
        (13, false, Reconstruction::PullPush),
    ] {
        let mut req = foveated("balanced", w, h, [0.2, 0.3]);
        req.display.width_cm = DISPLAY_CM;
        req.stream = stream;
        req.settings.foveation.motion = false;
        req.settings.foveation.edges_at_mar = at_mar;
        req.settings.foveation.reconstruction = reconstruction;
        r.render(&req).unwrap();
        maps.push(inspect(&r, &req));
    }
    let mut plain = foveated("balanced", w, h, [0.2, 0.3]);
    plain.display.width_cm = DISPLAY_CM;
    plain.stream = 14;
    plain.settings.foveation.motion = false;
    plain.settings.foveation.saliency = false;
    r.render(&plain).unwrap();
    let acuity = inspect(&r, &plain).probability;
    let f = &plain.settings.foveation;
    let v = Viewing {
        width: w,
        height: h,
        width_cm: plain.display.width_cm,
        distance_cm: plain.display.distance_cm,
    };
    let g = [0.2 * f64::from(w), 0.3 * f64::from(h)];
    let (slope, w0) = (f64::from(f.mar_slope), f64::from(f.mar_w0_deg));
    let (w_min, w_far) = (
        v.pixel_angle_deg(),
        mar_deg(v.max_eccentricity_deg(g), slope, w0),
    );
    let (mut raised_full, mut raised_mar, mut raised_in_margin) = (0usize, 0usize, 0usize);
    for k in 0..(w * h) as usize {
        if maps[0].flags[k] & FLAG_COVERED == 0 {
            continue;
        }
        let p = acuity[k];
        let px = [(k as u32 % w) as f64 + 0.5, (k as u32 / w) as f64 + 0.5];
        let e = v.eccentricity_deg(g, px);
        let edge = edge_eccentricity_deg(e);
        let p_edge = acuity_probability(f.probability, mar_deg(edge, slope, w0), w_min, w_far);
        let (full, mar, demod) = (
            maps[0].probability[k],
            maps[1].probability[k],
            maps[2].probability[k],
        );
        assert!(
            full >= p - 1e-6 && mar >= p - 1e-6 && demod >= p - 1e-6,
            "pixel {k}"
        );
        // The bound is the CPU twin's acuity in f64 at another eccentricity, not the GPU's own
        // p as before (1e-5 then): the f32 shader sits up to 2.2e-5 above it here.
        let bound = p_edge.sqrt() as f32;
        assert!(
            mar <= bound.max(p) + 1e-4,
            "pixel {k} at {e:.1}°: {mar} above √p = {bound} of the edge's {edge:.1}°"
        );
        // Inside the margin an edge asks for more than the acuity at its own eccentricity.
        raised_in_margin += usize::from(e < f64::from(EDGE_MARGIN_DEG) && mar > p.sqrt() + 1e-3);
        assert!(
            demod <= full + 1e-6,
            "pixel {k}: demodulated {demod} above eq. 3's {full}"
        );
        raised_full += usize::from(full > p + 1e-3);
        raised_mar += usize::from(mar > p + 1e-3);
    }
    assert!(
        raised_full > 100,
        "the bunny's silhouette and creases raise eq. 3: {raised_full}"
    );
    assert!(raised_mar > 0 && raised_mar <= raised_full);
    assert!(
        raised_in_margin > 0,
        "edges within the margin are sampled fully"
    );
    let total = |m: &Inspection| m.probability.iter().map(|v| f64::from(*v)).sum::<f64>();
    assert!(
        total(&maps[1]) < total(&maps[0]),
        "edges at the MAR ask for fewer samples"
    );
}

/// The largest frame a session may ask for reconstructs: its pyramid's staging buffers stay
/// within what the software adapter binds (128 MiB; six layers of moments at 3840×2160 in one
/// buffer would be 199 MB).
#[test]
fn the_largest_frame_a_session_may_ask_for_reconstructs() {
    let limits = fovea::protocol::Limits::default();
    let (w, h) = (limits.max_width, limits.max_height);
    let mut r = renderer();
    let frame = r.render(&foveated("balanced", w, h, [0.5, 0.5]));
    let frame = frame.unwrap_or_else(|e| panic!("{w}x{h} balanced: {e}"));
    assert_eq!((frame.width, frame.height), (w, h));
}
