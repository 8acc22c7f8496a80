// Light-space photon pass (seed 000, "photon generation"): the translucent objects rendered from
// the light, orthographically. Each texel is one photon: where the light enters the surface.
// Other materials are not drawn (they neither carry photons nor shadow them).

// Binding 0 is the shared prelude's frame uniform, unused here: the photon map does not depend
// on the camera.
@group(0) @binding(1) var<uniform> photons: Photons;
@group(0) @binding(2) var<storage, read> materials: array<Material>;
@group(0) @binding(3) var<storage, read> lights: array<PunctualLight>;
@group(0) @binding(4) var light_shadows: texture_2d<f32>;
@group(0) @binding(5) var tile_views: texture_2d<f32>;

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
    // rgb: radiosity's and the extra lights' irradiance where the photon enters, as the
    // pyramid's leaves take it: arriving at 60° (see `extra_light`).
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

// The extra punctual lights' light entering at x, written as the irradiance that, entering at
// 60° as the leaves take radiosity's, carries the same flux: E cos θ F_t(cos θ) / F_t(½).
// A photon stands for the surface the key light sees; what the extra lights give the rest of
// the body enters there locally (the shade pass weighs it by what the photons do not cover).
fn extra_light(m: Material, x: vec3<f32>, n: vec3<f32>) -> vec3<f32> {
    var sum = vec3<f32>(0.0);
    let shadowed = photons.shadow_params.z != 0.0;
    for (var i = 0u; i < photons.extra.x; i++) {
        let li = lights[i];
        let le = punctual_light(li, x);
        let cos_l = dot(n, le[0]);
        if (cos_l > 0.0 && any(le[1] > vec3<f32>(0.0))) {
            var seen = 1.0;
            if (shadowed) {
                seen = punctual_shadow_map(light_shadows, tile_views, li, x, n);
            }
            sum += le[1] * seen * cos_l * transmitted_always(m, cos_l);
        }
    }
    return sum / max(transmitted_always(m, 0.5), 1e-6);
}

@fragment
fn fs_main(in: VertexOut) -> PhotonTexel {
    let m = materials[in.material];
    if (m.subsurface == 0u) {
        discard;
    }
    let n = normalize(in.normal);
    var t: PhotonTexel;
    t.position = vec4<f32>(in.world, 1.0);
    t.normal = vec4<f32>(n, f32(in.material + 1u));
    t.irradiance = vec4<f32>(in.irradiance + extra_light(m, in.world, n), 0.0);
    return t;
}
