// Depth of field from the viewer's pupil (gaze-contingent focus): each pixel averages a disc
// as wide as its blur circle, β ≈ A·|1/d_focus − 1/d| (A pupil diameter, d_focus the depth under
// the gaze). A simple gather over a Vogel spiral; the background is treated as in focus.
// CPU twin: optics::dof::depth_of_field.

@group(0) @binding(1) var<storage, read> src: array<vec4<f32>>;
@group(0) @binding(2) var normal_distance: texture_2d<f32>;
@group(0) @binding(3) var<storage, read_write> out_dof: array<vec4<f32>>;

const TAPS: i32 = 24;
const MAX_RADIUS_PX: f32 = 24.0;
// cos and sin of the golden angle, π(3 − √5) = 2.39996323 rad.
const GOLDEN_COS: f32 = -0.73736888;
const GOLDEN_SIN: f32 = 0.67549029;

fn blur_radius_px(p: vec2<i32>) -> f32 {
    let d = textureLoad(normal_distance, p, 0).w;
    if (d <= 0.0) {
        return 0.0;
    }
    let metres = frame.metres_per_unit;
    let focus = max(focus_distance(normal_distance) * metres, 1e-3);
    let beta = frame.pupil_mm * 1e-3 * abs(1.0 / focus - 1.0 / max(d * metres, 1e-3));
    return min(0.5 * beta / frame.radians_per_pixel, MAX_RADIUS_PX);
}

@compute @workgroup_size(8, 8)
fn main(@builtin(global_invocation_id) id: vec3<u32>) {
    let p = vec2<i32>(id.xy);
    if (!in_frame(p)) {
        return;
    }
    let r = blur_radius_px(p);
    let k = index_of(p);
    if (r < 0.5) {
        out_dof[k] = src[k];
        return;
    }
    var sum = vec3<f32>(0.0);
    // Vogel spiral: even coverage of the disc with any tap count. Tap i turns by the golden
    // angle from tap i − 1, so the direction is rotated by a fixed (cos, sin) each tap instead
    // of a cosine and a sine per tap (on lavapipe 68 → 55 ms a 1280×720 frame).
    var dir = vec2<f32>(1.0, 0.0);
    for (var i = 0; i < TAPS; i++) {
        let t = (f32(i) + 0.5) / f32(TAPS);
        let offset = dir * (sqrt(t) * r);
        let q = clamp(p + vec2<i32>(round(offset)), vec2<i32>(0), frame_size() - 1);
        sum += src[index_of(q)].rgb;
        dir = vec2<f32>(
            dir.x * GOLDEN_COS - dir.y * GOLDEN_SIN,
            dir.x * GOLDEN_SIN + dir.y * GOLDEN_COS,
        );
    }
    out_dof[k] = vec4<f32>(sum / f32(TAPS), 1.0);
}
