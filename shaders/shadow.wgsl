// Shadow pass: every object rendered from the key light (orthographically) or a spot light
// (in perspective, into its tile of the spot atlas), keeping the nearest surface per texel. Both faces are drawn so open and thin meshes cast shadows too.
// The shading passes compare a point's own light-space depth against it (`shadow_factor` in
// the prelude).

// Binding 0 is the shared prelude's frame uniform, unused here: the map does not depend on
// the camera.
@group(0) @binding(1) var<uniform> shadow: ShadowUniform;

struct ShadowUniform {
    light_view_proj: mat4x4<f32>,
    // xyz: the light's position; w: 1 to store the distance to it (spot lights, perspective),
    // 0 to store depth (the key light, orthographic).
    light_pos: vec4<f32>,
}

struct VertexOut {
    @builtin(position) clip: vec4<f32>,
    @location(0) world: vec3<f32>,
}

@vertex
fn vs_main(v: VertexIn) -> VertexOut {
    var out: VertexOut;
    out.clip = shadow.light_view_proj * vec4<f32>(v.position, 1.0);
    out.world = v.position;
    return out;
}

@fragment
fn fs_main(in: VertexOut) -> @location(0) vec4<f32> {
    // In a fragment, the position's z is the depth the rasteriser tests (0 near … 1 far);
    // perspective depth is too uneven to bias, so spot maps keep the distance instead.
    if (shadow.light_pos.w > 0.5) {
        return vec4<f32>(distance(in.world, shadow.light_pos.xyz), 0.0, 0.0, 0.0);
    }
    return vec4<f32>(in.clip.z, 0.0, 0.0, 0.0);
}
