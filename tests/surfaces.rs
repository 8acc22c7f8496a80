//! Surfaces, shadows and scenes on the GPU: the GGX shading held to its CPU twin, shadows
//! without acne or peter-panning, double-sided materials, every shipped scene finite, and a
//! served scene folder. Runs on the software Vulkan adapter; no adapter is a failure.

mod common;

use common::images::LAVAPIPE;
use fovea::optics::specular;
use fovea::render::{FrameRequest, Inspection, Renderer};
use fovea::scene::{Folder, Scene};
use fovea::settings::{Preset, RenderSettings};
use glam::{Vec3, Vec4};
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

/// Unit view ray through pixel k's centre.
fn ray(scene: &Scene, w: u32, h: u32, k: usize) -> Vec3 {
    let cam = scene.file.camera;
    let inv = cam.view_proj(w, h).inverse();
    let (x, y) = ((k as u32 % w) as f32 + 0.5, (k as u32 / w) as f32 + 0.5);
    let far = inv * Vec4::new(x / w as f32 * 2.0 - 1.0, 1.0 - y / h as f32 * 2.0, 1.0, 1.0);
    (far.truncate() / far.w - Vec3::from(cam.eye)).normalize()
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
            let v = -ray(&scene, w, h, k).as_dvec3();
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
    let band = 3.0 * texel;
    let eye = Vec3::from(scene.file.camera.eye);
    let (mut dark, mut open) = (0, 0);
    for (k, nd) in shadowed.normal_distance.iter().enumerate() {
        let x = eye + ray(&scene, w, h, k) * nd[3];
        if nd[3] <= 0.0 || x.y.abs() > 1e-3 {
            continue; // not the floor
        }
        // Where the ray towards the light crosses the roof's plane, and how far inside it.
        let p = x + l * (3.0 / l.y);
        let inside = 3.0 - p.x.abs().max(p.z.abs());
        if inside.abs() < band {
            continue;
        }
        let ratio = shadowed.color[k][1] / lit.color[k][1];
        if inside > 0.0 {
            assert!(
                ratio < 0.1,
                "pixel {k} under the roof keeps {ratio} of its light"
            );
            dark += 1;
        } else {
            assert!(
                ratio > 0.995,
                "pixel {k} in the open lost light: {ratio} (acne)"
            );
            open += 1;
        }
    }
    assert!(
        dark > 200 && open > 2000,
        "{dark} shadowed and {open} open floor pixels checked"
    );
}

#[test]
fn a_spot_light_casts_its_own_shadow() {
    let mut r = renderer();
    let (w, h) = (160, 120);
    // The key light off; one spot 8 units above the floor, the roof 3 above it.
    let scene = Scene::from_json(
        &json!({
            "name": "spot", "ambient": 0.0, "background_srgb": [0, 0, 0],
            "light": {"to_light": [0, 1, 0], "color": [1, 1, 1], "intensity": 0},
            "lights": [{"kind": "spot", "position": [0, 8, 0], "direction": [0, -1, 0],
                        "color": [1, 1, 1], "intensity": 64, "inner_deg": 50, "outer_deg": 60}],
            "camera": {"eye": [0, 16, 14], "target": [0, 0, 0], "fov_y_deg": 50, "near": 0.5, "far": 100},
            "materials": {"floor": {"kind": "opaque", "albedo": [0.8, 0.8, 0.8], "roughness": 1.0}},
            "objects": [
                {"mesh": "plane", "material": "floor", "scale": 40.0},
                {"mesh": "quad", "material": "floor", "corners": [[-3, 3, -3], [-3, 3, 3], [3, 3, 3], [3, 3, -3]]}
            ]
        })
        .to_string(),
    )
    .unwrap();
    r.add_scene(scene.clone()).unwrap();
    let lit = render(&mut r, &{
        let mut q = full("spot", w, h, 1);
        q.settings.shadows = false;
        q
    });
    let shadowed = render(&mut r, &full("spot", w, h, 2));
    let eye = Vec3::from(scene.file.camera.eye);
    let band = 0.25;
    let (mut dark, mut open) = (0, 0);
    for (k, nd) in shadowed.normal_distance.iter().enumerate() {
        let x = eye + ray(&scene, w, h, k) * nd[3];
        if nd[3] <= 0.0 || x.y.abs() > 1e-3 {
            continue;
        }
        // Inside the inner cone only (full light), and away from the roof's shadow edge: the
        // ray to the light crosses the roof's plane at 5/8 of the point's offset.
        if (x.x * x.x + x.z * x.z).sqrt() > 8.0 * 50f32.to_radians().tan() - band {
            continue;
        }
        let inside = 3.0 - (x.x.abs().max(x.z.abs()) * 5.0 / 8.0);
        if inside.abs() < band {
            continue;
        }
        let ratio = shadowed.color[k][1] / lit.color[k][1].max(1e-6);
        if inside > 0.0 {
            assert!(
                ratio < 0.1,
                "pixel {k} under the roof keeps {ratio} of the spot's light"
            );
            dark += 1;
        } else {
            assert!(
                ratio > 0.99,
                "pixel {k} in the spot's open light lost some: {ratio} (acne)"
            );
            open += 1;
        }
    }
    assert!(
        dark > 200 && open > 200,
        "{dark} shadowed and {open} open floor pixels checked"
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

/// A PNG of `w`×1 pixels with the given RGB colours.
fn png_row(colours: &[[u8; 3]]) -> Vec<u8> {
    let mut out = Vec::new();
    let mut enc = png::Encoder::new(&mut out, colours.len() as u32, 1);
    enc.set_color(png::ColorType::Rgb);
    let mut w = enc.write_header().unwrap();
    w.write_image_data(&colours.concat()).unwrap();
    drop(w);
    out
}

#[test]
fn a_normal_map_tilts_the_shading_normal_towards_its_tangent() {
    use base64::Engine;
    // A quad in the XZ plane facing +Y, u along +x, and a flat normal map that leans every
    // normal 45° towards +u: (1, 0, 1)/√2 encoded.
    let mut bin = Vec::new();
    for p in [
        [-1f32, 0.0, 1.0],
        [1.0, 0.0, 1.0],
        [1.0, 0.0, -1.0],
        [-1.0, 0.0, -1.0],
    ] {
        for c in p {
            bin.extend_from_slice(&c.to_le_bytes());
        }
    }
    for uv in [[0f32, 1.0], [1.0, 1.0], [1.0, 0.0], [0.0, 0.0]] {
        for c in uv {
            bin.extend_from_slice(&c.to_le_bytes());
        }
    }
    for i in [0u32, 1, 2, 0, 2, 3] {
        bin.extend_from_slice(&i.to_le_bytes());
    }
    let lean = (0.5 + 0.5 * std::f32::consts::FRAC_1_SQRT_2) * 255.0;
    let texel = [lean.round() as u8, 128, lean.round() as u8];
    let image = png_row(&[texel; 4]);
    let image_at = bin.len();
    bin.extend_from_slice(&image);
    let doc = json!({
        "asset": {"version": "2.0"},
        "buffers": [{"byteLength": bin.len(), "uri": format!("data:application/octet-stream;base64,{}", base64::engine::general_purpose::STANDARD.encode(&bin))}],
        "bufferViews": [
            {"buffer": 0, "byteOffset": 0, "byteLength": 48},
            {"buffer": 0, "byteOffset": 48, "byteLength": 32},
            {"buffer": 0, "byteOffset": 80, "byteLength": 24},
            {"buffer": 0, "byteOffset": image_at, "byteLength": image.len()}
        ],
        "accessors": [
            {"bufferView": 0, "componentType": 5126, "count": 4, "type": "VEC3", "min": [-1, 0, -1], "max": [1, 0, 1]},
            {"bufferView": 1, "componentType": 5126, "count": 4, "type": "VEC2"},
            {"bufferView": 2, "componentType": 5125, "count": 6, "type": "SCALAR"}
        ],
        "images": [{"bufferView": 3, "mimeType": "image/png"}],
        "samplers": [{}],
        "textures": [{"source": 0, "sampler": 0}],
        "materials": [{"normalTexture": {"index": 0}, "pbrMetallicRoughness": {"metallicFactor": 0.0}}],
        "meshes": [{"primitives": [{"attributes": {"POSITION": 0, "TEXCOORD_0": 1}, "indices": 2, "material": 0}]}],
        "nodes": [{"mesh": 0}],
        "scenes": [{"nodes": [0]}],
        "scene": 0
    });
    let dir = std::env::temp_dir().join(format!("fovea-normal-map-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    std::fs::write(dir.join("bumpy.gltf"), doc.to_string()).unwrap();
    let scene = Scene::load(&dir.join("bumpy.gltf"), &Folder::open(&dir).unwrap()).unwrap();
    std::fs::remove_dir_all(&dir).unwrap();
    assert_eq!(scene.normal_maps.len(), 1);
    let t = scene.mesh.tangent[0];
    assert!(
        (t[0] - 1.0).abs() < 1e-5 && t[3] != 0.0,
        "tangent along +u: {t:?}"
    );
    let mut r = renderer();
    r.add_scene(scene).unwrap();
    let img = render(&mut r, &full("bumpy", 64, 48, 1));
    let mut seen = 0;
    for nd in img.normal_distance.iter().filter(|nd| nd[3] > 0.0) {
        let n = Vec3::new(nd[0], nd[1], nd[2]);
        let expected = Vec3::new(1.0, 1.0, 0.0).normalize();
        assert!(
            n.dot(expected) > 0.999,
            "normal {n:?}, expected {expected:?}"
        );
        seen += 1;
    }
    assert!(seen > 100, "{seen} pixels");
}

#[test]
fn a_base_colour_texture_is_sampled_per_pixel() {
    use base64::Engine;
    // A quad in the XY plane facing +Z, u running along x; its texture: red | blue.
    let mut bin = Vec::new();
    for p in [
        [-1f32, -1.0, 0.0],
        [1.0, -1.0, 0.0],
        [1.0, 1.0, 0.0],
        [-1.0, 1.0, 0.0],
    ] {
        for c in p {
            bin.extend_from_slice(&c.to_le_bytes());
        }
    }
    for uv in [[0f32, 1.0], [1.0, 1.0], [1.0, 0.0], [0.0, 0.0]] {
        for c in uv {
            bin.extend_from_slice(&c.to_le_bytes());
        }
    }
    for i in [0u32, 1, 2, 0, 2, 3] {
        bin.extend_from_slice(&i.to_le_bytes());
    }
    // 8 red texels then 8 blue: bilinear filtering blends only near the edges.
    let row: Vec<[u8; 3]> = (0..16)
        .map(|i| if i < 8 { [255, 0, 0] } else { [0, 0, 255] })
        .collect();
    let image = png_row(&row);
    let image_at = bin.len();
    bin.extend_from_slice(&image);
    let doc = json!({
        "asset": {"version": "2.0"},
        "buffers": [{"byteLength": bin.len(), "uri": format!("data:application/octet-stream;base64,{}", base64::engine::general_purpose::STANDARD.encode(&bin))}],
        "bufferViews": [
            {"buffer": 0, "byteOffset": 0, "byteLength": 48},
            {"buffer": 0, "byteOffset": 48, "byteLength": 32},
            {"buffer": 0, "byteOffset": 80, "byteLength": 24},
            {"buffer": 0, "byteOffset": image_at, "byteLength": image.len()}
        ],
        "accessors": [
            {"bufferView": 0, "componentType": 5126, "count": 4, "type": "VEC3", "min": [-1, -1, 0], "max": [1, 1, 0]},
            {"bufferView": 1, "componentType": 5126, "count": 4, "type": "VEC2"},
            {"bufferView": 2, "componentType": 5125, "count": 6, "type": "SCALAR"}
        ],
        "images": [{"bufferView": 3, "mimeType": "image/png"}],
        "samplers": [{}],
        "textures": [{"source": 0, "sampler": 0}],
        "materials": [{"pbrMetallicRoughness": {"baseColorTexture": {"index": 0}, "metallicFactor": 0.0, "roughnessFactor": 1.0}}],
        "meshes": [{"primitives": [{"attributes": {"POSITION": 0, "TEXCOORD_0": 1}, "indices": 2, "material": 0}]}],
        "nodes": [{"mesh": 0}],
        "scenes": [{"nodes": [0]}],
        "scene": 0
    });
    let dir = std::env::temp_dir().join(format!("fovea-texture-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    std::fs::write(dir.join("tile.gltf"), doc.to_string()).unwrap();
    let scene = Scene::load(&dir.join("tile.gltf"), &Folder::open(&dir).unwrap()).unwrap();
    assert_eq!(scene.textures.len(), 1);
    let mut r = renderer();
    r.add_scene(scene).unwrap();
    let (w, h) = (80, 60);
    let img = render(&mut r, &full("tile", w, h, 1));
    // Mean red and blue over the covered pixels of the left and right thirds.
    let mut sums = [[0.0f32; 2]; 2];
    for (k, nd) in img.normal_distance.iter().enumerate() {
        let x = k as u32 % w;
        let side = if x < w / 3 {
            0
        } else if x >= 2 * w / 3 {
            1
        } else {
            continue;
        };
        if nd[3] > 0.0 {
            sums[side][0] += img.color[k][0];
            sums[side][1] += img.color[k][2];
        }
    }
    let [[left_r, left_b], [right_r, right_b]] = sums;
    // White is added evenly by the specular lobe and the ambient sky; the texture decides
    // which way each side leans.
    assert!(left_r > 1.3 * left_b, "left third is red: {sums:?}");
    assert!(right_b > 3.0 * right_r, "right third is blue: {sums:?}");
    std::fs::remove_dir_all(&dir).unwrap();
}
