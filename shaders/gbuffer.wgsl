// G-buffer pass: rasterises the mesh once at full resolution. Everything later passes need to
// decide, shade, reuse or reconstruct a pixel comes from here.

struct VertexIn {
    @location(0) position: vec3<f32>,
    @location(1) normal: vec3<f32>,
}

struct VertexOut {
    @builtin(position) clip: vec4<f32>,
    @location(0) world: vec3<f32>,
    @location(1) normal: vec3<f32>,
}

struct GBuffer {
    // xyz: unit normal; w: Euclidean distance from the eye (scene units). Cleared to w = -1.
    @location(0) normal_distance: vec4<f32>,
    // rgb: albedo; a: 1 where the mesh covers the pixel (cleared to 0).
    @location(1) albedo: vec4<f32>,
    // Where this surface point was on screen last frame, in pixels (motion vector = this − p).
    @location(2) previous: vec2<f32>,
}

@vertex
fn vs_main(v: VertexIn) -> VertexOut {
    var out: VertexOut;
    out.clip = frame.view_proj * vec4<f32>(v.position, 1.0);
    out.world = v.position;
    out.normal = v.normal;
    return out;
}

@fragment
fn fs_main(in: VertexOut) -> GBuffer {
    var g: GBuffer;
    let len = length(in.normal);
    var n = vec3<f32>(0.0);
    if (len > 1e-20) {
        n = in.normal / len;
    }
    g.normal_distance = vec4<f32>(n, distance(in.world, frame.eye.xyz));
    g.albedo = vec4<f32>(frame.albedo_ambient.rgb, 1.0);
    let prev = frame.prev_view_proj * vec4<f32>(in.world, 1.0);
    let s = vec2<f32>(frame_size());
    if (prev.w > 1e-6) {
        let ndc = prev.xy / prev.w;
        g.previous = vec2<f32>((ndc.x * 0.5 + 0.5) * s.x, (0.5 - ndc.y * 0.5) * s.y);
    } else {
        g.previous = vec2<f32>(-1e9, -1e9);
    }
    return g;
}
