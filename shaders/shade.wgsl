// Shading pass: the frame's shading, run only where it is needed. `shade_list` runs over the
// compacted list (one invocation per sampled pixel, dispatched indirectly); `shade_grid` over
// the whole frame, shading every pixel in full mode and only sampled ones otherwise (the
// uncompacted variant the compaction is measured against).

@group(0) @binding(1) var normal_distance: texture_2d<f32>;
@group(0) @binding(2) var albedo_tex: texture_2d<f32>;
@group(0) @binding(3) var<storage, read> flags: array<u32>;
@group(0) @binding(4) var<storage, read> list: array<u32>;
@group(0) @binding(5) var<storage, read> counter: array<u32, 4>;
@group(0) @binding(6) var<storage, read_write> out_color: array<vec4<f32>>;

fn shade(p: vec2<i32>) {
    let a = textureLoad(albedo_tex, p, 0);
    var rgb = frame.background.rgb;
    if (a.a > 0.5) {
        rgb = lambert(textureLoad(normal_distance, p, 0).xyz, a.rgb);
    }
    out_color[index_of(p)] = vec4<f32>(rgb, 0.0);
}

@compute @workgroup_size(64)
fn shade_list(@builtin(global_invocation_id) id: vec3<u32>) {
    if (id.x >= counter[0]) {
        return;
    }
    shade(unpack_seed(list[id.x]));
}

@compute @workgroup_size(8, 8)
fn shade_grid(@builtin(global_invocation_id) id: vec3<u32>) {
    let p = vec2<i32>(id.xy);
    if (!in_frame(p)) {
        return;
    }
    if (has_mode(MODE_FOVEATED) && (flags[index_of(p)] & FLAG_SAMPLED) == 0u) {
        return;
    }
    shade(p);
}
