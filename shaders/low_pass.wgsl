// Foveated encoding's low-pass on the GPU (CPU twin: src/encode/foveated.rs low_pass, which
// tests/low_pass.rs holds this to): the output image's periphery averaged to what the eye can
// resolve there, in place, before readback, so the encoder thread does not spend ~30 ms a 720p
// frame on it. Pixels at level 0 (the fovea and its guard) are not written: bit for bit the
// image the output pass made.
//
// `pyramid` runs once per level 1..=5 (the level in the dispatch's parameter slot), each a 2×2
// box average of the one below, halved rounding up with the edge repeated; level 1 averages
// the image's bytes. `apply` blends each pixel's two levels around its L, read bilinearly
// (vertically first, then horizontally, as the CPU twin's row buffers do), L itself the
// bilinear blend of the four corners of its 8-pixel cell from `grid`, which the CPU computes
// exactly (encode::foveated::level_grid) and uploads each frame.

struct LowPass {
    // The pyramid level this dispatch writes (1..=5); 0 for `apply`.
    level: u32,
    grid_width: u32,
    cell: u32,
    max_level: u32,
    // Per level 0..=5: width, height, offset of its first texel in `pyramid` (level 0: the frame).
    levels: array<vec4<u32>, 6>,
}

@group(0) @binding(1) var<uniform> lp: LowPass;
@group(0) @binding(2) var<storage, read> grid: array<f32>;
// Packed RGBA8 (red in the low byte), read and written in place.
@group(0) @binding(3) var<storage, read_write> image: array<u32>;
@group(0) @binding(4) var<storage, read_write> pyramid: array<vec4<f32>>;

fn bytes_rgb(p: u32) -> vec3<f32> {
    return vec3<f32>(f32(p & 0xffu), f32((p >> 8u) & 0xffu), f32((p >> 16u) & 0xffu));
}

fn image_rgb(x: u32, y: u32) -> vec3<f32> {
    return bytes_rgb(image[y * frame.width + x]);
}

fn texel(k: u32, x: u32, y: u32) -> vec3<f32> {
    let l = lp.levels[k];
    return pyramid[l.z + y * l.x + x].xyz;
}

@compute @workgroup_size(8, 8)
fn build(@builtin(global_invocation_id) id: vec3<u32>) {
    let k = lp.level;
    let here = lp.levels[k];
    if (id.x >= here.x || id.y >= here.y) {
        return;
    }
    let below = lp.levels[k - 1u];
    let x0 = 2u * id.x;
    let y0 = 2u * id.y;
    let x1 = min(x0 + 1u, below.x - 1u);
    let y1 = min(y0 + 1u, below.y - 1u);
    var a: vec3<f32>;
    var b: vec3<f32>;
    var c: vec3<f32>;
    var d: vec3<f32>;
    if (k == 1u) {
        a = image_rgb(x0, y0);
        b = image_rgb(x1, y0);
        c = image_rgb(x0, y1);
        d = image_rgb(x1, y1);
    } else {
        a = texel(k - 1u, x0, y0);
        b = texel(k - 1u, x1, y0);
        c = texel(k - 1u, x0, y1);
        d = texel(k - 1u, x1, y1);
    }
    pyramid[here.z + id.y * here.x + id.x] = vec4<f32>(0.25 * (a + b + c + d), 0.0);
}

// Where frame coordinate x falls on level k of n samples: the two samples and the weight of
// the second (level texel i covers frame pixels i·2^k … (i+1)·2^k − 1).
fn tap(x: u32, k: u32, n: u32) -> vec3<f32> {
    let s = f32(1u << k);
    let f = clamp((f32(x) + 0.5) / s - 0.5, 0.0, f32(n - 1u));
    let i0 = u32(f);
    return vec3<f32>(f32(i0), f32(min(i0 + 1u, n - 1u)), f - f32(i0));
}

// Level k (≥ 1) at frame pixel (x, y), bilinearly.
fn bilinear(k: u32, x: u32, y: u32) -> vec3<f32> {
    let l = lp.levels[k];
    let tx = tap(x, k, l.x);
    let ty = tap(y, k, l.y);
    let x0 = u32(tx.x);
    let x1 = u32(tx.y);
    let y0 = u32(ty.x);
    let y1 = u32(ty.y);
    let left = texel(k, x0, y0) + (texel(k, x0, y1) - texel(k, x0, y0)) * ty.z;
    let right = texel(k, x1, y0) + (texel(k, x1, y1) - texel(k, x1, y0)) * ty.z;
    return left + (right - left) * tx.z;
}

fn level_of(x: u32, y: u32) -> f32 {
    let i = x / lp.cell;
    let j = y / lp.cell;
    let fx = f32(x % lp.cell) / f32(lp.cell);
    let fy = f32(y % lp.cell) / f32(lp.cell);
    let gw = lp.grid_width;
    let g00 = grid[j * gw + i];
    let g10 = grid[j * gw + i + 1u];
    let g01 = grid[(j + 1u) * gw + i];
    let g11 = grid[(j + 1u) * gw + i + 1u];
    let top = g00 + (g10 - g00) * fx;
    let bottom = g01 + (g11 - g01) * fx;
    return top + (bottom - top) * fy;
}

@compute @workgroup_size(8, 8)
fn apply(@builtin(global_invocation_id) id: vec3<u32>) {
    if (!in_frame(vec2<i32>(id.xy))) {
        return;
    }
    let l = level_of(id.x, id.y);
    if (!(l > 0.0)) {
        return;
    }
    let k = min(u32(l), lp.max_level);
    let t = l - f32(k);
    let i = index_of(vec2<i32>(id.xy));
    let p = image[i];
    var a: vec3<f32>;
    if (k == 0u) {
        a = bytes_rgb(p);
    } else {
        a = bilinear(k, id.x, id.y);
    }
    var b = a;
    if (t > 0.0 && k < lp.max_level) {
        b = bilinear(k + 1u, id.x, id.y);
    }
    let c = vec3<u32>(clamp(a + (b - a) * t + 0.5, vec3<f32>(0.0), vec3<f32>(255.0)));
    image[i] = (p & 0xff000000u) | c.x | (c.y << 8u) | (c.z << 16u);
}
