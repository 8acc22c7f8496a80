//! Radiosity in the frame (GPU, software adapter): the cornell box's walls light each other and
//! the translucent bunny, the solve is shared by every renderer, open scenes never run it unless
//! their file asks, and then a sunlit floor lights the object standing on it.

use std::time::Duration;

use fovea::render::{FrameRequest, Inspection, Renderer};

fn renderer() -> Renderer {
    Renderer::new().unwrap_or_else(|e| panic!("GPU tests need an adapter: {e}"))
}

const W: u32 = 160;
const H: u32 = 120;

fn frame(
    r: &mut Renderer,
    indirect: bool,
    stream: u64,
) -> (Inspection, fovea::render::RenderedFrame) {
    let mut req = FrameRequest::new("cornell", W, H);
    req.settings = fovea::settings::RenderSettings::of(fovea::settings::Preset::Full);
    req.settings.indirect = indirect;
    req.stream = stream;
    req.marker = false;
    let f = r.render(&req).unwrap();
    (r.inspect(stream, "cornell", W, H).unwrap(), f)
}

/// Mean linear colour of the pixels whose normal passes `keep` and whose column is in `cols`.
fn mean(img: &Inspection, keep: impl Fn([f32; 3]) -> bool, cols: std::ops::Range<u32>) -> [f64; 3] {
    let (mut sum, mut n) = ([0.0f64; 3], 0.0);
    for (k, nd) in img.normal_distance.iter().enumerate() {
        let x = k as u32 % W;
        let c = img.color[k];
        // Lamp pixels show its exitance (≫ 1): not a surface lit by anything.
        if nd[3] > 0.0 && cols.contains(&x) && keep([nd[0], nd[1], nd[2]]) && c[0] < 5.0 {
            for i in 0..3 {
                sum[i] += f64::from(c[i]);
            }
            n += 1.0;
        }
    }
    assert!(n > 10.0, "too few pixels selected ({n})");
    sum.map(|s| s / n)
}

fn ceiling(n: [f32; 3]) -> bool {
    n[1] < -0.99
}
fn floor(n: [f32; 3]) -> bool {
    n[1] > 0.99
}
/// The bunny: no wall has a slanted normal.
fn bunny(n: [f32; 3]) -> bool {
    n.iter().all(|c| c.abs() < 0.99)
}

#[test]
fn the_walls_light_the_room_and_the_bunny_once_radiosity_converges() {
    let mut r = renderer();
    // As the bench waits before measuring: the frames after it read the converged solution.
    r.settle_radiosity("cornell", Duration::from_secs(600), &|| false)
        .unwrap();
    let solve = r
        .radiosity("cornell")
        .unwrap()
        .expect("the plan runs radiosity for cornell");
    let snap = solve.latest().expect("a snapshot");
    assert!(snap.converged, "{:?}", snap.stats);
    let (gi, f) = frame(&mut r, true, 1);
    let (direct, _) = frame(&mut r, false, 2);
    let progress = f.radiosity.expect("frames say which solve lit them");
    assert!(
        progress.converged && progress.unshot < 0.001,
        "{progress:?}"
    );

    // The ceiling faces away from the lamp beside it: only interreflected light reaches it.
    let all = 0..W;
    assert!(mean(&direct, ceiling, all.clone())[1] < 1e-3);
    assert!(mean(&gi, ceiling, all.clone())[1] > 0.05);
    // Colour bleeding: the floor by the red wall is redder than by the green one, which it is
    // not under the lamp's direct light alone.
    let ratio = |c: [f64; 3]| c[0] / c[1];
    let (left, right) = (0..W / 3, 2 * W / 3..W);
    let bleed = ratio(mean(&gi, floor, left.clone())) / ratio(mean(&gi, floor, right.clone()));
    let plain = ratio(mean(&direct, floor, left)) / ratio(mean(&direct, floor, right));
    assert!(
        bleed > 1.1 && (plain - 1.0).abs() < 0.01,
        "bleed {bleed}, direct only {plain}"
    );
    // The translucent bunny gets the walls' light through its photons: brighter, and its side
    // facing the red wall redder than its side facing the green one.
    let lit = mean(&gi, bunny, all.clone());
    let unlit = mean(&direct, bunny, all);
    assert!(
        lit[1] > 1.5 * unlit[1],
        "bunny {lit:?} vs direct only {unlit:?}"
    );
    let facing_red = mean(&gi, |n| bunny(n) && n[0] < -0.5, 0..W);
    let facing_green = mean(&gi, |n| bunny(n) && n[0] > 0.5, 0..W);
    assert!(
        ratio(facing_red) > 1.5 * ratio(facing_green),
        "{facing_red:?} vs {facing_green:?}"
    );
}

#[test]
fn renderers_share_one_solve_and_open_scenes_have_none() {
    let (mut a, mut b) = (renderer(), renderer());
    let sa = a.radiosity("cornell").unwrap().unwrap();
    let sb = b.radiosity("cornell").unwrap().unwrap();
    assert!(sa.same_solve(&sb));
    for open in ["bunny-marble", "materials", "opaque"] {
        assert!(a.radiosity(open).unwrap().is_none(), "{open}");
    }
    let mut req = FrameRequest::new("bunny-marble", 32, 24);
    req.settings = fovea::settings::RenderSettings::of(fovea::settings::Preset::Fast);
    assert!(a.render(&req).unwrap().radiosity.is_none());
}

/// Towards the key light of the sunlit-floor scenes.
const TO_LIGHT: [f32; 3] = [-0.5, 0.7, 0.6];

/// A bunny of `material` on a plaster floor under a sun, no emitter and no ambient, radiosity
/// on; the renderer holds it with its solve converged.
fn sunlit_bunny(name: &str, material: serde_json::Value) -> Renderer {
    let scene = fovea::scene::Scene::from_json(
        &serde_json::json!({
            "name": name, "ambient": 0.0, "background_srgb": [0, 0, 0],
            "light": {"to_light": TO_LIGHT, "color": [1, 1, 1], "intensity": 1},
            "camera": {"eye": [0, 9, 22], "target": [0, 3, 0], "fov_y_deg": 35, "near": 1, "far": 200},
            "radiosity": {"mode": "on", "patch_size": 2.5},
            "materials": {
                "bunny": material,
                "plaster": {"kind": "opaque", "albedo": [0.7, 0.7, 0.7], "roughness": 0.9}
            },
            "objects": [
                {"mesh": "bunny.ply", "material": "bunny", "scale": 0.7},
                {"mesh": "quad", "material": "plaster",
                 "corners": [[-20, 0, -20], [-20, 0, 20], [20, 0, 20], [20, 0, -20]]}
            ]
        })
        .to_string(),
    )
    .unwrap();
    let mut r = renderer();
    r.add_scene(scene).unwrap();
    let solve = r.radiosity(name).unwrap().expect("mode on runs it");
    let snap = solve.wait(Duration::from_secs(600)).expect("a snapshot");
    assert!(snap.converged, "{:?}", snap.stats);
    r
}

/// One `full` frame of `name` at `rung` (None: the preset's), with or without radiosity's
/// interreflected light.
fn sunlit_shot(
    r: &mut Renderer,
    name: &str,
    rung: Option<fovea::settings::Rung>,
    indirect: bool,
    stream: u64,
) -> Inspection {
    let mut req = FrameRequest::new(name, W, H);
    req.settings = fovea::settings::RenderSettings::of(fovea::settings::Preset::Full);
    if let Some(rung) = rung {
        req.settings.translucency.rung = rung;
    }
    req.settings.indirect = indirect;
    req.stream = stream;
    req.marker = false;
    r.render(&req).unwrap();
    r.inspect(stream, name, W, H).unwrap()
}

/// The bunny's sides facing away from the light and down: they see the floor, never the sun.
fn away(n: [f32; 3]) -> bool {
    bunny(n) && glam::Vec3::from(n).dot(glam::Vec3::from(TO_LIGHT).normalize()) < -0.1 && n[1] < 0.0
}

#[test]
fn a_sunlit_floor_lights_the_bunny_on_it_when_the_scene_asks_for_radiosity() {
    // No emitter and no ambient: with radiosity on, the key light's first bounce is the only
    // light the bunny's shaded side gets.
    let white = serde_json::json!({"kind": "opaque", "albedo": [0.8, 0.8, 0.8], "roughness": 0.9});
    let mut r = sunlit_bunny("sunlit-floor", white);
    let lit = sunlit_shot(&mut r, "sunlit-floor", None, true, 1);
    let dark = sunlit_shot(&mut r, "sunlit-floor", None, false, 2);
    let (b_lit, b_dark) = (mean(&lit, away, 0..W)[1], mean(&dark, away, 0..W)[1]);
    assert!(
        b_dark < 1e-3 && b_lit > 0.05,
        "the bunny's unlit side: {b_dark} direct only, {b_lit} with the floor's bounce"
    );
    // The floor mostly sees the sky: its light barely changes.
    let (f_lit, f_dark) = (mean(&lit, floor, 0..W)[1], mean(&dark, floor, 0..W)[1]);
    assert!(
        f_lit >= f_dark && f_lit < 1.08 * f_dark,
        "floor {f_lit} with radiosity, {f_dark} without"
    );
}

#[test]
fn the_floors_bounce_reaches_a_translucent_bodys_far_side_on_every_rung() {
    // The photons carry radiosity's irradiance only where they enter, on the side facing the
    // key light; the side facing away gets the floor's bounce locally. On every rung the
    // bounce adds about what it adds on the opaque one (albedo × irradiance through the
    // interface), not only the interface's reflection of it.
    let marble = serde_json::json!({"kind": "translucent", "preset": "marble", "roughness": 0.3});
    let mut r = sunlit_bunny("sunlit-marble", marble);
    let mut stream = 0;
    let mut gain = |r: &mut Renderer, rung| {
        stream += 2;
        let lit = sunlit_shot(r, "sunlit-marble", Some(rung), true, stream);
        let dark = sunlit_shot(r, "sunlit-marble", Some(rung), false, stream + 1);
        mean(&lit, away, 0..W)[1] - mean(&dark, away, 0..W)[1]
    };
    use fovea::settings::Rung;
    let opaque = gain(&mut r, Rung::Opaque);
    assert!(opaque > 0.03, "the bounce on the opaque rung: {opaque}");
    for rung in [Rung::Hierarchical, Rung::BruteForce] {
        let g = gain(&mut r, rung);
        assert!(
            g > 0.8 * opaque && g < 1.5 * opaque,
            "{rung:?}: the bounce adds {g}, on the opaque rung {opaque}"
        );
    }
}
