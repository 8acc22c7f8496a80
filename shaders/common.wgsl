// Shared by every pass: the frame's uniforms and small helpers. Prepended to each pass's source
// (see src/render/gpu.rs `compose`).

// The frame's uniforms. Rust twin: FrameUniform in src/render/uniforms.rs (field docs there);
// tests/shaders.rs compares every offset. The MODE_*, FLAG_*, RUNG_*, OVERLAY_*, PROBABILITY_*
// and NO_SEED constants are generated from that file and placed in front of this prelude.
struct Frame {
    view_proj: mat4x4<f32>,
    inv_view_proj: mat4x4<f32>,
    prev_view_proj: mat4x4<f32>,
    eye: vec3<f32>,
    metres_per_unit: f32,
    prev_eye: vec3<f32>,
    has_history: u32,
    to_light: vec3<f32>,
    ambient: f32,
    light: vec3<f32>,
    mm_per_unit: f32,
    background: vec3<f32>,
    overlay: u32,
    width: u32,
    height: u32,
    frame_index: u32,
    mode: u32,
    gaze_px: vec2<f32>,
    pupil_mm: f32,
    focus_distance: f32,
    cm_per_pixel: f32,
    distance_cm: f32,
    w_min_deg: f32,
    w_far_deg: f32,
    mar_slope: f32,
    mar_w0_deg: f32,
    min_probability: f32,
    probability_form: u32,
    max_history_age: u32,
    depth_epsilon: f32,
    radians_per_pixel: f32,
    sibson_window: u32,
    tile_offset: vec2<u32>,
    marker_centre: vec2<f32>,
    marker_radius: f32,
    marker_thickness: f32,
    photon_side: u32,
    photon_radius_mm: f32,
    photon_start_level: u32,
    cut_level: u32,
    cut_epsilon: f32,
    rung: u32,
    pyramid_ready: u32,
    light_count: u32,
    shade_rows: vec2<u32>,
    shadow_view_proj: mat4x4<f32>,
    shadow_params: vec4<f32>,
}

// One material, as the renderer uploads it (src/render/materials.rs).
struct Material {
    // 0 opaque, 1 translucent, 2 area light (albedo holds its exitance).
    kind: u32,
    // 1 when the scene plan gives this translucent material its subsurface rungs.
    subsurface: u32,
    eta: f32,
    // 1 when back faces are shaded (with the normal turned to face the viewer).
    double_sided: u32,
    // Opaque albedo (base colour), or the dipole's total diffuse reflectance per channel.
    albedo: vec4<f32>,
    // Dipole constants per channel (mm, mm⁻¹): σtr, z_r, z_v, reduced albedo α'.
    sigma_tr: vec4<f32>,
    z_r: vec4<f32>,
    z_v: vec4<f32>,
    alpha: vec4<f32>,
    // x: GGX α (clamped ≥ optics::specular::MIN_ALPHA); y: metallic; z: a dielectric's F0;
    // w: the base colour texture's layer in `materials.textures`, −1 for none.
    surface: vec4<f32>,
    // x: the normal map's layer in `materials.linear_maps`, −1 for none; y: its scale;
    // z: the occlusion map's layer (R channel), −1 for none; w: its strength.
    maps: vec4<f32>,
    // Wrap codes of the base colour, normal and occlusion maps: u's mode in bits 0-1, v's in
    // bits 2-3; 0 repeat, 1 clamp to edge, 2 mirrored repeat (CPU twin: scene::sampling).
    wrap: vec4<u32>,
    // The specular lobe's directional albedo split E(μ) = F0·A + F90·B at LOBE_TABLE values
    // of μ: entry i is (A, B) in lobe[i / 2].xy (even i) or .zw (odd i).
    lobe: array<vec4<f32>, 8>,
    // xy: the table's cosine-weighted hemisphere averages of A and B; zw unused.
    lobe_average: vec4<f32>,
}

// A node of the light-space photon pyramid.
struct PhotonNode {
    // xyz: flux-weighted mean position (scene units); w: extent (radius around it).
    pos_extent: vec4<f32>,
    // rgb: flux (light × mm²); w: scalar weight (luminance of the flux).
    flux: vec4<f32>,
    // x: the surface its photons enter through (mm²), which the gathers weigh like the flux to
    // find how much of R_d's reach around a point the photons cover; yzw unused.
    area: vec4<f32>,
}

// ---- Microfacet specular (CPU twin: optics::specular; Karis's UE4 form) ----

// Entry i of the lobe table. Read with constant indices only: indexing a struct value's
// array by a variable makes the shader compiler copy the whole material (288 bytes) to
// per-invocation memory at every call, which cost the software adapter 30% of gallery's
// shading pass.
fn lobe_entry(m: Material, i: u32) -> vec2<f32> {
    let j = i / 2u;
    var q = m.lobe[0];
    q = select(q, m.lobe[1], j == 1u);
    q = select(q, m.lobe[2], j == 2u);
    q = select(q, m.lobe[3], j == 3u);
    q = select(q, m.lobe[4], j == 4u);
    q = select(q, m.lobe[5], j == 5u);
    q = select(q, m.lobe[6], j == 6u);
    q = select(q, m.lobe[7], j == 7u);
    if ((i & 1u) == 0u) {
        return q.xy;
    }
    return q.zw;
}

// Schlick's F90: min(50 F0, 1), so F0 → 0 (η → 1) reflects nothing even at grazing angles.
fn f90_of(f0: vec3<f32>) -> vec3<f32> {
    return min(50.0 * f0, vec3<f32>(1.0));
}

// The specular lobe's directional albedo E(μ) per channel (optics::specular::lobe_albedo).
fn lobe_albedo(m: Material, f0: vec3<f32>, mu: f32) -> vec3<f32> {
    if (has_mode(MODE_NO_SPECULAR)) {
        return vec3<f32>(0.0);
    }
    return lobe_albedo_always(m, f0, mu);
}

// The share of light arriving evenly over the hemisphere that the lobe reflects, so the
// diffuse part receives 1 − this of the sky and of radiosity's irradiance
// (optics::specular::lobe_average).
fn lobe_average(m: Material, f0: vec3<f32>) -> vec3<f32> {
    if (has_mode(MODE_NO_SPECULAR)) {
        return vec3<f32>(0.0);
    }
    let ab = m.lobe_average.xy;
    return clamp(f0 * ab.x + f90_of(f0) * ab.y, vec3<f32>(0.0), vec3<f32>(1.0));
}

// `lobe_albedo` whatever the frame's mode: for passes without the frame uniform (photons).
fn lobe_albedo_always(m: Material, f0: vec3<f32>, mu: f32) -> vec3<f32> {
    let x = clamp(mu, 0.0, 1.0) * f32(LOBE_TABLE - 1u);
    let i = min(u32(floor(x)), LOBE_TABLE - 2u);
    let t = x - f32(i);
    let ab = mix(lobe_entry(m, i), lobe_entry(m, i + 1u), t);
    return clamp(f0 * ab.x + f90_of(f0) * ab.y, vec3<f32>(0.0), vec3<f32>(1.0));
}

// F0 per channel: a dielectric's from its index, a metal's from its (tinted) base colour.
fn specular_f0(m: Material, base: vec3<f32>) -> vec3<f32> {
    return mix(vec3<f32>(m.surface.z), base, m.surface.y);
}

// π D V F (optics::specular::specular without the n·l it multiplies by), per channel.
fn specular_lobe(m: Material, f0: vec3<f32>, n: vec3<f32>, v: vec3<f32>, l: vec3<f32>) -> vec3<f32> {
    let n_l = dot(n, l);
    let n_v = dot(n, v);
    if (n_l <= 0.0 || n_v <= 0.0 || has_mode(MODE_NO_SPECULAR)) {
        return vec3<f32>(0.0);
    }
    let h = normalize(l + v);
    let a = m.surface.x;
    let a2 = a * a;
    let n_h = clamp(dot(n, h), 0.0, 1.0);
    let d0 = n_h * n_h * (a2 - 1.0) + 1.0;
    let d = a2 / (3.14159265 * d0 * d0);
    let cv = clamp(n_v, 1e-4, 1.0);
    let cl = clamp(n_l, 1e-4, 1.0);
    let vis = 0.5 / (cl * sqrt(cv * cv * (1.0 - a2) + a2) + cv * sqrt(cl * cl * (1.0 - a2) + a2));
    let fc = pow(1.0 - clamp(dot(v, h), 0.0, 1.0), 5.0);
    let f = f0 + (f90_of(f0) - f0) * fc;
    return 3.14159265 * d * vis * f;
}

// What a unit light along l sends towards v off a surface with diffuse reflectance `diffuse`
// (optics::specular::surface): the diffuse part scaled by what crosses the interface both
// ways, plus the lobe, times n·l.
fn surface_light(m: Material, f0: vec3<f32>, diffuse: vec3<f32>, n: vec3<f32>, v: vec3<f32>, l: vec3<f32>) -> vec3<f32> {
    let n_l = dot(n, l);
    let n_v = dot(n, v);
    if (n_l <= 0.0 || n_v <= 0.0) {
        return vec3<f32>(0.0);
    }
    let cross = (1.0 - lobe_albedo(m, f0, n_l)) * (1.0 - lobe_albedo(m, f0, n_v));
    return n_l * (diffuse * cross + specular_lobe(m, f0, n, v, l));
}

// The share of light crossing a translucent material's rough interface at incidence cos θ:
// 1 − E(cos θ) (Walter et al. 2007 reduced to the total the dipole needs; 0 below the horizon).
fn transmitted(m: Material, cos_theta: f32) -> f32 {
    if (cos_theta <= 0.0) {
        return 0.0;
    }
    return 1.0 - lobe_albedo(m, vec3<f32>(m.surface.z), cos_theta).x;
}

// `transmitted` for the photon pass, which has no frame (the specular knob does not reach it).
fn transmitted_always(m: Material, cos_theta: f32) -> f32 {
    if (cos_theta <= 0.0) {
        return 0.0;
    }
    return 1.0 - lobe_albedo_always(m, vec3<f32>(m.surface.z), cos_theta).x;
}

// ---- Shadows and lights ----

// The lit share of a 4×4 texel footprint around `uv` (texel units) of a map holding the
// nearest occluder's depth or distance: each texel lit when `z` is not beyond it, weighted by a
// 3×3 tent (bilinear weights), texels clamped into [lo, hi] (a map or an atlas tile).
fn pcf(map: texture_2d<f32>, uv: vec2<f32>, z: f32, lo: vec2<i32>, hi: vec2<i32>) -> f32 {
    let base = floor(uv);
    let f = uv - base;
    var wx = array<f32, 4>(1.0 - f.x, 1.0, 1.0, f.x);
    var wy = array<f32, 4>(1.0 - f.y, 1.0, 1.0, f.y);
    var lit = 0.0;
    for (var j = 0; j < 4; j++) {
        for (var i = 0; i < 4; i++) {
            let t = clamp(vec2<i32>(base) + vec2<i32>(i - 1, j - 1), lo, hi);
            lit += select(0.0, wx[i] * wy[j], z <= textureLoad(map, t, 0).x);
        }
    }
    return lit / 9.0;
}

// How much of the key light reaches world point x with normal n (1 lit … 0 shadowed): the
// shadow map tested at x moved off the surface along n, with a depth bias, over a 3×3 tent
// so edges are soft rather than stair-stepped.
fn shadow_factor(map: texture_2d<f32>, x: vec3<f32>, n: vec3<f32>) -> f32 {
    if (has_mode(MODE_NO_SHADOWS) || frame.shadow_params.z == 0.0) {
        return 1.0;
    }
    let p = frame.shadow_view_proj * vec4<f32>(x + n * frame.shadow_params.y, 1.0);
    let side = frame.shadow_params.w;
    let uv = vec2<f32>(p.x * 0.5 + 0.5, 0.5 - p.y * 0.5) * side - 0.5;
    let last = vec2<i32>(i32(side) - 1);
    return pcf(map, uv, p.z - frame.shadow_params.x, vec2<i32>(0), last);
}

// An extra punctual light (src/render/lights.rs GpuLight).
struct PunctualLight {
    // xyz: position, or the unit vector towards a directional light; w: 0 directional,
    // 1 point, 2 spot.
    position_kind: vec4<f32>,
    // rgb: colour × intensity; w: range (0: none).
    color_range: vec4<f32>,
    // xyz: spot axis (away from the light); w: cos of the outer angle.
    axis_cos_outer: vec4<f32>,
    // x: cos of the inner angle.
    cone: vec4<f32>,
    // x: first tile of the shadow atlas, −1 unshadowed (a spot has one, a point light six, one
    // per cube face in `cube_face` order); y: a texel's size per unit distance; z: tile side;
    // w: tiles per atlas row.
    shadow: vec4<f32>,
}

// The cube face that sees direction d from a point light, in the order +X −X +Y −Y +Z −Z: the
// axis of d's largest component (CPU twin: render::lights::cube_face).
fn cube_face(d: vec3<f32>) -> u32 {
    let a = abs(d);
    if (a.x >= a.y && a.x >= a.z) {
        return select(0u, 1u, d.x < 0.0);
    }
    if (a.y >= a.z) {
        return select(2u, 3u, d.y < 0.0);
    }
    return select(4u, 5u, d.z < 0.0);
}

// How much of a spot or point light reaches x (normal n): its tile of `atlas` (a point light:
// the tile of the cube face towards x) holds distances to the light; the lookup moves one texel
// off the surface and allows 1.5 texels of bias plus 2 × the slope (tan of the light's angle to
// the normal, at most 8), a texel being as wide as the tile's pixels are at x's distance. The
// slope term is what keeps a floor lit at grazing light: across the PCF's ±2 texels its own
// distance to the light changes by about 2 texels × the slope.
fn punctual_shadow(atlas: texture_2d<f32>, views: texture_2d<f32>, li: PunctualLight, x: vec3<f32>, n: vec3<f32>) -> f32 {
    if (has_mode(MODE_NO_SHADOWS)) {
        return 1.0;
    }
    return punctual_shadow_map(atlas, views, li, x, n);
}

// World → clip of shadow tile `tile`: row `tile` of `views` holds its columns
// (render::lights::upload_tile_views).
fn tile_view(views: texture_2d<f32>, tile: u32) -> mat4x4<f32> {
    let t = i32(tile);
    return mat4x4<f32>(
        textureLoad(views, vec2<i32>(0, t), 0),
        textureLoad(views, vec2<i32>(1, t), 0),
        textureLoad(views, vec2<i32>(2, t), 0),
        textureLoad(views, vec2<i32>(3, t), 0),
    );
}

// The light's shadow tiles alone (the photon pass has no frame, and so no mode bits).
fn punctual_shadow_map(atlas: texture_2d<f32>, views: texture_2d<f32>, li: PunctualLight, x: vec3<f32>, n: vec3<f32>) -> f32 {
    if (li.shadow.x < 0.0) {
        return 1.0;
    }
    let pos = li.position_kind.xyz;
    let texel = li.shadow.y * distance(x, pos);
    let xo = x + n * texel;
    let point = u32(li.position_kind.w) == 1u;
    let face = select(0u, cube_face(xo - pos), point);
    let tile = u32(li.shadow.x) + face;
    let p = tile_view(views, tile) * vec4<f32>(xo, 1.0);
    if (p.w <= 0.0) {
        return 1.0;
    }
    var ndc = p.xy / p.w;
    if (point) {
        // The face's edge, reached by rounding: the cube leaves no direction out.
        ndc = clamp(ndc, vec2<f32>(-1.0), vec2<f32>(1.0));
    } else if (any(abs(ndc) > vec2<f32>(1.0))) {
        return 1.0;
    }
    let side = li.shadow.z;
    let columns = max(u32(li.shadow.w), 1u);
    let origin = vec2<f32>(f32(tile % columns), f32(tile / columns)) * side;
    let uv = origin + vec2<f32>(ndc.x * 0.5 + 0.5, 0.5 - ndc.y * 0.5) * side - 0.5;
    let lo = vec2<i32>(origin);
    let cos_l = clamp(dot(n, normalize(pos - x)), 0.0, 1.0);
    let slope = min(sqrt(1.0 - cos_l * cos_l) / max(cos_l, 1e-3), 8.0);
    let z = distance(xo, pos) - (1.5 + 2.0 * slope) * texel;
    return pcf(atlas, uv, z, lo, lo + vec2<i32>(i32(side) - 1));
}

// (unit vector towards the light, irradiance facing it) at x, packed as two vec4s
// (CPU twin: optics::lights::punctual).
fn punctual_light(li: PunctualLight, x: vec3<f32>) -> array<vec3<f32>, 2> {
    let kind = u32(li.position_kind.w);
    if (kind == 0u) {
        return array<vec3<f32>, 2>(normalize(li.position_kind.xyz), li.color_range.rgb);
    }
    let to = li.position_kind.xyz - x;
    let d = max(length(to), 1e-4);
    let l = to / d;
    var falloff = 1.0 / (d * d);
    let range = li.color_range.w;
    if (range > 0.0) {
        let q = clamp(1.0 - pow(d / range, 4.0), 0.0, 1.0);
        falloff *= q * q;
    }
    if (kind == 2u) {
        let co = li.axis_cos_outer.w;
        let t = clamp((dot(-l, li.axis_cos_outer.xyz) - co) / max(li.cone.x - co, 1e-6), 0.0, 1.0);
        falloff *= t * t;
    }
    return array<vec3<f32>, 2>(l, li.color_range.rgb * falloff);
}

// Dipole diffuse reflectance R_d(r) per channel, r in mm (corrected eq. 4; CPU twin:
// optics::dipole::Dipole::rd).
fn dipole_rd(m: Material, r: f32) -> vec3<f32> {
    let r2 = r * r;
    let dr = sqrt(r2 + m.z_r.xyz * m.z_r.xyz);
    let dv = sqrt(r2 + m.z_v.xyz * m.z_v.xyz);
    let real = m.z_r.xyz * (m.sigma_tr.xyz * dr + 1.0) * exp(-m.sigma_tr.xyz * dr) / (dr * dr * dr);
    let virt = m.z_v.xyz * (m.sigma_tr.xyz * dv + 1.0) * exp(-m.sigma_tr.xyz * dv) / (dv * dv * dv);
    return m.alpha.xyz / (4.0 * 3.14159265) * (real + virt);
}



// History age marking "no valid colour here".
const INVALID_AGE: f32 = 65000.0;

@group(0) @binding(0) var<uniform> frame: Frame;

// A pipeline built for one frame mode (`graph::Recorder::dispatch_specialised`) has the mode
// bits as a constant, so the code of every mode it is not in is dropped when it is compiled; one
// that is not reads them from the frame uniforms.
override SPECIALISED_MODE: u32 = NOT_SPECIALISED;

fn has_mode(bit: u32) -> bool {
    if (SPECIALISED_MODE != NOT_SPECIALISED) {
        return (SPECIALISED_MODE & bit) != 0u;
    }
    return (frame.mode & bit) != 0u;
}

fn frame_size() -> vec2<i32> {
    return vec2<i32>(i32(frame.width), i32(frame.height));
}

fn in_frame(p: vec2<i32>) -> bool {
    let s = frame_size();
    return p.x >= 0 && p.y >= 0 && p.x < s.x && p.y < s.y;
}

// Per-pixel buffers are row-major arrays: storage buffers are much cheaper than storage
// textures on software adapters, and no slower on GPUs for these access patterns.
fn index_of(p: vec2<i32>) -> u32 {
    return u32(p.y) * frame.width + u32(p.x);
}

fn pack_seed(p: vec2<i32>) -> u32 {
    return u32(p.x) | (u32(p.y) << 16u);
}

fn unpack_seed(s: u32) -> vec2<i32> {
    return vec2<i32>(i32(s & 0xFFFFu), i32(s >> 16u));
}

// Squared distance to a seed; a huge value (not infinity: integers) without one.
fn seed_dist2(s: u32, p: vec2<i32>) -> i32 {
    if (s == NO_SEED) {
        return 0x7FFFFFFF;
    }
    let d = unpack_seed(s) - p;
    return d.x * d.x + d.y * d.y;
}

// The mesh vertex both raster passes read (src/render/pass/gbuffer.rs VERTEX_LAYOUT).
struct VertexIn {
    @location(0) position: vec3<f32>,
    @location(1) normal: vec3<f32>,
    @location(2) blurred_normal: vec3<f32>,
    @location(3) material: u32,
    // Radiosity's irradiance at this vertex (src/render/pass/gbuffer.rs GI_LAYOUT): direct from
    // area lights, and interreflected (with the preview of energy not yet shot). Zero in
    // scenes without radiosity.
    @location(4) gi_direct: vec4<f32>,
    @location(5) gi_indirect: vec4<f32>,
    // Linear RGBA multiplying the base colour (glTF vertex colours and textures; white
    // elsewhere).
    @location(6) tint: vec4<f32>,
    // Texture coordinates: xy the material's base colour map, zw its normal and occlusion maps.
    @location(7) uv: vec4<f32>,
    // Tangent (xyz) and bitangent sign (w) for the normal map; zero without one.
    @location(8) tangent: vec4<f32>,
}

// The light-space photon pass's uniforms (src/render/pass/photons.rs PhotonUniform).
struct Photons {
    light_view_proj: mat4x4<f32>,
    // xyz: unit vector towards the light; w: 1 when photons carry radiosity's interreflected
    // light as well as its direct light.
    to_light: vec4<f32>,
    // rgb: light colour × intensity.
    light: vec4<f32>,
    // x: map side N; y: area one texel covers perpendicular to the light (mm²);
    // z: texel size (scene units); w: pyramid level being built (reduce entry point).
    params: vec4<f32>,
    // The key light's shadow map (world → map) and (depth bias, normal offset, 1 when photons
    // are tested against it, side).
    shadow_view_proj: mat4x4<f32>,
    shadow_params: vec4<f32>,
    // x: extra punctual lights whose light the photons carry (the scene's, at most 8).
    extra: vec4<u32>,
}

// Depth under the gaze, from the G-buffer's normal + distance: what the eye focuses on. Off the
// object, the camera's target distance.
fn focus_distance(normal_distance: texture_2d<f32>) -> f32 {
    let g = clamp(vec2<i32>(floor(frame.gaze_px)), vec2<i32>(0), frame_size() - 1);
    let d = textureLoad(normal_distance, g, 0).w;
    if (d > 0.0) {
        return d;
    }
    return frame.focus_distance;
}

// Material id stored in the G-buffer albedo alpha ((id + 1)/255; 0 = background).
fn material_id(albedo_alpha: f32) -> u32 {
    return u32(round(albedo_alpha * 255.0)) - 1u;
}

// Direct lighting of a Lambertian surface; CPU twin: optics::shading::lambert.
fn lambert(normal: vec3<f32>, albedo: vec3<f32>) -> vec3<f32> {
    let len = length(normal);
    var n = vec3<f32>(0.0);
    if (len > 1e-20) {
        n = normal / len;
    }
    let cos_theta = max(dot(n, frame.to_light), 0.0);
    return albedo * frame.light * (cos_theta + frame.ambient);
}

// Unit direction of the camera ray through pixel centre p.
fn view_ray(p: vec2<f32>) -> vec3<f32> {
    let s = vec2<f32>(frame_size());
    let ndc = vec2<f32>(p.x / s.x * 2.0 - 1.0, 1.0 - p.y / s.y * 2.0);
    let far = frame.inv_view_proj * vec4<f32>(ndc, 1.0, 1.0);
    return normalize(far.xyz / far.w - frame.eye);
}
