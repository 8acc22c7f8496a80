//! glTF textures on the GPU: a base colour map sampled per pixel and a normal map tilting the
//! shading normal, each on a one-quad glTF built here. Software Vulkan adapter; no adapter is a
//! failure.

use base64::Engine;
use fovea::render::{FrameRequest, Inspection, Renderer};
use fovea::scene::{Folder, Scene};
use fovea::settings::{Preset, RenderSettings};
use glam::Vec3;
use serde_json::json;

fn render(scene: Scene, w: u32, h: u32) -> Inspection {
    let mut r = Renderer::new().unwrap_or_else(|e| panic!("GPU tests need an adapter: {e}"));
    let name = scene.name().to_string();
    r.add_scene(scene).unwrap();
    let mut req = FrameRequest::new(&name, w, h);
    req.settings = RenderSettings::of(Preset::Full);
    req.marker = false;
    r.render(&req).unwrap();
    r.inspect(req.stream, &name, w, h).unwrap()
}

/// A PNG one pixel high with the given RGB colours.
fn png_row(colours: &[[u8; 3]]) -> Vec<u8> {
    let mut out = Vec::new();
    let mut enc = png::Encoder::new(&mut out, colours.len() as u32, 1);
    enc.set_color(png::ColorType::Rgb);
    let mut w = enc.write_header().unwrap();
    w.write_image_data(&colours.concat()).unwrap();
    drop(w);
    out
}

/// A glTF of one quad (corners counter-clockwise from the front, TEXCOORD_0 (0,1) (1,1) (1,0)
/// (0,0), TEXCOORD_1 the same mirrored in u) whose material `material` may use texture 0, the
/// image `row`; loaded as scene `name`.
fn quad(name: &str, corners: [[f32; 3]; 4], material: serde_json::Value, row: &[[u8; 3]]) -> Scene {
    quad_sampled(name, corners, material, row, json!({}))
}

/// [`quad`] with its texture read through `sampler` (a glTF sampler object).
fn quad_sampled(
    name: &str,
    corners: [[f32; 3]; 4],
    material: serde_json::Value,
    row: &[[u8; 3]],
    sampler: serde_json::Value,
) -> Scene {
    let mut bin = Vec::new();
    for c in corners.iter().flatten() {
        bin.extend_from_slice(&c.to_le_bytes());
    }
    for c in [
        0f32, 1.0, 1.0, 1.0, 1.0, 0.0, 0.0, 0.0, 1.0, 1.0, 0.0, 1.0, 0.0, 0.0, 1.0, 0.0,
    ] {
        bin.extend_from_slice(&c.to_le_bytes());
    }
    for i in [0u32, 1, 2, 0, 2, 3] {
        bin.extend_from_slice(&i.to_le_bytes());
    }
    let image = png_row(row);
    let image_at = bin.len();
    bin.extend_from_slice(&image);
    let lo: Vec<f32> = (0..3)
        .map(|k| corners.iter().map(|c| c[k]).fold(f32::MAX, f32::min))
        .collect();
    let hi: Vec<f32> = (0..3)
        .map(|k| corners.iter().map(|c| c[k]).fold(f32::MIN, f32::max))
        .collect();
    let doc = json!({
        "asset": {"version": "2.0"},
        "buffers": [{"byteLength": bin.len(), "uri": format!("data:application/octet-stream;base64,{}", base64::engine::general_purpose::STANDARD.encode(&bin))}],
        "bufferViews": [
            {"buffer": 0, "byteOffset": 0, "byteLength": 48},
            {"buffer": 0, "byteOffset": 48, "byteLength": 32},
            {"buffer": 0, "byteOffset": 112, "byteLength": 24},
            {"buffer": 0, "byteOffset": image_at, "byteLength": image.len()},
            {"buffer": 0, "byteOffset": 80, "byteLength": 32}
        ],
        "accessors": [
            {"bufferView": 0, "componentType": 5126, "count": 4, "type": "VEC3", "min": lo, "max": hi},
            {"bufferView": 1, "componentType": 5126, "count": 4, "type": "VEC2"},
            {"bufferView": 2, "componentType": 5125, "count": 6, "type": "SCALAR"},
            {"bufferView": 4, "componentType": 5126, "count": 4, "type": "VEC2"}
        ],
        "images": [{"bufferView": 3, "mimeType": "image/png"}],
        "samplers": [sampler],
        "textures": [{"source": 0, "sampler": 0}],
        "materials": [material],
        "meshes": [{"primitives": [{"attributes": {"POSITION": 0, "TEXCOORD_0": 1, "TEXCOORD_1": 3}, "indices": 2, "material": 0}]}],
        "nodes": [{"mesh": 0}],
        "scenes": [{"nodes": [0]}],
        "scene": 0
    });
    let dir = std::env::temp_dir().join(format!("fovea-{name}-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let file = dir.join(format!("{name}.gltf"));
    std::fs::write(&file, doc.to_string()).unwrap();
    let scene = Scene::load(&file, &Folder::open(&dir).unwrap()).unwrap();
    std::fs::remove_dir_all(&dir).unwrap();
    scene
}

/// Summed (red, blue) over the left and right thirds of what the quad covers.
fn red_and_blue_by_side(img: Inspection, w: u32) -> [[f32; 2]; 2] {
    let xs: Vec<u32> = (0..img.normal_distance.len())
        .filter(|&k| img.normal_distance[k][3] > 0.0)
        .map(|k| k as u32 % w)
        .collect();
    let (lo, hi) = (*xs.iter().min().unwrap(), *xs.iter().max().unwrap());
    let third = (hi - lo) / 3;
    let mut sums = [[0.0f32; 2]; 2];
    for (k, nd) in img.normal_distance.iter().enumerate() {
        let x = k as u32 % w;
        let side = if x < lo + third {
            0
        } else if x > hi - third {
            1
        } else {
            continue;
        };
        if nd[3] > 0.0 {
            sums[side][0] += img.color[k][0];
            sums[side][1] += img.color[k][2];
        }
    }
    sums
}

/// 8 red texels then 8 blue (filtering blends only the edges).
fn red_then_blue() -> Vec<[u8; 3]> {
    (0..16)
        .map(|i| if i < 8 { [255, 0, 0] } else { [0, 0, 255] })
        .collect()
}

/// A quad facing +Z, u along x.
const FACING_Z: [[f32; 3]; 4] = [
    [-1.0, -1.0, 0.0],
    [1.0, -1.0, 0.0],
    [1.0, 1.0, 0.0],
    [-1.0, 1.0, 0.0],
];

#[test]
fn a_base_colour_texture_is_sampled_per_pixel() {
    let material = json!({"pbrMetallicRoughness": {"baseColorTexture": {"index": 0}, "metallicFactor": 0.0, "roughnessFactor": 1.0}});
    let scene = quad("tile", FACING_Z, material, &red_then_blue());
    assert_eq!(scene.textures.len(), 1);
    let sums = red_and_blue_by_side(render(scene, 80, 60), 80);
    let [[left_r, left_b], [right_r, right_b]] = sums;
    // White is added evenly by the specular lobe and the ambient sky; the texture decides
    // which way each side leans.
    assert!(left_r > 1.3 * left_b, "left third is red: {sums:?}");
    assert!(right_b > 3.0 * right_r, "right third is blue: {sums:?}");
}

#[test]
fn a_texture_transform_mirrors_the_base_colour_on_the_gpu() {
    // u' = 1 − u: the red half of the image lands on the quad's right.
    let material = json!({"pbrMetallicRoughness": {"baseColorTexture": {"index": 0,
        "extensions": {"KHR_texture_transform": {"offset": [1, 0], "scale": [-1, 1]}}},
        "metallicFactor": 0.0, "roughnessFactor": 1.0}});
    let scene = quad("mirrored", FACING_Z, material, &red_then_blue());
    let sums = red_and_blue_by_side(render(scene, 80, 60), 80);
    let [[left_r, left_b], [right_r, right_b]] = sums;
    assert!(left_b > 3.0 * left_r, "left third is blue: {sums:?}");
    assert!(right_r > 1.3 * right_b, "right third is red: {sums:?}");
}

#[test]
fn each_map_reads_its_own_coordinate_set_and_transform() {
    // TEXCOORD_1 is TEXCOORD_0 mirrored in u. Base colour on set 1 scaled by 2; normal map on
    // set 0 turned a quarter (u' = v, v' = 1 − u with the offset).
    let material = json!({
        "pbrMetallicRoughness": {"baseColorTexture": {"index": 0, "texCoord": 1,
            "extensions": {"KHR_texture_transform": {"scale": [2, 2]}}}},
        "normalTexture": {"index": 0,
            "extensions": {"KHR_texture_transform": {"rotation": std::f64::consts::FRAC_PI_2, "offset": [0, 1]}}}
    });
    let scene = quad("two-sets", FACING_Z, material, &[[128, 128, 255]; 2]);
    // Vertex 1 has TEXCOORD_0 (1, 1) and TEXCOORD_1 (0, 1).
    let [bu, bv, du, dv] = scene.mesh.uv[1];
    assert_eq!([bu, bv], [0.0, 2.0], "base colour: set 1 scaled");
    assert!(
        (du - 1.0).abs() < 1e-6 && (dv - 0.0).abs() < 1e-6,
        "normal map: set 0 turned, {:?}",
        [du, dv]
    );
    // The tangent follows the normal map's turned coordinates: u' grows with v, which runs
    // down the quad (−y).
    let t = scene.mesh.tangent[1];
    assert!(t[1] < -0.999, "tangent along −y: {t:?}");
    // A set the primitive lacks leaves the map without coordinates rather than failing.
    let material =
        json!({"pbrMetallicRoughness": {"baseColorTexture": {"index": 0, "texCoord": 5}}});
    let scene = quad("missing-set", FACING_Z, material, &red_then_blue());
    assert!(scene.mesh.uv.iter().all(|uv| *uv == [0.0; 4]));
}

#[test]
fn a_normal_map_tilts_the_shading_normal_towards_its_tangent() {
    // A quad facing +Y, u along +x, and a flat map leaning every normal 45° towards +u.
    let lean = ((0.5 + 0.5 * std::f32::consts::FRAC_1_SQRT_2) * 255.0).round() as u8;
    let material =
        json!({"normalTexture": {"index": 0}, "pbrMetallicRoughness": {"metallicFactor": 0.0}});
    let corners = [
        [-1.0, 0.0, 1.0],
        [1.0, 0.0, 1.0],
        [1.0, 0.0, -1.0],
        [-1.0, 0.0, -1.0],
    ];
    let scene = quad("bumpy", corners, material, &[[lean, 128, lean]; 4]);
    assert_eq!(scene.linear_maps.len(), 1);
    let t = scene.mesh.tangent[0];
    assert!(
        (t[0] - 1.0).abs() < 1e-5 && t[3] != 0.0,
        "tangent along +u: {t:?}"
    );
    let img = render(scene, 64, 48);
    let expected = Vec3::new(1.0, 1.0, 0.0).normalize();
    let mut seen = 0;
    for nd in img.normal_distance.iter().filter(|nd| nd[3] > 0.0) {
        let n = Vec3::new(nd[0], nd[1], nd[2]);
        assert!(
            n.dot(expected) > 0.999,
            "normal {n:?}, expected {expected:?}"
        );
        seen += 1;
    }
    assert!(seen > 100, "{seen} pixels");
}

#[test]
fn an_occlusion_map_dims_the_ambient_light_only() {
    // The same quad three times: fully occluded (R = 0) at strength 1, the same map at
    // strength 0, and unoccluded (R = 255) at strength 1. The model's default key light and
    // its ambient sky (0.1) light it.
    let corners = [
        [-1.0, 0.0, 1.0],
        [1.0, 0.0, 1.0],
        [1.0, 0.0, -1.0],
        [-1.0, 0.0, -1.0],
    ];
    let shade = |name: &str, value: u8, strength: f64| {
        let material = json!({"occlusionTexture": {"index": 0, "strength": strength},
            "pbrMetallicRoughness": {"metallicFactor": 0.0, "roughnessFactor": 1.0}});
        let scene = quad(name, corners, material, &[[value, value, value]; 2]);
        assert_eq!(scene.material_occlusion_maps[0], Some((0, strength as f32)));
        let img = render(scene, 48, 36);
        img.color
            .iter()
            .zip(&img.normal_distance)
            .filter(|(_, nd)| nd[3] > 0.0)
            .map(|(c, _)| c[1])
            .collect::<Vec<f32>>()
    };
    let dark = shade("occluded", 0, 1.0);
    let plain = shade("ignored", 0, 0.0);
    let open = shade("open", 255, 1.0);
    assert!(dark.len() > 100 && dark.len() == plain.len() && plain.len() == open.len());
    for ((d, p), o) in dark.iter().zip(&plain).zip(&open) {
        assert!(
            p - d > 0.05 && p - d < 0.15,
            "the ambient sky's share: {p} − {d}"
        );
        assert!(
            (o - p).abs() < 2e-3,
            "an unoccluded map changes nothing: {o} vs {p}"
        );
    }
}

/// The red share r / (r + b) of each covered pixel along the middle row, left to right.
fn red_share_along_the_middle(img: &Inspection, w: u32, h: u32) -> Vec<f32> {
    let row = (h / 2 * w) as usize;
    (row..row + w as usize)
        .filter(|&k| img.normal_distance[k][3] > 0.0)
        .map(|k| img.color[k][0] / (img.color[k][0] + img.color[k][2]).max(1e-6))
        .collect()
}

#[test]
fn wrap_modes_repeat_clamp_or_mirror_the_texture_beyond_its_edge() {
    // u runs 0 → 3 across the quad over an image that is red on its left half, blue on its
    // right: repeat shows R B R B R B, clamp R B then the edge texel's blue, mirror R B B R R B.
    let material = json!({"pbrMetallicRoughness": {"baseColorTexture": {"index": 0,
        "extensions": {"KHR_texture_transform": {"scale": [3, 1]}}},
        "metallicFactor": 0.0, "roughnessFactor": 1.0}});
    let (w, h) = (320, 200);
    let changes = |wrap: u32| {
        let sampler = json!({"wrapS": wrap, "wrapT": 33071});
        let scene = quad_sampled(
            "wrapped",
            FACING_Z,
            material.clone(),
            &red_then_blue(),
            sampler,
        );
        let shares = red_share_along_the_middle(&render(scene, w, h), w, h);
        assert!(shares.len() > 80, "{} pixels", shares.len());
        // Colour changes, counted with hysteresis so a filtered edge counts once.
        let mut red = shares[0] > 0.5;
        let mut n = 0;
        for s in &shares {
            if (red && *s < 0.3) || (!red && *s > 0.7) {
                red = !red;
                n += 1;
            }
        }
        (n, shares[0] > 0.5, *shares.last().unwrap() > 0.5)
    };
    assert_eq!(changes(10497), (5, true, false), "REPEAT");
    assert_eq!(changes(33071), (1, true, false), "CLAMP_TO_EDGE");
    assert_eq!(changes(33648), (3, true, false), "MIRRORED_REPEAT");
}

#[test]
fn a_nearest_magnified_texture_keeps_its_texels_square() {
    // Two texels stretched over the whole quad: filtered, the middle is a long red-to-blue
    // ramp; NEAREST (9728), a sharp edge.
    let material = json!({"pbrMetallicRoughness": {"baseColorTexture": {"index": 0},
        "metallicFactor": 0.0, "roughnessFactor": 1.0}});
    let (w, h) = (320, 200);
    let blended = |sampler: serde_json::Value, nearest: bool| {
        let scene = quad_sampled(
            "pixel-art",
            FACING_Z,
            material.clone(),
            &[[255, 0, 0], [0, 0, 255]],
            sampler,
        );
        assert_eq!(scene.textures[0].sampling.nearest, nearest);
        let shares = red_share_along_the_middle(&render(scene, w, h), w, h);
        assert!(shares.len() > 80, "{} pixels", shares.len());
        shares.iter().filter(|s| (0.3..0.7).contains(*s)).count()
    };
    let linear = blended(json!({"magFilter": 9729}), false);
    let nearest = blended(json!({"magFilter": 9728}), true);
    eprintln!("mixed pixels: linear {linear}, nearest {nearest}");
    assert!(linear >= 15, "a filtered ramp: {linear} mixed pixels");
    assert!(nearest <= 3, "a sharp edge: {nearest} mixed pixels");
}
