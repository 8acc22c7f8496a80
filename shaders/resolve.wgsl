// Resolve pass (foveated frames only): every pixel gets a colour. Background from the G-buffer coverage; shaded and
// reused pixels keep theirs; the rest take their nearest sample's colour (Voronoi) or the
// windowed approximate Sibson average (thesis Listing 4 in gather form: every covered q in the
// window whose empty circle |q − s(q)| reaches p contributes s(q)'s colour). The window is the
// ξ bound shrunk to twice the distance to p's nearest sample. CPU twin:
// foveation::reconstruct::reconstruct.

@group(0) @binding(1) var<storage, read> color: array<vec4<f32>>;
@group(0) @binding(2) var nearest: texture_2d<u32>;
@group(0) @binding(3) var albedo_tex: texture_2d<f32>;
@group(0) @binding(4) var<storage, read_write> out_resolved: array<vec4<f32>>;
@group(0) @binding(5) var normal_distance: texture_2d<f32>;
@group(0) @binding(6) var<storage, read> flags: array<u32>;

fn covered(p: vec2<i32>) -> bool {
    return (flags[index_of(p)] & FLAG_COVERED) != 0u;
}

fn seed_color(s: u32) -> vec3<f32> {
    return color[index_of(unpack_seed(s))].rgb;
}

@compute @workgroup_size(8, 8)
fn main(@builtin(global_invocation_id) id: vec3<u32>) {
    let p = vec2<i32>(id.xy);
    if (!in_frame(p)) {
        return;
    }
    let k = index_of(p);
    if (!covered(p)) {
        out_resolved[k] = vec4<f32>(frame.background, 1.0);
        return;
    }
    let s = textureLoad(nearest, p, 0).x;
    if (s == NO_SEED) {
        // No sample within jump-flooding reach (a sliver of the object far from every sample):
        // shade the pixel itself. Rare by construction of the reach, so cheap.
        // (The cheap rung: the albedo is the material's, or its dipole's total reflectance.)
        let a = textureLoad(albedo_tex, p, 0).rgb;
        out_resolved[k] = vec4<f32>(lambert(textureLoad(normal_distance, p, 0).xyz, a), 1.0);
        return;
    }
    let d2 = seed_dist2(s, p);
    if (d2 == 0 || !has_mode(MODE_SIBSON)) {
        out_resolved[k] = vec4<f32>(seed_color(s), 1.0);
        return;
    }
    let j = clamp(i32(ceil(2.0 * sqrt(f32(d2)))), 1, max(i32(frame.sibson_window), 1));
    let lo = max(p - vec2<i32>(j), vec2<i32>(0));
    let hi = min(p + vec2<i32>(j), frame_size() - 1);
    var sum = vec3<f32>(0.0);
    var count = 0.0;
    for (var qy = lo.y; qy <= hi.y; qy++) {
        for (var qx = lo.x; qx <= hi.x; qx++) {
            let q = vec2<i32>(qx, qy);
            if (!covered(q)) {
                continue;
            }
            let sq = textureLoad(nearest, q, 0).x;
            if (sq == NO_SEED) {
                continue;
            }
            let dq = q - p;
            if (dq.x * dq.x + dq.y * dq.y > seed_dist2(sq, q)) {
                continue;
            }
            sum += seed_color(sq);
            count += 1.0;
        }
    }
    var rgb = seed_color(s);
    if (count > 0.0) {
        rgb = sum / count;
    }
    out_resolved[k] = vec4<f32>(rgb, 1.0);
}
