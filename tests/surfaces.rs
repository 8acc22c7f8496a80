//! Surfaces, shadows and scenes on the GPU: the GGX shading held to its CPU twin, shadows
//! without acne or peter-panning, double-sided materials, every shipped scene finite, and a
//! served scene folder. Runs on the software Vulkan adapter; no adapter is a failure.

mod common;

use common::images::LAVAPIPE;
use common::view_ray;
use fovea::optics::specular;
use fovea::render::{FrameRequest, Inspection, Renderer};
use fovea::scene::{Folder, Scene};
use fovea::settings::{Preset, RenderSettings};
use glam::Vec3;
use serde_json::json;

fn renderer() -> Renderer {
    Renderer::new().unwrap_or_else(|e| panic!("GPU tests need an adapter: {e}"))
}

fn full(scene: &str, w: u32, h: u32, stream: u64) -> FrameRequest {
    let mut r = FrameRequest::new(scene, w, h);
    r.settings = RenderSettings::of(Preset::Full);
    r.marker = false;
    r.stream = stream;
    r
}

fn render(r: &mut Renderer, req: &FrameRequest) -> Inspection {
    r.render(req).unwrap();
    r.inspect(req.stream, &req.scene, req.width, req.height)
        .unwrap()
}

fn scene_json(
    name: &str,
    objects: serde_json::Value,
    materials: serde_json::Value,
    camera: serde_json::Value,
    to_light: [f32; 3],
    ambient: f32,
) -> Scene {
    Scene::from_json(
        &json!({
            "name": name, "ambient": ambient, "background_srgb": [0, 0, 0],
            "light": {"to_light": to_light, "color": [1, 1, 1], "intensity": 1},
            "camera": camera, "materials": materials, "objects": objects
        })
        .to_string(),
    )
    .unwrap()
}

#[test]
fn ggx_shading_on_the_gpu_matches_its_cpu_twin() {
    let mut r = renderer();
    let (w, h) = (96, 72);
    let camera =
        json!({"eye": [4, 6, 14], "target": [0, 4.5, 0], "fov_y_deg": 40, "near": 0.5, "far": 100});
    // Albedos on exact 8-bit steps: the G-buffer stores the base colour in 8 bits.
    for (i, material) in [
        json!({"kind": "opaque", "albedo": [0.6, 0.4, 0.2], "roughness": 0.3}),
        json!({"kind": "opaque", "albedo": [0.6, 0.4, 0.2], "roughness": 0.6, "metallic": 1.0}),
        json!({"kind": "opaque", "albedo": [0.6, 0.4, 0.2], "roughness": 0.0}),
    ]
    .into_iter()
    .enumerate()
    {
        let to_light = Vec3::new(0.5, 0.8, 0.6).normalize();
        let scene = scene_json(
            "ggx",
            json!([{"mesh": "bunny.ply", "material": "m"}]),
            json!({"m": material}),
            camera.clone(),
            to_light.into(),
            0.0,
        );
        r.add_scene(scene.clone()).unwrap();
        let mut req = full("ggx", w, h, 10 + i as u64);
        req.settings.shadows = false;
        let img = render(&mut r, &req);
        let surface = scene.materials[0].1.surface().copied().unwrap();
        let alpha = specular::alpha(surface.roughness);
        let table = specular::directional_albedo_table(alpha);
        let albedo = scene.materials[0].1.albedo();
        let mut checked = 0;
        for (k, nd) in img.normal_distance.iter().enumerate() {
            if nd[3] <= 0.0 {
                continue;
            }
            let n = Vec3::new(nd[0], nd[1], nd[2]).as_dvec3();
            let v = -view_ray(&scene, w, h, k).as_dvec3();
            let l = to_light.as_dvec3();
            let hv = (l + v).normalize();
            for c in 0..3 {
                let diffuse = albedo[c] * (1.0 - surface.metallic);
                let expected = specular::surface(
                    diffuse,
                    surface.f0[c],
                    alpha,
                    &table,
                    n.dot(l),
                    n.dot(v),
                    n.dot(hv),
                    v.dot(hv),
                );
                let got = f64::from(img.color[k][c]);
                // α at its floor is a mirror: its lobe is one or two pixels wide and f32 vs f64
                // half-vectors put its peak in different pixels, so compare away from it.
                if i == 2 && expected > 2.0 * (diffuse + 0.05) {
                    continue;
                }
                assert!(
                    (got - expected).abs() <= 2e-3 * expected.max(0.05),
                    "material {i} pixel {k} channel {c}: GPU {got}, CPU {expected} (bound from {LAVAPIPE})"
                );
            }
            checked += 1;
        }
        assert!(checked > 500, "{checked} pixels checked");
    }
}

/// Checks every floor pixel (y = 0) of a shadowed render against the same render unshadowed:
/// `inside(x)` says how far inside (> 0) or outside (< 0) the geometric shadow a floor point
/// lies, `None` to skip it; points within `band` of the edge are skipped. Shadowed points must
/// keep < 10% of their light, open ones more than `open_keeps`. Returns (shadowed, open) counts.
fn check_floor_shadow(
    scene: &Scene,
    (w, h): (u32, u32),
    shadowed: &Inspection,
    lit: &Inspection,
    band: f32,
    open_keeps: f32,
    mut inside: impl FnMut(Vec3) -> Option<f32>,
) -> (usize, usize) {
    let eye = Vec3::from(scene.file.camera.eye);
    let (mut dark, mut open) = (0, 0);
    for (k, nd) in shadowed.normal_distance.iter().enumerate() {
        let x = eye + view_ray(scene, w, h, k) * nd[3];
        if nd[3] <= 0.0 || x.y.abs() > 1e-3 {
            continue; // not the floor
        }
        let Some(depth) = inside(x) else { continue };
        if depth.abs() < band {
            continue;
        }
        let ratio = shadowed.color[k][1] / lit.color[k][1].max(1e-6);
        if depth > 0.0 {
            assert!(
                ratio < 0.1,
                "pixel {k} in the shadow keeps {ratio} of its light"
            );
            dark += 1;
        } else {
            assert!(
                ratio > open_keeps,
                "pixel {k} in the open lost light: {ratio} (acne)"
            );
            open += 1;
        }
    }
    (dark, open)
}

/// A floor with a square roof 3 units above it, lit from above at a slant.
fn shadow_scene() -> (Scene, Vec3) {
    let to_light = Vec3::new(0.3, 1.0, 0.2).normalize();
    let s = scene_json(
        "shadowed",
        json!([
            {"mesh": "plane", "material": "floor", "scale": 40.0},
            {"mesh": "quad", "material": "floor", "corners": [[-3, 3, -3], [-3, 3, 3], [3, 3, 3], [3, 3, -3]]}
        ]),
        json!({"floor": {"kind": "opaque", "albedo": [0.8, 0.8, 0.8], "roughness": 1.0}}),
        json!({"eye": [0, 14, 16], "target": [0, 0, 0], "fov_y_deg": 45, "near": 0.5, "far": 100}),
        to_light.into(),
        0.05,
    );
    (s, to_light)
}

#[test]
fn shadows_fall_where_the_roof_blocks_the_light_with_no_acne_and_no_peter_panning() {
    let mut r = renderer();
    let (w, h) = (160, 120);
    let (scene, l) = shadow_scene();
    r.add_scene(scene.clone()).unwrap();
    let lit = render(&mut r, &{
        let mut q = full("shadowed", w, h, 1);
        q.settings.shadows = false;
        q
    });
    let shadowed = render(&mut r, &full("shadowed", w, h, 2));
    // The map's texel over the scene's bounding sphere; edges may blur over ~3 of them.
    let (lo, hi) = scene.mesh.bounds();
    let texel = (hi - lo).length() / fovea::render::pass::shadow::SIDE as f32;
    // Where the ray towards the light crosses the roof's plane, and how far inside it.
    let (dark, open) =
        check_floor_shadow(&scene, (w, h), &shadowed, &lit, 3.0 * texel, 0.995, |x| {
            let p = x + l * (3.0 / l.y);
            Some(3.0 - p.x.abs().max(p.z.abs()))
        });
    assert!(
        dark > 200 && open > 2000,
        "{dark} shadowed and {open} open floor pixels checked"
    );
}

/// The key light off, one punctual light `light` (scene JSON), a floor and a 2·`half` square
/// roof 3 units above it: (the scene, its render unshadowed, its render shadowed).
fn one_light_over_a_roof(
    r: &mut Renderer,
    name: &str,
    light: serde_json::Value,
    half: f32,
    (w, h): (u32, u32),
) -> (Scene, Inspection, Inspection) {
    let scene = Scene::from_json(
        &json!({
            "name": name, "ambient": 0.0, "background_srgb": [0, 0, 0],
            "light": {"to_light": [0, 1, 0], "color": [1, 1, 1], "intensity": 0},
            "lights": [light],
            "camera": {"eye": [0, 16, 14], "target": [0, 0, 0], "fov_y_deg": 50, "near": 0.5, "far": 100},
            "materials": {"floor": {"kind": "opaque", "albedo": [0.8, 0.8, 0.8], "roughness": 1.0}},
            "objects": [
                {"mesh": "plane", "material": "floor", "scale": 40.0},
                {"mesh": "quad", "material": "floor",
                 "corners": [[-half, 3, -half], [-half, 3, half], [half, 3, half], [half, 3, -half]]}
            ]
        })
        .to_string(),
    )
    .unwrap();
    r.add_scene(scene.clone()).unwrap();
    let lit = render(r, &{
        let mut q = full(name, w, h, 1);
        q.settings.shadows = false;
        q
    });
    let shadowed = render(r, &full(name, w, h, 2));
    (scene, lit, shadowed)
}

#[test]
fn a_spot_light_casts_its_own_shadow() {
    let mut r = renderer();
    let (w, h) = (160, 120);
    // One spot 8 units above the floor, the roof 3 above it.
    let spot = json!({"kind": "spot", "position": [0, 8, 0], "direction": [0, -1, 0],
                      "color": [1, 1, 1], "intensity": 64, "inner_deg": 50, "outer_deg": 60});
    let (scene, lit, shadowed) = one_light_over_a_roof(&mut r, "spot", spot, 3.0, (w, h));
    // Inside the inner cone only (full light); the ray to the light crosses the roof's plane
    // at 5/8 of the point's offset from the axis.
    let cone = 8.0 * 50f32.to_radians().tan() - 0.25;
    let (dark, open) = check_floor_shadow(&scene, (w, h), &shadowed, &lit, 0.25, 0.99, |x| {
        let r = (x.x * x.x + x.z * x.z).sqrt();
        (r < cone).then(|| 3.0 - x.x.abs().max(x.z.abs()) * 5.0 / 8.0)
    });
    assert!(
        dark > 200 && open > 200,
        "{dark} shadowed and {open} open floor pixels checked"
    );
}

#[test]
fn a_point_light_casts_a_shadow_across_its_cube_faces() {
    let mut r = renderer();
    let (w, h) = (160, 120);
    // A point light 4 units above the floor, 1 above a 3×3 roof: the roof's shadow reaches 6
    // units out, past where the downward cube face ends (4 units, 45°), so the shadow's edge
    // lies in the side faces' tiles and its middle in the bottom face's.
    let point = json!({"kind": "point", "position": [0, 4, 0], "color": [1, 1, 1], "intensity": 64});
    let (scene, lit, shadowed) = one_light_over_a_roof(&mut r, "point", point, 1.5, (w, h));
    // The ray to the light crosses the roof's plane at 1/4 of the point's offset; open floor
    // is checked out to 12 units (the light 18° above the floor).
    let (mut edge_beyond_bottom_face, mut far_open) = (0, 0);
    let (dark, open) = check_floor_shadow(&scene, (w, h), &shadowed, &lit, 0.1, 0.99, |x| {
        let reach = x.x.abs().max(x.z.abs());
        let depth = 1.5 - reach / 4.0;
        if reach > 4.0 && depth > 0.1 {
            edge_beyond_bottom_face += 1;
        }
        if reach > 6.5 && reach < 12.0 {
            far_open += 1;
        }
        (reach < 12.0).then_some(depth)
    });
    assert!(
        dark > 200 && open > 200 && edge_beyond_bottom_face > 50 && far_open > 200,
        "{dark} shadowed ({edge_beyond_bottom_face} beyond the bottom face) and {open} open \
         ({far_open} in the side faces) floor pixels checked"
    );
}

#[test]
fn double_sided_materials_show_their_back_and_one_sided_ones_do_not() {
    let mut r = renderer();
    let (w, h) = (64, 48);
    for (i, two) in [false, true].into_iter().enumerate() {
        let scene = scene_json(
            "underneath",
            json!([{"mesh": "plane", "material": "sheet", "scale": 10.0}]),
            json!({"sheet": {"kind": "opaque", "albedo": [0.8, 0.8, 0.8], "double_sided": two}}),
            json!({"eye": [0, -6, 2], "target": [0, 0, 0], "fov_y_deg": 50, "near": 0.1, "far": 100}),
            [0.0, 1.0, 0.0],
            0.2,
        );
        r.add_scene(scene).unwrap();
        let img = render(&mut r, &full("underneath", w, h, 20 + i as u64));
        let covered = img.normal_distance.iter().filter(|nd| nd[3] > 0.0).count();
        if two {
            assert!(
                covered > w as usize * h as usize / 2,
                "{covered} pixels see the sheet's back"
            );
            // Its normal faces the viewer (downwards), so only ambient light reaches it.
            let k = img
                .normal_distance
                .iter()
                .position(|nd| nd[3] > 0.0)
                .unwrap();
            assert!(img.normal_distance[k][1] < -0.99);
            assert!(
                img.color[k][1] > 0.1 && img.color[k][1] < 0.25,
                "{:?}",
                img.color[k]
            );
        } else {
            assert_eq!(
                covered, 0,
                "a one-sided sheet seen from behind is not drawn"
            );
        }
    }
}

#[test]
fn every_shipped_scene_renders_finite() {
    let mut r = renderer();
    let (w, h) = (64, 48);
    let mut names: Vec<String> = fovea::scene::builtin_names()
        .iter()
        .map(|s| s.to_string())
        .collect();
    let dir = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("assets/models");
    let folder = Folder::open(&dir).unwrap();
    for glb in ["lamps.glb"] {
        let s = Scene::load(&dir.join(glb), &folder).unwrap();
        names.push(s.name().to_string());
        r.add_scene(s).unwrap();
    }
    for (i, name) in names.iter().enumerate() {
        for (j, preset) in [Preset::Full, Preset::Balanced].into_iter().enumerate() {
            let mut req = FrameRequest::new(name, w, h);
            req.settings = RenderSettings::of(preset);
            req.stream = 100 + 2 * i as u64 + j as u64;
            let img = render(&mut r, &req);
            let covered: Vec<_> = img
                .color
                .iter()
                .zip(&img.normal_distance)
                .filter(|(_, nd)| nd[3] > 0.0)
                .collect();
            assert!(
                covered.len() > 100,
                "{name}: {} pixels covered",
                covered.len()
            );
            for (c, _) in covered {
                assert!(
                    c.iter().all(|x| x.is_finite() && *x >= 0.0),
                    "{name} {preset:?}: {c:?}"
                );
            }
        }
    }
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn a_served_folder_offers_its_scenes_by_name_and_leaves_broken_ones_out() {
    use fovea::client::{Client, Event};
    use fovea::protocol::{Gaze, Hello};
    let dir = std::env::temp_dir().join(format!("fovea-served-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    std::fs::copy(
        concat!(env!("CARGO_MANIFEST_DIR"), "/assets/models/lamps.glb"),
        dir.join("lamps.glb"),
    )
    .unwrap();
    std::fs::write(dir.join("broken.gltf"), b"{ not json").unwrap();
    let catalog = fovea::scene::Catalog::with_folders(&[dir.clone()]).unwrap();
    let options = fovea::server::ServerOptions {
        catalog,
        ..Default::default()
    };
    let (addr, running) = common::start(options).await;
    let mut c = Client::connect(&format!("ws://{addr}/ws")).await.unwrap();
    let welcome = c
        .hello(&Hello {
            scene: "lamps".into(),
            width: 64,
            height: 48,
            preset: "fast".into(),
            ..Hello::default()
        })
        .await
        .unwrap();
    assert!(
        welcome.scenes.contains(&"lamps".to_string()),
        "{:?}",
        welcome.scenes
    );
    assert!(welcome.scenes.contains(&"bunny-marble".to_string()));
    assert!(
        !welcome.scenes.iter().any(|s| s == "broken"),
        "a broken file is left out"
    );
    assert_eq!(
        welcome.limits.scene_files.max_vertices,
        fovea::scene::limits::MAX_VERTICES
    );
    c.gaze(&Gaze {
        seq: 1,
        t_ms: 0.0,
        x: 0.5,
        y: 0.5,
        pupil_mm: None,
        sample_t_ms: None,
    })
    .await
    .unwrap();
    loop {
        match c
            .next_event(std::time::Duration::from_secs(60))
            .await
            .unwrap()
        {
            Event::Frame { .. } => break,
            Event::Closed(reason) => panic!("closed: {reason:?}"),
            _ => {}
        }
    }
    // A client names scenes, never paths.
    let mut other = Client::connect(&format!("ws://{addr}/ws")).await.unwrap();
    let refused = other
        .hello(&Hello {
            scene: "../lamps".into(),
            width: 64,
            height: 48,
            ..Hello::default()
        })
        .await;
    assert!(refused.is_err(), "{refused:?}");
    running.stop().await;
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn an_opaque_roof_keeps_the_light_out_of_a_translucent_slab_below_it() {
    let mut r = renderer();
    // A marble slab (a quad) under an opaque roof that covers it, the key light straight above.
    let scene = scene_json(
        "roofed",
        json!([
            {"mesh": "quad", "material": "marble", "corners": [[-2, 0, -2], [-2, 0, 2], [2, 0, 2], [2, 0, -2]]},
            {"mesh": "quad", "material": "roof", "corners": [[-3, 2, -3], [-3, 2, 3], [3, 2, 3], [3, 2, -3]]}
        ]),
        json!({"marble": {"kind": "translucent", "preset": "marble"},
               "roof": {"kind": "opaque", "albedo": [0.5, 0.5, 0.5]}}),
        json!({"eye": [0, 1, 8], "target": [0, 0, 0], "fov_y_deg": 50, "near": 0.1, "far": 100}),
        [0.0, 1.0, 0.0],
        0.0,
    );
    r.add_scene(scene).unwrap();
    let mut flux = |shadows: bool, stream: u64| {
        let mut q = full("roofed", 64, 48, stream);
        q.settings.translucency.rung = fovea::settings::Rung::BruteForce;
        q.settings.shadows = shadows;
        let img = render(&mut r, &q);
        // Photons the slab holds (a texel it covers has an extent), lit or not.
        let photons = img.photons.iter().filter(|p| p[3] > 0.0).count();
        (
            img.photons
                .iter()
                .map(|p| f64::from(p[4] + p[5] + p[6]))
                .sum::<f64>(),
            photons,
        )
    };
    let (open, n) = flux(false, 1);
    let (roofed, n_roofed) = flux(true, 2);
    assert!(n > 1000 && open > 0.0, "{n} photons carry {open}");
    assert_eq!(
        n, n_roofed,
        "the light still sees the slab's photons; the roof stops their light"
    );
    assert!(
        roofed < 1e-3 * open,
        "under the roof the photons carry {roofed} of {open}"
    );
}
