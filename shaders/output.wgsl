// Output pass: linear colour to sRGB bytes (CPU twin: optics::color::linear_to_srgb), with the
// optional overlays that show how the frame was made.

@group(0) @binding(1) var src: texture_2d<f32>;
@group(0) @binding(2) var flags_tex: texture_2d<u32>;
@group(0) @binding(3) var probability_tex: texture_2d<f32>;
@group(0) @binding(4) var out_final: texture_storage_2d<rgba8unorm, write>;

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
    var rgb = textureLoad(src, p, 0).rgb;
    if (has_mode(MODE_FOVEATED) && frame.tile.z != 0u) {
        let flags = textureLoad(flags_tex, p, 0).r;
        if (frame.tile.z == 1u) {
            if ((flags & FLAG_SAMPLED) != 0u) {
                rgb = mix(rgb, vec3<f32>(0.1, 1.0, 0.2), 0.6);
            } else if ((flags & FLAG_REUSED) != 0u) {
                rgb = mix(rgb, vec3<f32>(0.1, 0.3, 1.0), 0.45);
            }
        } else if ((flags & FLAG_COVERED) != 0u) {
            rgb = mix(rgb, heat(textureLoad(probability_tex, p, 0).r), 0.7);
        }
    }
    let s = vec3<f32>(linear_to_srgb(rgb.r), linear_to_srgb(rgb.g), linear_to_srgb(rgb.b));
    textureStore(out_final, p, vec4<f32>(s, 1.0));
}
