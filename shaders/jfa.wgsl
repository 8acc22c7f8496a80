// One jump-flooding pass (Rong & Tan 2006): each pixel keeps the nearest seed known to itself
// or to the 8 pixels `step` away. CPU twin: foveation::reconstruct::jfa_pass (same scan order,
// same strict comparison, integer distances: bit-identical results).

@group(0) @binding(1) var seeds_in: texture_2d<u32>;
@group(0) @binding(2) var seeds_out: texture_storage_2d<r32uint, write>;
// x: jump size in pixels.
@group(0) @binding(3) var<uniform> jump: vec4<u32>;

@compute @workgroup_size(8, 8)
fn main(@builtin(global_invocation_id) id: vec3<u32>) {
    let p = vec2<i32>(id.xy);
    if (!in_frame(p)) {
        return;
    }
    let k = i32(jump.x);
    var best = textureLoad(seeds_in, p, 0).r;
    var best_d = seed_dist2(best, p);
    for (var j = -1; j <= 1; j++) {
        for (var i = -1; i <= 1; i++) {
            let q = p + vec2<i32>(i, j) * k;
            if (!in_frame(q)) {
                continue;
            }
            let s = textureLoad(seeds_in, q, 0).r;
            let d = seed_dist2(s, p);
            if (d < best_d) {
                best = s;
                best_d = d;
            }
        }
    }
    textureStore(seeds_out, p, vec4<u32>(best));
}
