//! Shadow maps on the GPU: the key light's, a spot light's and a point light's cube, each
//! casting a roof's shadow on a floor with no acne and no peter-panning. Software Vulkan
//! adapter; no adapter is a failure.

mod common;

use common::frames::{full, render, renderer, scene_json};
use common::view_ray;
use fovea::render::{Inspection, Renderer};
use fovea::scene::Scene;
use glam::Vec3;
use serde_json::json;

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
    let point =
        json!({"kind": "point", "position": [0, 4, 0], "color": [1, 1, 1], "intensity": 64});
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
