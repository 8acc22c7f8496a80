// RGB → I420 for H.264 sessions (CPU twin: src/encode/yuv.rs rgba_to_i420): the output image's
// packed sRGB RGBA8 to BT.601 full-range Y, U and V planes, rounded to nearest, chroma from
// each 2×2 block's mean RGB. Read back instead of the RGBA image: 1.5 bytes a pixel, not 4.
//
// `output.i420` holds the Y plane (w·h bytes), then U and V, each padded to whole words:
// invocation k writes Y bytes 4k..4k+3 (four pixels in row-major order, possibly across a row
// end) and, while k is inside them, words k of U and V.

@group(0) @binding(1) var<storage, read> image: array<u32>;
@group(0) @binding(2) var<storage, read_write> planes: array<u32>;

fn rgb_at(i: u32) -> vec3<f32> {
    let p = image[i];
    return vec3<f32>(f32(p & 0xffu), f32((p >> 8u) & 0xffu), f32((p >> 16u) & 0xffu));
}

fn luma(c: vec3<f32>) -> f32 {
    return 0.299 * c.r + 0.587 * c.g + 0.114 * c.b;
}

fn code(x: f32) -> u32 {
    return u32(clamp(x + 0.5, 0.0, 255.0));
}

// Chroma sample c (row-major over the half-size grid): (U, V) codes of its 2×2 block.
fn chroma(c: u32, width: u32) -> vec2<u32> {
    let hw = width / 2u;
    let x = (c % hw) * 2u;
    let y = (c / hw) * 2u;
    let i = y * width + x;
    let m = (rgb_at(i) + rgb_at(i + 1u) + rgb_at(i + width) + rgb_at(i + width + 1u)) * 0.25;
    let l = luma(m);
    return vec2<u32>(
        code(128.0 + (m.b - l) / 1.772),
        code(128.0 + (m.r - l) / 1.402),
    );
}

@compute @workgroup_size(64)
fn main(@builtin(global_invocation_id) id: vec3<u32>) {
    let size = vec2<u32>(frame_size());
    let pixels = size.x * size.y;
    let y_words = pixels / 4u;
    let chroma_n = pixels / 4u;
    let c_words = (chroma_n + 3u) / 4u;
    let k = id.x;
    if (k < y_words) {
        var word = 0u;
        for (var j = 0u; j < 4u; j++) {
            word |= code(luma(rgb_at(4u * k + j))) << (8u * j);
        }
        planes[k] = word;
    }
    if (k < c_words) {
        var u = 0u;
        var v = 0u;
        for (var j = 0u; j < 4u; j++) {
            let c = 4u * k + j;
            if (c < chroma_n) {
                let uv = chroma(c, size.x);
                u |= uv.x << (8u * j);
                v |= uv.y << (8u * j);
            }
        }
        planes[y_words + k] = u;
        planes[y_words + c_words + k] = v;
    }
}
