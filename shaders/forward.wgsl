// Forward pass: the mesh, lit by one directional light plus a constant ambient term.
// CPU twin: src/optics/shading.rs `lambert`. Output is linear; the sRGB target encodes it.

struct Frame {
    view_proj: mat4x4<f32>,
    // xyz: unit vector from the surface towards the light.
    to_light: vec4<f32>,
    // rgb: light colour × intensity.
    light: vec4<f32>,
    // rgb: diffuse albedo; w: ambient as a fraction of the light.
    albedo_ambient: vec4<f32>,
}

@group(0) @binding(0) var<uniform> frame: Frame;

struct VertexIn {
    @location(0) position: vec3<f32>,
    @location(1) normal: vec3<f32>,
}

struct VertexOut {
    @builtin(position) clip: vec4<f32>,
    @location(0) normal: vec3<f32>,
}

@vertex
fn vs_main(v: VertexIn) -> VertexOut {
    var out: VertexOut;
    out.clip = frame.view_proj * vec4<f32>(v.position, 1.0);
    out.normal = v.normal;
    return out;
}

@fragment
fn fs_main(in: VertexOut) -> @location(0) vec4<f32> {
    // Interpolated normals shrink between vertices; a zero one (degenerate) gets ambient only.
    let len = length(in.normal);
    var n = vec3<f32>(0.0);
    if (len > 1e-20) {
        n = in.normal / len;
    }
    let cos_theta = max(dot(n, frame.to_light.xyz), 0.0);
    let rgb = frame.albedo_ambient.rgb * frame.light.rgb * (cos_theta + frame.albedo_ambient.w);
    return vec4<f32>(rgb, 1.0);
}
