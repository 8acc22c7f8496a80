// G-buffer pass: rasterises every object once at full resolution. Everything later passes need
// to decide, shade, reuse or reconstruct a pixel comes from here.

@group(0) @binding(1) var<storage, read> materials: array<Material>;
// Base colour textures (sRGB, mip-mapped), one layer each, and their trilinear sampler.
@group(0) @binding(2) var material_textures: texture_2d_array<f32>;
@group(0) @binding(3) var material_sampler: sampler;
// Tangent-space normal maps (linear), one layer each.
@group(0) @binding(4) var linear_maps: texture_2d_array<f32>;
// The same filtering with the other wrap modes, per axis (u then v; r repeat, c clamp to edge,
// m mirrored repeat): the sampler does the folding, as a GPU's does it exactly.
@group(0) @binding(5) var sampler_cr: sampler;
@group(0) @binding(6) var sampler_mr: sampler;
@group(0) @binding(7) var sampler_rc: sampler;
@group(0) @binding(8) var sampler_cc: sampler;
@group(0) @binding(9) var sampler_mc: sampler;
@group(0) @binding(10) var sampler_rm: sampler;
@group(0) @binding(11) var sampler_cm: sampler;
@group(0) @binding(12) var sampler_mm: sampler;

// True in the pipeline of a scene with a map that clamps or mirrors. Off, every map repeats and
// the switch below is compiled out: on the software adapter its nine sampling branches cost
// the G-buffer 3-4x even when no pixel takes them.
override WRAP_MODES: bool = false;
// False in the pipeline of a scene where no material has a map of that kind: its read is
// compiled out. The software adapter filters a map for every pixel of a row of 8 whether or
// not its material has one (a branch is a lane mask there, not a jump), so on a scene
// without maps the three reads were 40% of the pass (11 of 27 ms at 1280×720).
override BASE_MAPS: bool = true;
override NORMAL_MAPS: bool = true;
override OCCLUSION_MAPS: bool = true;

// A map read through the sampler its wrap code names (scene::sampling::Sampling::code: u's
// mode in bits 0-1, v's in bits 2-3; 0 repeat, 1 clamp, 2 mirror); white where there is no map
// (layer < 0). Mip levels come from the caller's derivatives, taken before anything branches.
fn sample_map(t: texture_2d_array<f32>, uv: vec2<f32>, layer: f32, code: u32, ddx: vec2<f32>, ddy: vec2<f32>) -> vec4<f32> {
    if (layer < 0.0) {
        return vec4<f32>(1.0);
    }
    let l = i32(layer);
    if (!WRAP_MODES || code == 0u) {
        return textureSampleGrad(t, material_sampler, uv, l, ddx, ddy);
    }
    switch code {
        case 1u: { return textureSampleGrad(t, sampler_cr, uv, l, ddx, ddy); }
        case 2u: { return textureSampleGrad(t, sampler_mr, uv, l, ddx, ddy); }
        case 4u: { return textureSampleGrad(t, sampler_rc, uv, l, ddx, ddy); }
        case 5u: { return textureSampleGrad(t, sampler_cc, uv, l, ddx, ddy); }
        case 6u: { return textureSampleGrad(t, sampler_mc, uv, l, ddx, ddy); }
        case 8u: { return textureSampleGrad(t, sampler_rm, uv, l, ddx, ddy); }
        case 9u: { return textureSampleGrad(t, sampler_cm, uv, l, ddx, ddy); }
        case 10u: { return textureSampleGrad(t, sampler_mm, uv, l, ddx, ddy); }
        default: { return textureSampleGrad(t, material_sampler, uv, l, ddx, ddy); }
    }
}

struct VertexOut {
    @builtin(position) clip: vec4<f32>,
    @location(0) world: vec3<f32>,
    @location(1) normal: vec3<f32>,
    @location(2) blurred_normal: vec3<f32>,
    @location(3) @interpolate(flat) material: u32,
    @location(4) irradiance: vec3<f32>,
    @location(5) tint: vec3<f32>,
    @location(6) uv: vec4<f32>,
    @location(7) tangent: vec4<f32>,
}

struct GBuffer {
    // xyz: unit normal; w: Euclidean distance from the eye (scene units). Cleared to w = -1.
    @location(0) normal_distance: vec4<f32>,
    // rgb: the material's albedo; a: (material id + 1)/255, 0 where nothing covers the pixel.
    @location(1) albedo: vec4<f32>,
    // xyz: the normal blurred over the material's subsurface reach (not renormalised), as
    // n·0.5 + 0.5.
    @location(2) blurred_normal: vec4<f32>,
    // rgb: radiosity's irradiance (zero without radiosity); a: the surface's ambient
    // occlusion (glTF occlusion map, 1 without one).
    @location(3) irradiance: vec4<f32>,
}

@vertex
fn vs_main(v: VertexIn) -> VertexOut {
    var out: VertexOut;
    out.clip = frame.view_proj * vec4<f32>(v.position, 1.0);
    out.world = v.position;
    out.normal = v.normal;
    out.blurred_normal = v.blurred_normal;
    out.material = v.material;
    out.irradiance = v.gi_direct.rgb;
    out.tint = v.tint.rgb;
    out.uv = v.uv;
    out.tangent = v.tangent;
    if (!has_mode(MODE_DIRECT_ONLY)) {
        out.irradiance += v.gi_indirect.rgb;
    }
    return out;
}

// Both faces are rasterised: a one-sided material's back faces are discarded (culling, per
// material), a double-sided one's are shaded with the normal turned towards the viewer.
@fragment
fn fs_main(in: VertexOut, @builtin(front_facing) front: bool) -> GBuffer {
    var g: GBuffer;
    let m = materials[in.material];
    // Sampled before anything branches, so the mip level's derivatives are defined.
    let layer = m.surface.w;
    let dx = dpdx(in.uv);
    let dy = dpdy(in.uv);
    var texel = vec4<f32>(1.0);
    var bump = vec4<f32>(0.5, 0.5, 1.0, 1.0);
    var occluded = 1.0;
    if (BASE_MAPS) {
        texel = sample_map(material_textures, in.uv.xy, layer, m.wrap.x, dx.xy, dy.xy);
    }
    if (NORMAL_MAPS) {
        bump = sample_map(linear_maps, in.uv.zw, m.maps.x, m.wrap.y, dx.zw, dy.zw);
    }
    if (OCCLUSION_MAPS) {
        occluded = sample_map(linear_maps, in.uv.zw, m.maps.z, m.wrap.z, dx.zw, dy.zw).r;
    }
    if (!front && m.double_sided == 0u) {
        discard;
    }
    let len = length(in.normal);
    var n = vec3<f32>(0.0);
    if (len > 1e-20) {
        n = in.normal / len;
    }
    // A normal map tilts the shading normal in the tangent frame (glTF: xy scaled, z kept).
    let tp = in.tangent.xyz - n * dot(n, in.tangent.xyz);
    if (m.maps.x >= 0.0 && length(tp) > 1e-6 && len > 1e-20) {
        let t = normalize(tp);
        let b = cross(n, t) * select(-1.0, 1.0, in.tangent.w >= 0.0);
        let tn = (bump.xyz * 2.0 - 1.0) * vec3<f32>(m.maps.y, m.maps.y, 1.0);
        n = normalize(t * tn.x + b * tn.y + n * tn.z);
    }
    var blurred = in.blurred_normal;
    if (!front) {
        n = -n;
        blurred = -blurred;
    }
    g.normal_distance = vec4<f32>(n, distance(in.world, frame.eye));
    // Opaque surfaces take the vertex tint (textures, vertex colours); the translucent
    // rungs shade with the dipole's own reflectance.
    var albedo = m.albedo.rgb;
    if (m.kind == 0u) {
        albedo *= in.tint;
        if (layer >= 0.0) {
            albedo *= texel.rgb;
        }
    }
    g.albedo = vec4<f32>(albedo, f32(in.material + 1u) / 255.0);
    var ao = 1.0;
    if (m.maps.z >= 0.0) {
        ao = 1.0 + m.maps.w * (occluded - 1.0);
    }
    g.irradiance = vec4<f32>(in.irradiance, ao);
    g.blurred_normal = vec4<f32>(clamp(blurred, vec3<f32>(-1.0), vec3<f32>(1.0)) * 0.5 + 0.5, 0.0);
    return g;
}
