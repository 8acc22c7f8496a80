// Output pass: linear colour to sRGB bytes (CPU twin: optics::color::linear_to_srgb), with the
// optional overlays that show how the frame was made, and the gaze marker: a magenta ring with
// a centre dot and a dark outline at the gaze position the server used.

@group(0) @binding(1) var<storage, read> src: array<vec4<f32>>;
@group(0) @binding(2) var<storage, read> flags: array<u32>;
@group(0) @binding(3) var<storage, read> probability: array<f32>;
// Packed RGBA8 (red in the low byte): exactly the bytes of the image.
@group(0) @binding(4) var<storage, read_write> out_final: array<u32>;

// 1 inside `half_width` of the curve, 0 beyond it, with a one-pixel antialiased edge.
fn band(distance_to_curve: f32, half_width: f32) -> f32 {
    return 1.0 - smoothstep(half_width - 0.5, half_width + 0.5, distance_to_curve);
}

// The marker over an sRGB-encoded colour.
fn draw_marker(p: vec2<f32>, under: vec3<f32>) -> vec3<f32> {
    let d = distance(p, frame.marker_centre);
    let r = frame.marker_radius;
    let t = frame.marker_thickness;
    let half_t = 0.5 * t;
    let fill = max(band(abs(d - r), half_t), band(d, 0.6 * t));
    let outline = max(band(abs(d - r), half_t + 1.5), band(d, 0.6 * t + 1.5));
    let magenta = vec3<f32>(1.0, 0.25, 0.8);
    let alpha = max(0.85 * outline, fill);
    // Premultiplied: the magenta fill over a dark outline over the frame.
    return magenta * fill + under * (1.0 - alpha);
}

fn linear_to_srgb(c: f32) -> f32 {
    let x = clamp(c, 0.0, 1.0);
    if (x <= 0.0031308) {
        return 12.92 * x;
    }
    return 1.055 * pow(x, 1.0 / 2.4) - 0.055;
}

// Blue → cyan → yellow → red for a probability in [0, 1].
fn heat(t: f32) -> vec3<f32> {
    let x = clamp(t, 0.0, 1.0);
    return clamp(vec3<f32>(1.5 * x - 0.25, 1.0 - abs(2.0 * x - 1.0) * 0.9, 1.0 - 1.5 * x), vec3<f32>(0.0), vec3<f32>(1.0));
}

@compute @workgroup_size(8, 8)
fn main(@builtin(global_invocation_id) id: vec3<u32>) {
    let p = vec2<i32>(id.xy);
    if (!in_frame(p)) {
        return;
    }
    let k = index_of(p);
    var rgb = src[k].rgb;
    if (has_mode(MODE_FOVEATED) && frame.overlay != OVERLAY_NONE) {
        let f = flags[k];
        if (frame.overlay == OVERLAY_SAMPLES) {
            if ((f & FLAG_SAMPLED) != 0u) {
                rgb = mix(rgb, vec3<f32>(0.1, 1.0, 0.2), 0.6);
            } else if ((f & FLAG_REUSED) != 0u) {
                rgb = mix(rgb, vec3<f32>(0.1, 0.3, 1.0), 0.45);
            }
        } else if ((f & FLAG_COVERED) != 0u) {
            rgb = mix(rgb, heat(probability[k]), 0.7);
        }
    }
    var s = vec3<f32>(linear_to_srgb(rgb.r), linear_to_srgb(rgb.g), linear_to_srgb(rgb.b));
    if (frame.marker_radius > 0.0) {
        s = draw_marker(vec2<f32>(p) + 0.5, s);
    }
    out_final[k] = pack4x8unorm(vec4<f32>(s, 1.0));
}
