// Which tiles pull-push's three dispatches nearest the pixels run (CPU twin: pass::
// pull_push_tiles::needed). The fill writes only covered pixels without a sample, so a fill
// workgroup (32×32 pixels from pixel −1) with none is left out of its indirect dispatch; the
// pull from the pixels merges only pixels that hold a sample, so its workgroup (32×32 pixels
// from pixel 0) with none would store only empty cells, which the cleared staging buffers hold
// already; level 1's planes are read only by the fill, so its push runs where a listed fill
// tile reads them. A software adapter runs a branch for every row of lanes whether or not one
// takes it; only a workgroup not dispatched is free.

@group(0) @binding(1) var<storage, read> flags: array<u32>;
// Two words per fill workgroup, 1 where needed (cleared each frame): the fill's, the pull's.
@group(0) @binding(2) var<storage, read_write> marks: array<u32>;
// Indirect dispatch arguments (x, y, z): the fill's, the pull's, level 1's push's.
@group(0) @binding(3) var<storage, read_write> args: array<atomic<u32>, 9>;
// The listed workgroups, packed x | y << 16: the fill's at 3i, the pull's at 3i + 1, level 1's
// push's at 3i + 2.
@group(0) @binding(4) var<storage, read_write> tiles: array<u32>;

// The fill's workgroups along a side of `n` pixels: an invocation per two 2×2 quads of pixels,
// quads starting at odd pixels (n/2 + 1 of them), 8 invocations a group.
fn push_groups(n: u32) -> u32 {
    return ((n / 2u + 2u) / 2u + 7u) / 8u;
}

fn fill_grid() -> vec2<u32> {
    return vec2<u32>(push_groups(frame.width), push_groups(frame.height));
}

// The pull's workgroups: a level-2 cell (4×4 pixels) an invocation, 8×8 a group.
fn pull_grid() -> vec2<u32> {
    return (vec2<u32>(frame.width, frame.height) + 31u) / 32u;
}

// As the fill's invocations: pixels 4·id − 1 … 4·id + 2 are the fill's (a workgroup is one
// fill tile), 4·id … 4·id + 3 the pull's (a workgroup is one pull tile): one 5×5 read.
@compute @workgroup_size(8, 8)
fn mark(@builtin(global_invocation_id) id: vec3<u32>) {
    let grid = fill_grid();
    if (any(id.xy >= 8u * grid)) {
        return;
    }
    let o = vec2<i32>(id.xy) * 4 - 1;
    var fill = false;
    var pull = false;
    for (var y = 0; y < 5; y++) {
        for (var x = 0; x < 5; x++) {
            let p = o + vec2<i32>(x, y);
            if (in_frame(p)) {
                let f = flags[index_of(p)];
                let covered = (f & FLAG_COVERED) != 0u;
                let sample = (f & (FLAG_SAMPLED | FLAG_REUSED)) != 0u;
                fill = fill || (covered && !sample && x < 4 && y < 4);
                pull = pull || (covered && sample && x > 0 && y > 0);
            }
        }
    }
    let t = id.xy / 8u;
    let i = 2u * (t.y * grid.x + t.x);
    if (fill) {
        marks[i] = 1u;
    }
    if (pull) {
        marks[i + 1u] = 1u;
    }
}

// Level 1's push's workgroups (32×32 cells of level 1 from cell −1): the push's grid at level
// 1's size (`push_groups` of its cells).
fn level1_grid() -> vec2<u32> {
    return vec2<u32>(push_groups((frame.width + 1u) / 2u), push_groups((frame.height + 1u) / 2u));
}

// Whether level 1's workgroup j has planes a listed fill tile reads: fill tile k reads level-1
// cells 16k − 1 … 16k + 15, workgroup j writes 32j − 1 … 32j + 30, so tiles 2j − 1 … 2j + 1.
fn level1_needed(j: vec2<u32>, grid: vec2<u32>) -> bool {
    var need = false;
    for (var dy = -1; dy <= 1; dy++) {
        for (var dx = -1; dx <= 1; dx++) {
            let k = vec2<i32>(j) * 2 + vec2<i32>(dx, dy);
            if (all(k >= vec2<i32>(0)) && all(k < vec2<i32>(grid))) {
                need = need || marks[2u * (u32(k.y) * grid.x + u32(k.x))] != 0u;
            }
        }
    }
    return need;
}

// One invocation per fill tile (the pull's and level 1's grids are never wider or taller):
// listed where needed, each list at every third word.
@compute @workgroup_size(8, 8)
fn list(@builtin(global_invocation_id) id: vec3<u32>) {
    let grid = fill_grid();
    if (all(id.xy == vec2<u32>(0u))) {
        for (var k = 0; k < 3; k++) {
            atomicStore(&args[3 * k + 1], 1u);
            atomicStore(&args[3 * k + 2], 1u);
        }
    }
    if (any(id.xy >= grid)) {
        return;
    }
    let i = 2u * (id.y * grid.x + id.x);
    let packed = id.x | (id.y << 16u);
    if (marks[i] != 0u) {
        tiles[3u * atomicAdd(&args[0], 1u)] = packed;
    }
    if (all(id.xy < pull_grid()) && marks[i + 1u] != 0u) {
        tiles[3u * atomicAdd(&args[3], 1u) + 1u] = packed;
    }
    if (all(id.xy < level1_grid()) && level1_needed(id.xy, grid)) {
        tiles[3u * atomicAdd(&args[6], 1u) + 2u] = packed;
    }
}
