// Light-space photon pass (seed 000, "photon generation"): the translucent objects rendered from
// the light, orthographically. Each texel is one photon: where the light enters the surface.
// Other materials are not drawn (they neither carry photons nor shadow them).

// Binding 0 is the shared prelude's frame uniform, unused here: the photon map does not depend
// on the camera.
@group(0) @binding(1) var<uniform> photons: Photons;
@group(0) @binding(2) var<storage, read> materials: array<Material>;

struct VertexOut {
    @builtin(position) clip: vec4<f32>,
    @location(0) world: vec3<f32>,
    @location(1) normal: vec3<f32>,
    @location(2) @interpolate(flat) material: u32,
    @location(3) irradiance: vec3<f32>,
}

struct PhotonTexel {
    // xyz: where the photon enters (scene units); w: 1 (coverage).
    @location(0) position: vec4<f32>,
    // xyz: surface normal; w: material id + 1.
    @location(1) normal: vec4<f32>,
    // rgb: radiosity's irradiance where the photon enters.
    @location(2) irradiance: vec4<f32>,
}

@vertex
fn vs_main(v: VertexIn) -> VertexOut {
    var out: VertexOut;
    out.clip = photons.light_view_proj * vec4<f32>(v.position, 1.0);
    out.world = v.position;
    out.normal = v.normal;
    out.material = v.material;
    out.irradiance = v.gi_direct.rgb + v.gi_indirect.rgb * photons.to_light.w;
    return out;
}

@fragment
fn fs_main(in: VertexOut) -> PhotonTexel {
    if (materials[in.material].subsurface == 0u) {
        discard;
    }
    var t: PhotonTexel;
    t.position = vec4<f32>(in.world, 1.0);
    t.normal = vec4<f32>(normalize(in.normal), f32(in.material + 1u));
    t.irradiance = vec4<f32>(in.irradiance, 0.0);
    return t;
}
