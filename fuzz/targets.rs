//! What is fuzzed: every parser that takes bytes from outside (a client's messages, a server's
//! frames, scene files, PLY, OBJ and glTF models, gaze recordings, target URLs). Each target
//! parses and drops the result; errors are fine, panics, hangs and runaway allocation are not.
//! Included with `#[path]` beside `engine.rs`; `target.rs` is the CLI's URL guard, included
//! from `src/cli` the same way (it lives in the binary).

use super::engine::Target;
use super::url_guard;

fn text(b: &[u8]) -> std::borrow::Cow<'_, str> {
    String::from_utf8_lossy(b)
}

pub const TARGETS: &[Target] = &[
    Target {
        name: "client_message",
        run: |b| {
            let _ = fovea::protocol::parse_client_message(&text(b), &Default::default());
        },
        dictionary: &[
            "\"type\"",
            "\"hello\"",
            "\"gaze\"",
            "\"ack\"",
            "\"settings\"",
            "\"camera\"",
            "\"width\":",
            "\"height\":",
            "\"preset\":",
            "\"reference\"",
            "\"t_ms\":",
            "\"x\":",
            "\"seq\":",
            "\"pupil_mm\":",
            "\"frame\":",
            "\"display\":",
            "\"codec\":",
            "\"png\"",
            "\"max_in_flight\":",
            "\"orbit\":",
            "\"zoom\":",
            "null",
            "true",
            "[]",
            "{}",
        ],
        seeds: &[
            r#"{"type":"hello","v":1,"scene":"gallery","width":640,"height":480,"preset":"balanced","codec":"jpeg","quality":80,"max_in_flight":2}"#,
            r#"{"type":"gaze","seq":3,"t_ms":12.5,"x":0.4,"y":0.6,"pupil_mm":4.2}"#,
            r#"{"type":"ack","frame":7,"t_ms":30.0,"dropped":false}"#,
            r#"{"type":"settings","preset":"fast","mar_slope":0.03,"foveation":true}"#,
            r#"{"type":"camera","orbit_deg":[10,-5],"zoom":1.2}"#,
        ],
    },
    Target {
        name: "frame",
        run: |b| {
            let _ = fovea::protocol::decode_frame(b);
        },
        dictionary: &["FOVF", "\"frame\":", "\"stages_ms\":", "{}"],
        seeds: &[],
    },
    Target {
        name: "scene_file",
        run: |b| {
            let _ = fovea::scene::Scene::from_json(&text(b));
        },
        dictionary: &[
            "\"objects\":",
            "\"mesh\":",
            "\"quad\"",
            "\"sphere\"",
            "\"plane\"",
            "\"bunny\"",
            "\"materials\":",
            "\"kind\":",
            "\"translucent\"",
            "\"emitter\"",
            "\"radiosity\":",
            "\"patch_size\":",
            "\"max_depth\":",
            "\"corners\":",
            "\"scale\":",
            "\"lights\":",
            "\"spot\"",
            "\"point\"",
            "\"camera\":",
            "\"fov_y_deg\":",
            "\"mm_per_unit\":",
        ],
        seeds: &[],
    },
    Target {
        name: "ply",
        run: |b| {
            let _ = fovea::scene::parse_ply(b);
        },
        dictionary: &[
            "ply\n",
            "format ascii 1.0\n",
            "format binary_little_endian 1.0\n",
            "format binary_big_endian 1.0\n",
            "element vertex ",
            "element face ",
            "property float x\n",
            "property list uchar int vertex_indices\n",
            "end_header\n",
            "comment ",
            "property double nx\n",
        ],
        seeds: &[],
    },
    Target {
        name: "obj",
        run: |b| {
            let _ = fovea::scene::parse_obj(b);
        },
        dictionary: &[
            "v ", "vn ", "vt ", "f ", "/", "//", "o ", "g ", "usemtl ", "mtllib ", "\n",
        ],
        seeds: &[],
    },
    Target {
        name: "gltf",
        run: |b| {
            let _ = fovea::scene::Scene::check_gltf_bytes(b);
        },
        dictionary: &[
            "\"accessors\":",
            "\"bufferViews\":",
            "\"buffers\":",
            "\"byteLength\":",
            "\"byteOffset\":",
            "\"byteStride\":",
            "\"count\":",
            "\"componentType\":",
            "5126",
            "5125",
            "5123",
            "\"VEC3\"",
            "\"SCALAR\"",
            "\"meshes\":",
            "\"primitives\":",
            "\"indices\":",
            "\"POSITION\"",
            "\"materials\":",
            "\"extensionsRequired\":",
            "\"KHR_lights_punctual\"",
            "\"nodes\":",
            "\"matrix\":",
            "\"scenes\":",
            "glTF",
        ],
        seeds: &[],
    },
    Target {
        name: "gaze_csv",
        run: |b| {
            let _ = fovea::gaze::formats::parse(&text(b), &Default::default());
        },
        dictionary: &[
            "t_s,xpos,ypos,ps\n",
            "t_ms,x,y,pupil_mm\n",
            "gaze_timestamp,norm_pos_x,norm_pos_y\n",
            "timestamp [ns],gaze x [px],gaze y [px]\n",
            "device_time_stamp,gaze_point_x,gaze_point_y\n",
            ",",
            "\n",
            ".",
            "nan",
            "-",
            "\"",
        ],
        seeds: &[],
    },
    Target {
        name: "url",
        run: |b| {
            let _ = url_guard::url_is_allowed(&text(b), &["example.org".to_string()]);
        },
        dictionary: &[
            "ws://",
            "wss://",
            "http://",
            "127.0.0.1",
            "localhost",
            "[::1]",
            "[::ffff:127.0.0.1]",
            "@",
            ":",
            "/ws",
            "0x7f",
            "2130706433",
            "%2e",
            ".",
            "example.org",
            "?",
            "#",
        ],
        seeds: &[
            "ws://127.0.0.1:8080/ws",
            "ws://localhost:1@127.1:9/ws",
            "ws://[::1]:80/ws",
            "ws://example.org/ws",
            "ws://0x7f.1/ws",
            "ws://2130706433/ws",
        ],
    },
];
