// Compaction (the thesis's CSR reordering, as stream compaction): the sampled pixels become one
// dense list, so the shading dispatch runs exactly as many invocations as there are samples.
// Each 8×8 tile reserves its slots with one global atomic, so list order keeps tiles together.
// A frame in parts lists each band of rows (shade_rows) just before shading it, after the bands
// before it; a whole frame is one band.

@group(0) @binding(1) var<storage, read> flags: array<u32>;
@group(0) @binding(2) var<storage, read_write> list: array<u32>;
// [0]: samples listed so far (the frame's count once every band is listed); [1..4]: indirect
// dispatch arguments for shading the last band's samples; [4]: where they start in the list.
@group(0) @binding(3) var<storage, read_write> counter: array<atomic<u32>, 8>;

// One invocation per 8×8 tile, its pixels in row-major order: the tile reserves its slots with
// one global atomic, and no workgroup barrier is needed (a software adapter splits a shader
// at each barrier into pieces it resumes one by one). A workgroup's 8×8 tiles are listed
// together, so a shading workgroup takes neighbouring samples: on that adapter shading was
// 10–20% slower while each tile was a workgroup and the worker threads' tiles interleaved.
@compute @workgroup_size(8, 8)
fn main(@builtin(global_invocation_id) id: vec3<u32>) {
    let origin = vec2<i32>(id.xy * 8u + vec2<u32>(0u, frame.shade_rows.x));
    let end = vec2<i32>(i32(frame.width), i32(min(frame.height, frame.shade_rows.y)));
    if (any(origin >= end)) {
        return;
    }
    // The tile's sampled pixels as bits, row-major: rows 0–3 in `lo`, 4–7 in `hi`.
    let last = min(origin + 8, end);
    var lo = 0u;
    var hi = 0u;
    for (var y = origin.y; y < last.y; y++) {
        var row = 0u;
        for (var x = origin.x; x < last.x; x++) {
            let f = flags[index_of(vec2<i32>(x, y))];
            row |= select(0u, 1u, (f & FLAG_SAMPLED) != 0u) << u32(x - origin.x);
        }
        let r = u32(y - origin.y);
        if (r < 4u) {
            lo |= row << (8u * r);
        } else {
            hi |= row << (8u * (r - 4u));
        }
    }
    let upper = countOneBits(lo);
    let count = upper + countOneBits(hi);
    if (count == 0u) {
        return;
    }
    let slot = atomicAdd(&counter[0], count);
    append(&lo, origin, slot);
    append(&hi, origin + vec2<i32>(0, 4), slot + upper);
}

// Lists the pixels of four tile rows from `origin` whose bits are set in `bits`, from `slot`.
fn append(bits: ptr<function, u32>, origin: vec2<i32>, slot: u32) {
    var s = slot;
    while (*bits != 0u) {
        let b = firstTrailingBit(*bits);
        *bits &= *bits - 1u;
        list[s] = pack_seed(origin + vec2<i32>(i32(b & 7u), i32(b >> 3u)));
        s += 1u;
    }
}

// One invocation before `main`: the band's samples start where the list ends.
@compute @workgroup_size(1)
fn band_start() {
    atomicStore(&counter[4], atomicLoad(&counter[0]));
}

// One invocation after `main`: turns the band's count into workgroups of 64 for the list dispatch.
@compute @workgroup_size(1)
fn indirect_args() {
    let n = atomicLoad(&counter[0]) - atomicLoad(&counter[4]);
    atomicStore(&counter[1], (n + 63u) / 64u);
    atomicStore(&counter[2], 1u);
    atomicStore(&counter[3], 1u);
}
