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

var<workgroup> tile_count: atomic<u32>;
var<workgroup> tile_base: u32;

@compute @workgroup_size(8, 8)
fn main(@builtin(global_invocation_id) id: vec3<u32>, @builtin(local_invocation_index) li: u32) {
    if (li == 0u) {
        atomicStore(&tile_count, 0u);
    }
    workgroupBarrier();
    let p = vec2<i32>(id.xy + vec2<u32>(0u, frame.shade_rows.x));
    var slot = 0xFFFFFFFFu;
    let listed = in_frame(p) && u32(p.y) < frame.shade_rows.y;
    if (listed && (flags[index_of(p)] & FLAG_SAMPLED) != 0u) {
        slot = atomicAdd(&tile_count, 1u);
    }
    workgroupBarrier();
    if (li == 0u) {
        tile_base = atomicAdd(&counter[0], atomicLoad(&tile_count));
    }
    let base = workgroupUniformLoad(&tile_base);
    if (slot != 0xFFFFFFFFu) {
        list[base + slot] = pack_seed(p);
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
