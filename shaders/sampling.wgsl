// Sampling pass (thesis eqs. 2–4): per pixel, the probability the eye needs it shaded, the
// blue-noise decision, and for pixels not chosen, whether last frame's colour can be reused.
// CPU twins: optics::acuity (probability, DoF), foveation::reprojection (cache test).

@group(0) @binding(1) var normal_distance: texture_2d<f32>;
@group(0) @binding(2) var albedo_tex: texture_2d<f32>;
@group(0) @binding(3) var rank_map: texture_2d<f32>;
@group(0) @binding(4) var<storage, read> history_color: array<vec4<f32>>;
@group(0) @binding(5) var history_normal_distance: texture_2d<f32>;
@group(0) @binding(6) var<storage, read_write> out_probability: array<f32>;
@group(0) @binding(7) var<storage, read_write> out_flags: array<u32>;
@group(0) @binding(8) var<storage, read_write> out_color: array<vec4<f32>>;
@group(0) @binding(9) var<storage, read_write> out_seeds: array<u32>;
// Each pixel's saliency, kept for the frames after this one while the G-buffer stays the same.
@group(0) @binding(10) var<storage, read_write> saliency_cache: array<f32>;

fn screen_point(p: vec2<f32>) -> vec3<f32> {
    let s = vec2<f32>(frame_size());
    return vec3<f32>((p - 0.5 * s) * frame.cm_per_pixel, frame.distance_cm);
}

// Degrees between the gaze and pixel centre p, seen from the eye; atan2 form, exact near 0.
fn eccentricity_deg(p: vec2<f32>) -> f32 {
    let a = screen_point(frame.gaze_px);
    let b = screen_point(p);
    return degrees(atan2(length(cross(a, b)), dot(a, b)));
}

fn acuity_probability(w: f32) -> f32 {
    let w_min = frame.w_min_deg;
    let w_far = frame.w_far_deg;
    var p = 1.0;
    if (frame.probability_form == PROBABILITY_LINEAR) {
        let span = w_far - w_min;
        if (span > 1e-12) {
            p = 1.0 - (w - w_min) / span;
        }
    } else if (w > 1e-12) {
        p = (w_min / w) * (w_min / w);
    }
    return clamp(p, 0.0, 1.0);
}

// CIE-Lab (D65) of a linear sRGB colour: saliency is measured where colour differences are
// perceptually even, as the thesis does.
fn lab_f(t: f32) -> f32 {
    if (t > 0.008856) {
        return pow(t, 1.0 / 3.0);
    }
    return 7.787 * t + 16.0 / 116.0;
}

fn to_lab(rgb: vec3<f32>) -> vec3<f32> {
    let x = dot(rgb, vec3<f32>(0.4124, 0.3576, 0.1805)) / 0.95047;
    let y = dot(rgb, vec3<f32>(0.2126, 0.7152, 0.0722));
    let z = dot(rgb, vec3<f32>(0.0193, 0.1192, 0.9505)) / 1.08883;
    let fx = lab_f(x);
    let fy = lab_f(y);
    let fz = lab_f(z);
    return vec3<f32>(116.0 * fy - 16.0, 500.0 * (fx - fy), 200.0 * (fy - fz));
}

fn load_clamped(t: texture_2d<f32>, p: vec2<i32>) -> vec4<f32> {
    return textureLoad(t, clamp(p, vec2<i32>(0), frame_size() - 1), 0);
}

// A Sobel tap of the albedo. Background (alpha 0) counts as black; the alpha holds the
// material id, not coverage.
fn tap_albedo(q: vec2<i32>) -> vec4<f32> {
    let a = load_clamped(albedo_tex, q);
    return vec4<f32>(a.rgb * select(0.0, 1.0, a.a > 0.0), a.a);
}

// Sobel weights at column i, row j (0..2) of a 3×3 window.
fn sobel_x(i: i32, j: i32) -> f32 {
    return f32((i - 1) * (2 - abs(j - 1)));
}

fn sobel_y(i: i32, j: i32) -> f32 {
    return f32((j - 1) * (2 - abs(i - 1)));
}

// One pixel's Sobel sums and albedo flatness while its 3×3 window is read.
struct Edges {
    gx_n: vec3<f32>,
    gy_n: vec3<f32>,
    gx_lab: vec3<f32>,
    gy_lab: vec3<f32>,
    first: vec4<f32>,
    flat_albedo: bool,
    one_material: bool,
}

fn edges() -> Edges {
    return Edges(vec3<f32>(0.0), vec3<f32>(0.0), vec3<f32>(0.0), vec3<f32>(0.0), vec4<f32>(0.0), true, true);
}

// The texel at (i, j) of the pixel's window (outside 0..2: not in it).
fn edges_tap(e: ptr<function, Edges>, n: vec3<f32>, a: vec4<f32>, i: i32, j: i32) {
    if (i < 0 || i > 2 || j < 0 || j > 2) {
        return;
    }
    (*e).gx_n += sobel_x(i, j) * n;
    (*e).gy_n += sobel_y(i, j) * n;
    if (i == 0 && j == 0) {
        (*e).first = a;
    } else if (any(a != (*e).first)) {
        (*e).flat_albedo = false;
        (*e).one_material = (*e).one_material && a.a == (*e).first.a;
    }
}

fn edges_lab(e: ptr<function, Edges>, lab: vec3<f32>, i: i32, j: i32) {
    if (i < 0 || i > 2 || j < 0 || j > 2) {
        return;
    }
    (*e).gx_lab += sobel_x(i, j) * lab;
    (*e).gy_lab += sobel_y(i, j) * lab;
}

// Largest per-pixel Sobel gradient of albedo (ΔE per pixel, /10) and normal (radians per
// pixel, /0.25), each normalised to [0, 1]. Background counts as black with a zero normal, so
// silhouettes are salient. CPU twin: optics::saliency::saliency.
fn edges_saliency(e: Edges) -> f32 {
    var d_albedo = 0.0;
    // A demodulated reconstruction restores albedo edges within a material from the G-buffer,
    // so only a change of material (alpha: material id), where the ratio to the G-buffer's
    // prediction jumps (an emitter beside a wall), is an edge.
    if (has_mode(MODE_DEMODULATED)) {
        d_albedo = select(1.0, 0.0, e.one_material);
    } else if (!e.flat_albedo) {
        let d_lab = sqrt(e.gx_lab * e.gx_lab + e.gy_lab * e.gy_lab) / 8.0;
        // Normalisers: optics::saliency::{ALBEDO_FULL, NORMAL_FULL}.
        d_albedo = max(d_lab.x, max(d_lab.y, d_lab.z)) / 10.0;
    }
    // Sobel weights sum to 8 across the kernel: /8 gives a per-pixel derivative.
    let d_n = sqrt(e.gx_n * e.gx_n + e.gy_n * e.gy_n) / 8.0;
    let d_normal = max(d_n.x, max(d_n.y, d_n.z)) / 0.25;
    return clamp(max(d_albedo, d_normal), 0.0, 1.0);
}

// Saliency of the 2×2 pixels at `base` + (0|1, 0|1), in x, y, z, w order (0,0), (1,0), (0,1),
// (1,1): the four 3×3 windows share one 4×4 window, so each G-buffer texel is read once for
// all four (8 reads a pixel instead of 18; Lab's cube roots 4 a pixel instead of 9). Each
// pixel's sums take its taps in the order a per-pixel loop would. The taps read the G-buffer
// directly: a workgroup tile shared through a barrier measured 25% slower on the software
// adapter (a barrier splits the shader into resumable pieces there).
fn saliency_quad(base: vec2<i32>) -> vec4<f32> {
    var e00 = edges();
    var e10 = edges();
    var e01 = edges();
    var e11 = edges();
    for (var r = 0; r < 4; r++) {
        for (var c = 0; c < 4; c++) {
            let q = base + vec2<i32>(c - 1, r - 1);
            let n = load_clamped(normal_distance, q).xyz;
            let a = tap_albedo(q);
            edges_tap(&e00, n, a, c, r);
            edges_tap(&e10, n, a, c - 1, r);
            edges_tap(&e01, n, a, c, r - 1);
            edges_tap(&e11, n, a, c - 1, r - 1);
        }
    }
    // Lab needs cube roots per tap: only worth it where the albedo actually changes.
    let flat = e00.flat_albedo && e10.flat_albedo && e01.flat_albedo && e11.flat_albedo;
    if (!has_mode(MODE_DEMODULATED) && !flat) {
        for (var r = 0; r < 4; r++) {
            for (var c = 0; c < 4; c++) {
                let lab = to_lab(tap_albedo(base + vec2<i32>(c - 1, r - 1)).rgb);
                edges_lab(&e00, lab, c, r);
                edges_lab(&e10, lab, c - 1, r);
                edges_lab(&e01, lab, c, r - 1);
                edges_lab(&e11, lab, c - 1, r - 1);
            }
        }
    }
    return vec4<f32>(edges_saliency(e00), edges_saliency(e10), edges_saliency(e01), edges_saliency(e11));
}

// The four pixels of the quad at `base` in x, y, z, w order; a pixel past the frame has none.
fn quad_pixel(base: vec2<i32>, i: i32) -> vec2<i32> {
    return base + vec2<i32>(i & 1, i >> 1u);
}

fn store_saliency(base: vec2<i32>, s: vec4<f32>) {
    for (var i = 0; i < 4; i++) {
        let p = quad_pixel(base, i);
        if (in_frame(p)) {
            saliency_cache[index_of(p)] = s[i];
        }
    }
}

fn cached_saliency(base: vec2<i32>) -> vec4<f32> {
    var s = vec4<f32>(0.0);
    for (var i = 0; i < 4; i++) {
        let p = quad_pixel(base, i);
        if (in_frame(p)) {
            s[i] = saliency_cache[index_of(p)];
        }
    }
    return s;
}

fn white_noise(p: vec2<u32>) -> f32 {
    var h = p.x * 0x8da6b343u ^ p.y * 0xd8163841u ^ frame.frame_index * 0xcb1ab31fu;
    h = (h ^ (h >> 16u)) * 0x7feb352du;
    h = (h ^ (h >> 15u)) * 0x846ca68bu;
    h = h ^ (h >> 16u);
    return f32(h >> 8u) / 16777216.0;
}

// The acuity term of eq. 3 at pixel p: the probability before saliency, motion and DoF.
fn acuity_at(p: vec2<i32>) -> f32 {
    let e = eccentricity_deg(vec2<f32>(p) + 0.5);
    return acuity_probability(frame.mar_slope * e + frame.mar_w0_deg);
}

// One invocation decides a 2×2 block of pixels, so their saliency shares its G-buffer reads.
@compute @workgroup_size(8, 8)
fn main(@builtin(global_invocation_id) id: vec3<u32>) {
    let base = vec2<i32>(id.xy) * 2;
    if (!in_frame(base)) {
        return;
    }
    let f = vec4<f32>(
        acuity_at(base),
        acuity_at(base + vec2<i32>(1, 0)),
        acuity_at(base + vec2<i32>(0, 1)),
        acuity_at(base + vec2<i32>(1, 1)),
    );
    var s = vec4<f32>(0.0);
    if (has_mode(MODE_SALIENCY_CACHED)) {
        s = cached_saliency(base);
    } else if (has_mode(MODE_SALIENCY)) {
        // Every quad, the fovea's too (where acuity alone asks for every pixel): a later frame
        // may read it with the gaze elsewhere.
        s = saliency_quad(base);
        store_saliency(base, s);
    }
    decide(base, f.x, s.x);
    decide(base + vec2<i32>(1, 0), f.y, s.y);
    decide(base + vec2<i32>(0, 1), f.z, s.z);
    decide(base + vec2<i32>(1, 1), f.w, s.w);
}

// Where the surface point seen through pixel centre `centre` at distance `d` was on screen last
// frame (off screen when it was behind last frame's eye).
fn reprojected(centre: vec2<f32>, d: f32) -> vec2<f32> {
    let world = frame.eye + view_ray(centre) * d;
    let prev_clip = frame.prev_view_proj * vec4<f32>(world, 1.0);
    if (prev_clip.w <= 1e-6) {
        return vec2<f32>(-1e9);
    }
    let ndc = prev_clip.xy / prev_clip.w;
    return vec2<f32>((ndc.x * 0.5 + 0.5) * f32(frame.width), (0.5 - ndc.y * 0.5) * f32(frame.height));
}

// Eq. 4 with |x| and a relative tolerance: is last frame's surface at `prev` the one seen
// through pixel p at distance d now? The stored depth is last frame's Euclidean distance from
// last frame's eye. CPU twin: foveation::reprojection::cache_hit.
fn history_hit(p: vec2<i32>, prev: vec2<f32>, d: f32) -> bool {
    let uv = prev / vec2<f32>(frame_size());
    if (any(uv < vec2<f32>(0.0)) || any(uv >= vec2<f32>(1.0))) {
        return false;
    }
    let prev_distance = textureLoad(history_normal_distance, vec2<i32>(floor(prev)), 0).w;
    let world = frame.eye + view_ray(vec2<f32>(p) + 0.5) * d;
    let now = distance(world, frame.prev_eye);
    return abs(prev_distance - now) < frame.depth_epsilon * max(now, 1e-6);
}

// Pixel p's probability (from its acuity term `acuity` and saliency `salient`), sample
// decision and reprojection.
fn decide(p: vec2<i32>, acuity: f32, salient: f32) {
    if (!in_frame(p)) {
        return;
    }
    let id = vec2<u32>(p);
    let nd = textureLoad(normal_distance, p, 0);
    let covered = textureLoad(albedo_tex, p, 0).a > 0.0;
    let k = index_of(p);
    if (!covered) {
        out_probability[k] = 0.0;
        out_flags[k] = 0u;
        out_color[k] = vec4<f32>(frame.background, INVALID_AGE);
        out_seeds[k] = NO_SEED;
        return;
    }
    let centre = vec2<f32>(p) + 0.5;
    // Where this surface point was on screen last frame (static geometry: only the camera
    // moves, so with a still camera it was here).
    var prev = centre;
    if (!has_mode(MODE_STILL_CAMERA)) {
        prev = reprojected(centre, nd.w);
    }
    var f = acuity;
    if (has_mode(MODE_SALIENCY) && f < 1.0) {
        var s = salient;
        if (has_mode(MODE_EDGES_AT_MAR)) {
            // One sample per pixel across an edge, one per resolvable cell along it, for the
            // acuity of the nearest point the eye may be looking at (the gaze is known only to
            // within EDGE_MARGIN_DEG). CPU twin: optics::acuity::edge_eccentricity_deg.
            let e = max(eccentricity_deg(centre) - f32(EDGE_MARGIN_DEG), 0.0);
            s *= sqrt(acuity_probability(frame.mar_slope * e + frame.mar_w0_deg));
        }
        f = max(f, s);
    }
    if (has_mode(MODE_MOTION)) {
        let moved = length(prev - centre);
        f = max(f, clamp(moved / 8.0, 0.0, 1.0));
    }
    if (has_mode(MODE_DOF)) {
        // β ≈ A·|1/d_focus − 1/d|; a blur b pixels wide needs a sample every b pixels.
        let metres = frame.metres_per_unit;
        let focus = max(focus_distance(normal_distance) * metres, 1e-3);
        let d = max(nd.w * metres, 1e-3);
        let blur_px = frame.pupil_mm * 1e-3 * abs(1.0 / focus - 1.0 / d) / frame.radians_per_pixel;
        if (blur_px > 1.0) {
            f = f / (blur_px * blur_px);
        }
    }
    f = clamp(f, frame.min_probability, 1.0);

    var threshold: f32;
    if (has_mode(MODE_WHITE_NOISE)) {
        threshold = white_noise(vec2<u32>(id.xy));
    } else {
        let t = (vec2<u32>(id.xy) + frame.tile_offset) % vec2<u32>(64u);
        threshold = textureLoad(rank_map, vec2<i32>(t), 0).r;
    }
    let sampled = threshold < f;
    var flags = FLAG_COVERED;
    var seed = NO_SEED;
    var color = vec4<f32>(0.0, 0.0, 0.0, INVALID_AGE);
    if (sampled) {
        flags |= FLAG_SAMPLED;
        seed = pack_seed(p);
    } else if (has_mode(MODE_REPROJECTION) && frame.has_history != 0u) {
        // A miss keeps INVALID_AGE, above any age cap (the knob stops at 1000).
        var old = vec4<f32>(0.0, 0.0, 0.0, INVALID_AGE);
        if (has_mode(MODE_STILL_CAMERA)) {
            // Same view, same static geometry: last frame's surface at p is this one, so
            // `history_hit` would pass; its reprojection and texture read are spared.
            old = history_color[k];
        } else if (history_hit(p, prev, nd.w)) {
            old = history_color[index_of(vec2<i32>(floor(prev)))];
        }
        if (old.a < f32(frame.max_history_age)) {
            flags |= FLAG_REUSED;
            seed = pack_seed(p);
            color = vec4<f32>(old.rgb, old.a + 1.0);
        }
    }
    out_probability[k] = f;
    out_flags[k] = flags;
    out_color[k] = color;
    out_seeds[k] = seed;
}
