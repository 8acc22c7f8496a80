// Which tiles pull-push's pixel fill runs (CPU twin: pass::pull_push_tiles::needed). The fill
// writes only covered pixels without a sample, so a fill workgroup (32×32 pixels) with none is
// left out of its indirect dispatch: the background and the fully sampled fovea cost nothing
// there. A software adapter runs a branch for every row of lanes whether or not one takes
// it; only a workgroup not dispatched is free.

@group(0) @binding(1) var<storage, read> flags: array<u32>;
// One word per fill workgroup: 1 where one of its pixels needs filling (cleared each frame).
@group(0) @binding(2) var<storage, read_write> marks: array<u32>;
// The fill's indirect dispatch arguments (x, y, z).
@group(0) @binding(3) var<storage, read_write> args: array<atomic<u32>, 3>;
// The listed workgroups, packed x | y << 16.
@group(0) @binding(4) var<storage, read_write> tiles: array<u32>;

// The fill's workgroups along a side of `n` pixels: an invocation per two 2×2 quads of pixels,
// quads starting at odd pixels (n/2 + 1 of them), 8 invocations a group.
fn push_groups(n: u32) -> u32 {
    return ((n / 2u + 2u) / 2u + 7u) / 8u;
}

fn fill_grid() -> vec2<u32> {
    return vec2<u32>(push_groups(frame.width), push_groups(frame.height));
}

// As the fill's invocations: the 4×4 pixels from 4·id − 1, so a workgroup is one fill tile.
@compute @workgroup_size(8, 8)
fn mark(@builtin(global_invocation_id) id: vec3<u32>) {
    let grid = fill_grid();
    if (any(id.xy >= 8u * grid)) {
        return;
    }
    let o = vec2<i32>(id.xy) * 4 - 1;
    var need = false;
    for (var y = 0; y < 4; y++) {
        for (var x = 0; x < 4; x++) {
            let p = o + vec2<i32>(x, y);
            if (in_frame(p)) {
                let f = flags[index_of(p)];
                let sample = (f & (FLAG_SAMPLED | FLAG_REUSED)) != 0u;
                need = need || ((f & FLAG_COVERED) != 0u && !sample);
            }
        }
    }
    if (need) {
        let t = id.xy / 8u;
        marks[t.y * grid.x + t.x] = 1u;
    }
}

// One invocation per fill tile: listed where marked.
@compute @workgroup_size(8, 8)
fn list(@builtin(global_invocation_id) id: vec3<u32>) {
    let grid = fill_grid();
    if (all(id.xy == vec2<u32>(0u))) {
        atomicStore(&args[1], 1u);
        atomicStore(&args[2], 1u);
    }
    if (any(id.xy >= grid) || marks[id.y * grid.x + id.x] == 0u) {
        return;
    }
    tiles[atomicAdd(&args[0], 1u)] = id.x | (id.y << 16u);
}
