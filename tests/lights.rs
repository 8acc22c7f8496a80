//! Extra punctual lights on the GPU held to their CPU twin (`optics::lights::punctual`, with
//! the surface model `optics::specular::surface`): a floor under a point light and a spot light,
//! the key light off. Software Vulkan adapter; no adapter is a failure.

mod common;

use common::view_ray;
use fovea::optics::{lights::punctual, specular};
use fovea::render::{FrameRequest, Renderer};
use fovea::scene::Scene;
use fovea::settings::{Preset, RenderSettings};
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
