//! Extra punctual lights on the GPU held to their CPU twin (`optics::lights::punctual`, with
//! the surface model `optics::specular::surface`): a floor under a point light and a spot light,
//! the key light off; and through a translucent body, against the key light. Software Vulkan
//! adapter; no adapter is a failure.

mod common;

use common::view_ray;
use fovea::optics::{lights::punctual, specular};
use fovea::render::{FrameRequest, Renderer};
use fovea::scene::Scene;
use fovea::settings::{Preset, RenderSettings, Rung};
use glam::Vec3;
use serde_json::json;

#[test]
fn point_and_spot_lights_on_the_gpu_match_their_cpu_twin() {
    let scene = Scene::from_json(
        &json!({
            "name": "lamps", "ambient": 0.0, "background_srgb": [0, 0, 0],
            "light": {"to_light": [0, 1, 0], "color": [1, 1, 1], "intensity": 0},
            "lights": [
                {"kind": "point", "position": [-2, 3, 0], "color": [1.0, 0.5, 0.25], "intensity": 9, "range": 12},
                {"kind": "spot", "position": [2, 4, 1], "direction": [0, -1, 0], "color": [0.2, 0.6, 1.0],
                 "intensity": 16, "inner_deg": 20, "outer_deg": 35}
            ],
            "camera": {"eye": [0, 9, 10], "target": [0, 0, 0], "fov_y_deg": 50, "near": 0.5, "far": 100},
            "materials": {"floor": {"kind": "opaque", "albedo": [0.6, 0.4, 0.2], "roughness": 0.4}},
            "objects": [{"mesh": "plane", "material": "floor", "scale": 30.0}]
        })
        .to_string(),
    )
    .unwrap();
    let mut r = Renderer::new().unwrap_or_else(|e| panic!("GPU tests need an adapter: {e}"));
    r.add_scene(scene.clone()).unwrap();
    let (w, h) = (96, 72);
    let mut req = FrameRequest::new("lamps", w, h);
    req.settings = RenderSettings::of(Preset::Full);
    // The spot's shadow map would see nothing but the floor itself; its PCF is tested elsewhere.
    req.settings.shadows = false;
    req.marker = false;
    r.render(&req).unwrap();
    let img = r.inspect(req.stream, "lamps", w, h).unwrap();
    let eye = Vec3::from(scene.file.camera.eye);
    let surface = scene.materials[0].1.surface().copied().unwrap();
    let alpha = specular::alpha(surface.roughness);
    let table = specular::directional_albedo_table(alpha);
    let albedo = scene.materials[0].1.albedo();
    let mut checked = 0;
    for (k, nd) in img.normal_distance.iter().enumerate() {
        if nd[3] <= 0.0 {
            continue;
        }
        let ray = view_ray(&scene, w, h, k);
        let p = eye + ray * nd[3];
        let n = Vec3::new(nd[0], nd[1], nd[2]).as_dvec3();
        let v = -ray.as_dvec3();
        let mut expected = [0.0f64; 3];
        for light in &scene.file.lights {
            let (l, e) = punctual(light, p);
            let l = l.as_dvec3();
            let hv = (l + v).normalize();
            for c in 0..3 {
                let lit = specular::surface(
                    albedo[c],
                    surface.f0[c],
                    alpha,
                    &table,
                    n.dot(l),
                    n.dot(v),
                    n.dot(hv),
                    v.dot(hv),
                );
                expected[c] += f64::from(e[c]) * lit;
            }
        }
        for c in 0..3 {
            let got = f64::from(img.color[k][c]);
            assert!(
                (got - expected[c]).abs() <= 3e-3 * expected[c].max(0.02),
                "pixel {k} channel {c}: GPU {got}, CPU {}",
                expected[c]
            );
        }
        checked += 1;
    }
    assert!(checked > 2000, "{checked} pixels checked");
}

/// A marble bunny lit from behind by the key light (`key` = 1) or, the key light dark, by an
/// extra directional light from the same direction; no ambient, no floor.
fn back_lit(name: &str, key: f32) -> Scene {
    let to_light = [0.3, 0.4, -0.86];
    let extra = if key > 0.0 {
        json!([])
    } else {
        json!([{"kind": "directional", "to_light": to_light, "color": [1, 1, 1], "intensity": 1}])
    };
    Scene::from_json(
        &json!({
            "name": name, "ambient": 0.0, "background_srgb": [0, 0, 0],
            "light": {"to_light": to_light, "color": [1, 1, 1], "intensity": key},
            "lights": extra,
            "camera": {"eye": [0, 6, 24], "target": [0, 4.5, 0], "fov_y_deg": 35, "near": 1, "far": 100},
            "materials": {"marble": {"kind": "translucent", "preset": "marble"}},
            "objects": [{"mesh": "bunny.ply", "material": "marble"}]
        })
        .to_string(),
    )
    .unwrap()
}

#[test]
fn an_extra_light_behind_a_translucent_body_shines_through_it_as_the_key_light_does() {
    // The photons carry the extra lights' light where they enter: the bunny's side facing the
    // camera, away from both lights, gets the same glow through the body from either. Before,
    // extra lights reached translucent bodies only at the opaque rung, and this side was black.
    let mut r = Renderer::new().unwrap_or_else(|e| panic!("GPU tests need an adapter: {e}"));
    r.add_scene(back_lit("key", 1.0)).unwrap();
    r.add_scene(back_lit("extra", 0.0)).unwrap();
    let (w, h) = (128, 96);
    let l = Vec3::new(0.3, 0.4, -0.86).normalize();
    for (i, rung) in [Rung::Hierarchical, Rung::BruteForce]
        .into_iter()
        .enumerate()
    {
        let mut means = Vec::new();
        for (j, name) in ["key", "extra"].into_iter().enumerate() {
            let mut req = FrameRequest::new(name, w, h);
            req.settings = RenderSettings::of(Preset::Full);
            req.settings.translucency.rung = rung;
            // The key light's shadow map has nothing opaque to hold; the directional one none.
            req.settings.shadows = false;
            req.marker = false;
            req.stream = 10 + 2 * i as u64 + j as u64;
            r.render(&req).unwrap();
            let img = r.inspect(req.stream, name, w, h).unwrap();
            let (mut sum, mut n) = (0.0f64, 0usize);
            for (k, nd) in img.normal_distance.iter().enumerate() {
                if nd[3] > 0.0 && Vec3::new(nd[0], nd[1], nd[2]).dot(l) < -0.2 {
                    sum += f64::from(img.color[k][0]);
                    n += 1;
                }
            }
            assert!(n > 500, "{name}: {n} pixels facing away");
            means.push(sum / n as f64);
        }
        let (key, extra) = (means[0], means[1]);
        assert!(
            key > 0.003 && (extra - key).abs() < 0.05 * key,
            "{rung:?}: the side away from the light, lit by the key light {key}, by an extra light {extra}"
        );
    }
}
