// One jump-flooding pass (Rong & Tan 2006): each pixel keeps the nearest seed known to itself
// or to the 8 pixels `step` away. CPU twin: foveation::reconstruct::jfa_pass (same scan order,
// same strict comparison, integer distances: bit-identical results).
//
// The steps ping-pong between two r32uint textures rather than buffers: each pixel reads nine
// others, and a software adapter fetches texels for a whole SIMD row at once where it loads
// buffer values at per-pixel addresses one lane at a time. The first step reads the sampling
// pass's seed buffer.

@group(0) @binding(1) var seeds_in: texture_2d<u32>;
@group(0) @binding(2) var seeds_out: texture_storage_2d<r32uint, write>;
// x: jump size in pixels.
@group(0) @binding(3) var<uniform> jump: vec4<u32>;
@group(0) @binding(4) var<storage, read> sampled_seeds: array<u32>;

fn seed_at(q: vec2<i32>, first: bool) -> u32 {
    if (first) {
        return sampled_seeds[index_of(q)];
    }
    return textureLoad(seeds_in, q, 0).x;
}

fn flood(p: vec2<i32>, first: bool) {
    if (!in_frame(p)) {
        return;
    }
    let k = i32(jump.x);
    var best = seed_at(p, first);
    var best_d = seed_dist2(best, p);
    for (var j = -1; j <= 1; j++) {
        for (var i = -1; i <= 1; i++) {
            let q = p + vec2<i32>(i, j) * k;
            if (!in_frame(q)) {
                continue;
            }
            let s = seed_at(q, first);
            let d = seed_dist2(s, p);
            if (d < best_d) {
                best = s;
                best_d = d;
            }
        }
    }
    textureStore(seeds_out, p, vec4<u32>(best, 0u, 0u, 0u));
}

@compute @workgroup_size(8, 8)
fn first(@builtin(global_invocation_id) id: vec3<u32>) {
    flood(vec2<i32>(id.xy), true);
}

@compute @workgroup_size(8, 8)
fn main(@builtin(global_invocation_id) id: vec3<u32>) {
    flood(vec2<i32>(id.xy), false);
}
