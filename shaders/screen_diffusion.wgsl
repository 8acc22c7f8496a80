// Screen-space diffusion (the middle translucency rung): irradiance at every covered pixel,
// blurred horizontally then vertically with the dipole profile R_d(r) as the kernel, r the
// distance on the surface in millimetres (pixel offset × the pixel's footprint at its depth).
// Taps on other materials or at depths beyond the profile's reach are skipped. Separable, so
// approximate; it cannot carry light through thin parts (nothing is lit behind the surface).

@group(0) @binding(1) var normal_distance: texture_2d<f32>;
@group(0) @binding(2) var albedo_tex: texture_2d<f32>;
@group(0) @binding(3) var<storage, read> materials: array<Material>;
// x: reach of each material's profile, mm (indexed by material id).
@group(0) @binding(4) var<storage, read> reach_mm: array<vec4<f32>>;
@group(0) @binding(5) var<storage, read> src: array<vec4<f32>>;
@group(0) @binding(6) var<storage, read_write> dst: array<vec4<f32>>;
@group(0) @binding(7) var shadow_tex: texture_2d<f32>;

const MAX_TAPS: i32 = 16;

@compute @workgroup_size(8, 8)
fn irradiance(@builtin(global_invocation_id) id: vec3<u32>) {
    let p = vec2<i32>(id.xy);
    if (!in_frame(p)) {
        return;
    }
    let a = textureLoad(albedo_tex, p, 0);
    var e = vec3<f32>(0.0);
    if (a.a > 0.0) {
        let m = materials[material_id(a.a)];
        let nd = textureLoad(normal_distance, p, 0);
        let cos_i = dot(nd.xyz, frame.to_light);
        let x = frame.eye + view_ray(vec2<f32>(p) + 0.5) * nd.w;
        e = frame.light * shadow_factor(shadow_tex, x, nd.xyz) * max(cos_i, 0.0) * transmitted(m, cos_i);
    }
    dst[index_of(p)] = vec4<f32>(e, 1.0);
}

fn blur(p: vec2<i32>, axis: vec2<i32>) {
    let k = index_of(p);
    let a = textureLoad(albedo_tex, p, 0);
    if (a.a <= 0.0) {
        dst[k] = src[k];
        return;
    }
    let id = material_id(a.a);
    let m = materials[id];
    let d = textureLoad(normal_distance, p, 0).w;
    // Millimetres one pixel spans on the surface at this depth.
    let footprint = d * frame.radians_per_pixel * frame.mm_per_unit;
    let reach = reach_mm[id].x;
    let radius_px = min(reach / max(footprint, 1e-6), f32(MAX_TAPS) * 4.0);
    let step = max(1, i32(ceil(radius_px / f32(MAX_TAPS))));
    let taps = min(i32(ceil(radius_px)) / step, MAX_TAPS);
    var sum = vec3<f32>(0.0);
    var weight = vec3<f32>(0.0);
    for (var t = -taps; t <= taps; t++) {
        let q = p + axis * (t * step);
        if (!in_frame(q)) {
            continue;
        }
        let qa = textureLoad(albedo_tex, q, 0);
        if (qa.a <= 0.0 || material_id(qa.a) != id) {
            continue;
        }
        let dq = textureLoad(normal_distance, q, 0).w;
        let r = length(vec2<f32>(f32(t * step) * footprint, (dq - d) * frame.mm_per_unit));
        if (r > reach) {
            continue;
        }
        let w = dipole_rd(m, r);
        sum += w * src[index_of(q)].rgb;
        weight += w;
    }
    dst[k] = vec4<f32>(sum / max(weight, vec3<f32>(1e-20)), 1.0);
}

@compute @workgroup_size(8, 8)
fn blur_horizontal(@builtin(global_invocation_id) id: vec3<u32>) {
    let p = vec2<i32>(id.xy);
    if (in_frame(p)) {
        blur(p, vec2<i32>(1, 0));
    }
}

@compute @workgroup_size(8, 8)
fn blur_vertical(@builtin(global_invocation_id) id: vec3<u32>) {
    let p = vec2<i32>(id.xy);
    if (in_frame(p)) {
        blur(p, vec2<i32>(0, 1));
    }
}
