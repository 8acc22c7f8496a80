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
}

// One material, as the renderer uploads it (src/render/materials.rs).
struct Material {
    // 0 opaque, 1 translucent, 2 area light (albedo holds its exitance).
    kind: u32,
    // 1 when the scene plan gives this translucent material its subsurface rungs.
    subsurface: u32,
    eta: f32,
    _pad: f32,
    // Opaque albedo, or the dipole's total diffuse reflectance per channel.
    albedo: vec4<f32>,
    // Dipole constants per channel (mm, mm⁻¹): σtr, z_r, z_v, reduced albedo α'.
    sigma_tr: vec4<f32>,
    z_r: vec4<f32>,
    z_v: vec4<f32>,
    alpha: vec4<f32>,
}

// A node of the light-space photon pyramid.
struct PhotonNode {
    // xyz: flux-weighted mean position (scene units); w: extent (radius around it).
    pos_extent: vec4<f32>,
    // rgb: flux (light × mm²); w: scalar weight (luminance of the flux).
    flux: vec4<f32>,
}

// Fresnel transmittance of unpolarised light, exact dielectric form (CPU twin:
// optics::dipole::fresnel_transmittance).
fn fresnel_transmittance(eta: f32, cos_theta: f32) -> f32 {
    let ci = clamp(cos_theta, 0.0, 1.0);
    if (ci <= 0.0) {
        return 0.0;
    }
    let sin2_t = (1.0 - ci * ci) / (eta * eta);
    if (sin2_t >= 1.0) {
        return 0.0;
    }
    let ct = sqrt(1.0 - sin2_t);
    let rs = (ci - eta * ct) / (ci + eta * ct);
    let rp = (eta * ci - ct) / (eta * ci + ct);
    return 1.0 - 0.5 * (rs * rs + rp * rp);
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

fn has_mode(bit: u32) -> bool {
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
