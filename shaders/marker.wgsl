// Gaze marker: a magenta ring with a centre dot and a dark outline, drawn over the finished
// frame at the gaze position the server used. Premultiplied alpha, so the scene shows through.

struct Marker {
    // xy: centre in pixels (top-left origin, like @builtin(position)); z: ring radius in
    // pixels; w: ring thickness in pixels.
    centre_radius_thickness: vec4<f32>,
}

@group(0) @binding(0) var<uniform> marker: Marker;

@vertex
fn vs_main(@builtin(vertex_index) i: u32) -> @builtin(position) vec4<f32> {
    // One triangle that covers the whole viewport.
    let uv = vec2<f32>(f32((i << 1u) & 2u), f32(i & 2u));
    return vec4<f32>(uv * 2.0 - 1.0, 0.0, 1.0);
}

// 1 inside `half_width` of the curve, 0 beyond it, with a one-pixel antialiased edge.
fn band(distance_to_curve: f32, half_width: f32) -> f32 {
    return 1.0 - smoothstep(half_width - 0.5, half_width + 0.5, distance_to_curve);
}

@fragment
fn fs_main(@builtin(position) p: vec4<f32>) -> @location(0) vec4<f32> {
    let c = marker.centre_radius_thickness;
    let d = distance(p.xy, c.xy);
    let half_t = 0.5 * c.w;
    let fill = max(band(abs(d - c.z), half_t), band(d, 0.6 * c.w));
    let outline = max(band(abs(d - c.z), half_t + 1.5), band(d, 0.6 * c.w + 1.5));
    // The target holds sRGB-encoded bytes already: this is the encoded colour.
    let magenta = vec3<f32>(1.0, 0.25, 0.8);
    let alpha = max(0.85 * outline, fill);
    return vec4<f32>(magenta * fill, alpha);
}
