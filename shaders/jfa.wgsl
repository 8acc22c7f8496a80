// One jump-flooding pass (Rong & Tan 2006): each pixel keeps the nearest seed known to itself
// or to the 8 pixels `step` away. CPU twin: foveation::reconstruct::jfa_pass (same scan order,
// same strict comparison, integer distances: bit-identical results).

@group(0) @binding(1) var<storage, read> seeds_in: array<u32>;
@group(0) @binding(2) var<storage, read_write> seeds_out: array<u32>;
// x: jump size in pixels.
@group(0) @binding(3) var<uniform> jump: vec4<u32>;

@compute @workgroup_size(8, 8)
fn main(@builtin(global_invocation_id) id: vec3<u32>) {
    let p = vec2<i32>(id.xy);
    if (!in_frame(p)) {
        return;
    }
    let k = i32(jump.x);
    var best = seeds_in[index_of(p)];
    var best_d = seed_dist2(best, p);
    for (var j = -1; j <= 1; j++) {
        for (var i = -1; i <= 1; i++) {
            let q = p + vec2<i32>(i, j) * k;
            if (!in_frame(q)) {
                continue;
            }
            let s = seeds_in[index_of(q)];
            let d = seed_dist2(s, p);
            if (d < best_d) {
                best = s;
                best_d = d;
            }
        }
    }
    seeds_out[index_of(p)] = best;
}
