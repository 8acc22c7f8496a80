//! The translucency ladder on the GPU: the dipole held to its CPU twin, the hierarchy to brute
//! force, energy bounded, the pyramid cached, and every rung composed with foveation.

mod common;

use common::images::LAVAPIPE;
use fovea::optics::dipole::{leaf_softening, softened_distance};
use fovea::optics::specular;
use fovea::render::pass::photons::photon_radius_mm;
use fovea::render::{FrameRequest, Inspection, Renderer};
use fovea::scene::{Material, Scene};
use fovea::settings::Rung;
use glam::{Vec3, Vec4};

fn renderer() -> Renderer {
    Renderer::new().unwrap_or_else(|e| panic!("GPU tests need an adapter: {e}"))
}

fn request(scene: &str, w: u32, h: u32, rung: Rung, stream: u64) -> FrameRequest {
    let mut r = FrameRequest::new(scene, w, h);
    r.settings = fovea::settings::RenderSettings::of(fovea::settings::Preset::Full);
    r.settings.translucency.rung = rung;
    r.stream = stream;
    r
}

fn render(r: &mut Renderer, req: &FrameRequest) -> Inspection {
    r.render(req).unwrap();
    r.inspect(req.stream, &req.scene, req.width, req.height)
        .unwrap()
}

/// Mean relative difference over covered pixels (brightness-weighted so dark pixels do not dominate).
fn relative_difference(a: &Inspection, b: &Inspection) -> f64 {
    let (mut diff, mut total) = (0.0, 0.0);
    for (k, nd) in a.normal_distance.iter().enumerate() {
        if nd[3] > 0.0 {
            for c in 0..3 {
                diff += f64::from((a.color[k][c] - b.color[k][c]).abs());
                total += f64::from(b.color[k][c]);
            }
        }
    }
    diff / total
}

#[test]
fn brute_force_dipole_on_the_gpu_matches_the_cpu_sum() {
    let mut r = renderer();
    let (w, h) = (96, 72);
    let scene = Scene::builtin("bunny-marble").unwrap();
    let img = render(&mut r, &request("bunny-marble", w, h, Rung::BruteForce, 1));
    assert!(
        !img.photons.is_empty() && img.photons.iter().filter(|p| p[7] > 0.0).count() > 500,
        "photons were generated"
    );
    let Material::Translucent {
        dipole, surface, ..
    } = &scene.materials[0].1
    else {
        panic!("marble is translucent")
    };
    let table = specular::directional_albedo_table(specular::alpha(surface.roughness));
    let to_light = Vec3::from(scene.file.light.to_light);
    let cam = scene.file.camera;
    let view_proj = cam.view_proj(w, h);
    let inv = view_proj.inverse();
    let eye = Vec3::from(cam.eye);
    let mm = scene.file.mm_per_unit;
    let radius = photon_radius_mm(&scene);
    let light = Vec3::from(scene.file.light.color) * scene.file.light.intensity;
    let albedo = scene.materials[0].1.albedo();
    let mut checked = 0;
    for (k, nd) in img.normal_distance.iter().enumerate() {
        let n = Vec3::new(nd[0], nd[1], nd[2]);
        // Facing away from the key light: no specular lobe and no shadow test, only the
        // dipole's light through the rough interface and the ambient sky.
        if nd[3] <= 0.0 || k % 7 != 0 || n.dot(to_light) > 0.0 {
            continue;
        }
        let (x, y) = ((k as u32 % w) as f32 + 0.5, (k as u32 / w) as f32 + 0.5);
        let ndc = Vec4::new(x / w as f32 * 2.0 - 1.0, 1.0 - y / h as f32 * 2.0, 1.0, 1.0);
        let far = inv * ndc;
        let ray = (far.truncate() / far.w - eye).normalize();
        let x_o = eye + ray * nd[3];
        let mut sum = [0.0f64; 3];
        for p in img.photons.iter().filter(|p| p[7] > 0.0) {
            let r_mm = f64::from(Vec3::new(p[0], p[1], p[2]).distance(x_o)) * mm;
            for c in 0..3 {
                let soft = leaf_softening(radius, f64::from(p[3]) * mm);
                sum[c] += dipole[c].rd(softened_distance(r_mm, soft))
                    * dipole[c].softening_gain(soft)
                    * f64::from(p[4 + c]);
            }
        }
        let e_o = specular::lobe_albedo(&table, surface.dielectric_f0, f64::from(n.dot(-ray)));
        for c in 0..3 {
            let expected = sum[c] * (1.0 - e_o)
                + (albedo[c] + e_o) * f64::from(light[c]) * f64::from(scene.file.ambient);
            let got = f64::from(img.color[k][c]);
            assert!(
                (got - expected).abs() <= 2e-3 * expected.max(1e-3),
                "pixel {k} channel {c}: GPU {got}, CPU {expected} (bound 2e-3 relative, from {LAVAPIPE})"
            );
        }
        checked += 1;
    }
    assert!(checked > 50, "{checked} pixels checked");
}

#[test]
fn hierarchy_cut_at_the_leaves_equals_brute_force_and_error_grows_as_the_cut_rises() {
    let mut r = renderer();
    let (w, h) = (96, 72);
    let brute = render(&mut r, &request("bunny-marble", w, h, Rung::BruteForce, 1));
    let mut leaves = request("bunny-marble", w, h, Rung::Hierarchical, 2);
    leaves.settings.translucency.cut_level = 0;
    leaves.settings.translucency.cut_epsilon = 0.0;
    let at_leaves = relative_difference(&render(&mut r, &leaves), &brute);
    assert!(
        at_leaves < 1e-4,
        "cut at the leaves differs from brute force by {at_leaves} (bound 1e-4, from {LAVAPIPE})"
    );
    let mut errors = Vec::new();
    for level in 0..=4 {
        let mut q = request("bunny-marble", w, h, Rung::Hierarchical, 10 + level);
        q.settings.translucency.cut_level = level as u32;
        q.settings.translucency.cut_epsilon = 0.0;
        errors.push(relative_difference(&render(&mut r, &q), &brute));
    }
    for pair in errors.windows(2) {
        assert!(
            pair[1] + 1e-6 >= pair[0],
            "error must not fall as the cut rises: {errors:?}"
        );
    }
    assert!(
        errors[4] > 10.0 * errors[0].max(1e-5),
        "a coarse cut is visibly worse: {errors:?}"
    );
    // The default cut (ε = 0.5 from the leaves) stays within 2% of the reference.
    let default = relative_difference(
        &render(
            &mut r,
            &request("bunny-marble", w, h, Rung::Hierarchical, 20),
        ),
        &brute,
    );
    assert!(
        default < 0.02,
        "default cut error {default} (bound 2%, a model bound: any adapter)"
    );
}

fn white_scene(orbit: f32) -> Scene {
    let json = include_str!("../assets/scenes/bunny-marble.json")
        .replace("\"name\": \"bunny-marble\"", &format!("\"name\": \"white-{orbit}\""))
        .replace("{ \"kind\": \"translucent\", \"preset\": \"marble\" }", "{ \"kind\": \"translucent\", \"sigma_s_prime\": [1.0, 2.0, 4.0], \"sigma_a\": [0.0, 0.0, 0.0], \"eta\": 1.0 }")
        .replace("\"intensity\": 2.5", &format!("\"intensity\": 1.0, \"orbit_deg_per_s\": {orbit}"))
        .replace("\"to_light\": [0.35, 0.45, -0.82]", "\"to_light\": [0.0, 0.3, 1.0]");
    Scene::from_json(&json).unwrap()
}

#[test]
fn no_rung_makes_a_white_non_absorbing_medium_brighter_than_the_light() {
    let mut r = renderer();
    let scene = white_scene(0.0);
    let name = scene.name().to_string();
    let ambient = scene.file.ambient;
    r.add_scene(scene).unwrap();
    for (i, rung) in Rung::ALL.iter().enumerate() {
        let img = render(&mut r, &request(&name, 96, 72, *rung, i as u64 + 1));
        let brightest = img
            .color
            .iter()
            .flat_map(|c| [c[0], c[1], c[2]])
            .fold(0.0f32, f32::max);
        // Unit irradiance plus the ambient fraction is all the light there is; 3% for the
        // photon clusters of concave parts seeing each other through the bunny (occlusion
        // inside the object is ignored, as in seed 000).
        assert!(
            brightest <= (1.0 + ambient) * 1.03,
            "{rung:?}: brightest pixel {brightest}"
        );
        assert!(
            brightest > 0.3,
            "{rung:?}: the lit side is lit ({brightest})"
        );
    }
}

#[test]
fn the_pyramid_is_built_once_for_a_static_light_and_every_frame_for_a_moving_one() {
    let mut r = renderer();
    let mut q = request("bunny-marble", 96, 72, Rung::Hierarchical, 1);
    for _ in 0..3 {
        r.render(&q).unwrap();
    }
    assert_eq!(r.pyramid_builds(), 1, "static scene: built once");
    let moving = white_scene(45.0);
    let name = moving.name().to_string();
    r.add_scene(moving).unwrap();
    q.scene = name;
    for t in 0..3 {
        q.time_s = f64::from(t);
        r.render(&q).unwrap();
    }
    assert_eq!(r.pyramid_builds(), 4, "orbiting light: rebuilt each frame");
    // Rungs that need no photons never build a pyramid.
    let mut cheap = request("bunny-skin", 96, 72, Rung::Screen, 2);
    cheap.time_s = 9.0;
    r.render(&cheap).unwrap();
    assert_eq!(r.pyramid_builds(), 4);
}

#[test]
fn every_rung_composes_with_foveation() {
    let mut r = renderer();
    let (w, h) = (96, 72);
    for (i, rung) in Rung::ALL.iter().enumerate() {
        let full = render(&mut r, &request("bunny-skin", w, h, *rung, 100 + i as u64));
        let mut fov = request("bunny-skin", w, h, *rung, 200 + i as u64);
        fov.settings = fovea::settings::RenderSettings::of(fovea::settings::Preset::Balanced);
        fov.settings.translucency.rung = *rung;
        fov.settings.foveation.min_probability = 1.0;
        let all = render(&mut r, &fov);
        let d = relative_difference(&all, &full);
        assert!(
            d < 1e-6,
            "{rung:?}: foveated with every pixel sampled differs from full by {d}"
        );
        fov.settings.foveation.min_probability = 0.05;
        fov.stream += 1000;
        let sparse = render(&mut r, &fov);
        assert!(
            sparse
                .resolved
                .iter()
                .all(|c| c.iter().all(|v| v.is_finite())),
            "{rung:?}: finite"
        );
    }
}

#[test]
fn explain_prints_the_plan() {
    let out = std::process::Command::new(env!("CARGO_BIN_EXE_fovea"))
        .args(["render", "--scene", "materials", "--explain"])
        .output()
        .unwrap();
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let text = String::from_utf8_lossy(&out.stdout);
    assert!(
        text.contains("material \"plaster\": opaque: Lambert + GGX"),
        "{text}"
    );
    assert!(
        text.contains("material \"marble\": subsurface scattering"),
        "{text}"
    );
    assert!(text.contains("built once"), "{text}");
    let out = std::process::Command::new(env!("CARGO_BIN_EXE_fovea"))
        .args(["render", "--scene", "opaque", "--explain"])
        .output()
        .unwrap();
    assert!(String::from_utf8_lossy(&out.stdout).contains("photon pass: off"));
}
