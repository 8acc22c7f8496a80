// Pull-push reconstruction (seed 000's hierarchical interpolation): moments pulled up a pyramid
// of 2×2 cells, planes pushed back down, each pixel without a sample filled from its four level-1
// planes, on colour over the G-buffer's prediction (`proxy`). CPU twin: foveation::pull_push.

// The shaded colour, filled in place where a pixel has no sample.
@group(0) @binding(1) var<storage, read_write> color: array<vec4<f32>>;
@group(0) @binding(2) var<storage, read> flags: array<u32>;
@group(0) @binding(3) var albedo_tex: texture_2d<f32>;
@group(0) @binding(6) var normal_distance: texture_2d<f32>;
// The pyramid is read from two texture atlases (odd, even levels; `_in` routed per dispatch);
// a dispatch writes its level to staging buffers, copied into the atlas (pass/pull_push.rs).
@group(0) @binding(4) var<storage, read_write> moments_staged: array<vec4<f32>>;
@group(0) @binding(10) var<storage, read_write> moments_staged_hi: array<vec4<f32>>;
@group(0) @binding(7) var moments_in: texture_2d_array<f32>;
@group(0) @binding(8) var planes_in: texture_2d_array<f32>;
@group(0) @binding(9) var<storage, read_write> planes_staged: array<vec4<f32>>;
// Workgroups three dispatches run (pull_push_tiles.wgsl): fill 3i, pull 3i + 1, level 1 3i + 2.
@group(0) @binding(11) var<storage, read> tiles: array<u32>;

// One dispatch: this level's size and corner in its atlas, and its neighbour's (pull: below).
struct Level {
    size: vec2<u32>,
    origin: vec2<u32>,
    near_size: vec2<u32>,
    near_origin: vec2<u32>,
    level: u32,
    has_parent: u32, // 1 when the level above exists (push): the top cell leans on nothing
    ridge: f32,
    floor: f32,
    depth_tolerance: f32,
    material_tolerance: f32,
    row: u32, // texels a row of the staging buffers holds at this level
}
@group(0) @binding(5) var<uniform> level: Level;

// Moments (pull): c, w, mean, scatter s = (xx, xy, yy), cross terms t per axis, mean depth and
// material id with spreads, sample range (lo, hi over all channels). Six layers: (c, w), (mean,
// s.xy), (tx, s.z), (ty, depth), (lo, hi, material, depth_var), (material_var). Planes: four.
struct Cell {
    c: vec3<f32>, w: f32, mean: vec2<f32>, s: vec3<f32>, tx: vec3<f32>, ty: vec3<f32>,
    depth: f32, lo: f32, hi: f32, material: f32, depth_var: f32, material_var: f32,
}

const BIG: f32 = 3.0e38;

fn empty_cell() -> Cell {
    let z = vec3<f32>(0.0);
    return Cell(z, 0.0, vec2<f32>(0.0), z, z, z, 0.0, BIG, -BIG, 0.0, 0.0, 0.0);
}

// The moments of the cell at atlas texel `q`; all zeros (a tile `pull_pixels` skipped) is empty.
fn load_cell(q: vec2<u32>) -> Cell {
    let p = vec2<i32>(q);
    let a = textureLoad(moments_in, p, 0, 0);
    let b = textureLoad(moments_in, p, 1, 0);
    let c = textureLoad(moments_in, p, 2, 0);
    let d = textureLoad(moments_in, p, 3, 0);
    let e = textureLoad(moments_in, p, 4, 0);
    let m = textureLoad(moments_in, p, 5, 0).x;
    let range = select(vec2<f32>(BIG, -BIG), e.xy, a.a > 0.0);
    return Cell(a.rgb, a.a, b.xy, vec3<f32>(b.z, b.w, c.a), c.rgb, d.rgb, d.a, range.x, range.y, e.z, e.w, m);
}

// This level's cell `c`, its moments to the staging buffers.
fn store_cell(c: vec2<u32>, v: Cell) {
    let i = c.y * level.row + c.x;
    let n = level.size.y * level.row;
    moments_staged[i] = vec4<f32>(v.c, v.w);
    moments_staged[i + n] = vec4<f32>(v.mean, v.s.x, v.s.y);
    moments_staged[i + 2u * n] = vec4<f32>(v.tx, v.s.z);
    moments_staged_hi[i] = vec4<f32>(v.ty, v.depth);
    moments_staged_hi[i + n] = vec4<f32>(v.lo, v.hi, v.material, v.depth_var);
    moments_staged_hi[i + 2u * n] = vec4<f32>(v.material_var, 0.0, 0.0, 0.0);
}

// Cell `c` completed, to the staging buffer: value, material spread, gradient, depth, range.
fn store_plane(c: vec2<u32>, v: Cell) {
    let i = c.y * level.row + c.x;
    let n = level.size.y * level.row;
    planes_staged[i] = vec4<f32>(v.c, v.material_var);
    planes_staged[i + n] = vec4<f32>(v.tx, 0.0);
    planes_staged[i + 2u * n] = vec4<f32>(v.ty, v.depth);
    planes_staged[i + 3u * n] = vec4<f32>(v.lo, v.hi, v.material, v.depth_var);
}

// What the G-buffer alone predicts of a pixel's colour: the key light's Lambert term with the
// ambient, on the albedo, plus the floor; colour / proxy is what is interpolated.
fn proxy(nd: vec4<f32>, albedo: vec4<f32>) -> vec3<f32> {
    return lambert(nd.xyz, albedo.rgb) + level.floor;
}

// The pixel's material id (the G-buffer albedo's alpha holds id / 255).
fn material_of(albedo: vec4<f32>) -> f32 {
    return round(albedo.a * 255.0);
}

// A pixel as a cell: its demodulated colour when it holds a sample, else (or off frame) empty.
fn pixel_cell(p: vec2<i32>) -> Cell {
    var out = empty_cell();
    if (!in_frame(p)) {
        return out;
    }
    let f = flags[index_of(p)];
    if ((f & FLAG_COVERED) != 0u && (f & (FLAG_SAMPLED | FLAG_REUSED)) != 0u) {
        let nd = textureLoad(normal_distance, p, 0);
        let albedo = textureLoad(albedo_tex, p, 0);
        out.c = color[index_of(p)].rgb / proxy(nd, albedo);
        out.w = 1.0;
        out.mean = vec2<f32>(p) + 0.5;
        out.depth = nd.w;
        out.material = material_of(albedo);
        out.lo = min(out.c.r, min(out.c.g, out.c.b));
        out.hi = max(out.c.r, max(out.c.g, out.c.b));
    }
    return out;
}

// The exact merge of four children (some may be empty), W then clamped to 1. Named cells, not
// an array: a GPU compiler keeps an array indexed in a loop in slow per-thread memory.
fn merge(c0: Cell, c1: Cell, c2: Cell, c3: Cell) -> Cell {
    var out = empty_cell();
    out.w = c0.w + c1.w + c2.w + c3.w;
    out.lo = min(min(min(c0.lo, c1.lo), c2.lo), c3.lo);
    out.hi = max(max(max(c0.hi, c1.hi), c2.hi), c3.hi);
    if (out.w <= 0.0) {
        return out;
    }
    add_means(&out, c0);
    add_means(&out, c1);
    add_means(&out, c2);
    add_means(&out, c3);
    add_spreads(&out, c0);
    add_spreads(&out, c1);
    add_spreads(&out, c2);
    add_spreads(&out, c3);
    if (out.w > 1.0) {
        let k = 1.0 / out.w;
        out.w = 1.0;
        out.s *= k;
        out.tx *= k;
        out.ty *= k;
    }
    return out;
}

// A child's share of the weighted means (`out.w` holds the children's total weight).
fn add_means(out: ptr<function, Cell>, ch: Cell) {
    let k = ch.w / (*out).w;
    (*out).mean += k * ch.mean;
    (*out).depth += k * ch.depth;
    (*out).material += k * ch.material;
    (*out).c += k * ch.c;
}

// A child's spreads about the merged means: depth, material, position, position × colour.
fn add_spreads(out: ptr<function, Cell>, ch: Cell) {
    if (ch.w <= 0.0) {
        return;
    }
    let k = ch.w / (*out).w;
    let dz = ch.depth - (*out).depth;
    (*out).depth_var += k * (ch.depth_var + dz * dz);
    let dm = ch.material - (*out).material;
    (*out).material_var += k * (ch.material_var + dm * dm);
    let d = ch.mean - (*out).mean;
    (*out).s += ch.s + ch.w * vec3<f32>(d.x * d.x, d.x * d.y, d.y * d.y);
    let dc = ch.c - (*out).c;
    (*out).tx += ch.tx + ch.w * d.x * dc;
    (*out).ty += ch.ty + ch.w * d.y * dc;
}

// Level 1's cell `q` merged from its pixels, or empty past level 1 (`bound`). Never stored
// (pull_pixels and push_level1 each merge it): its stores and copy cost more on lavapipe.
fn level1_cell(q: vec2<u32>, bound: vec2<u32>) -> Cell {
    if (any(q >= bound)) {
        return empty_cell();
    }
    let p = vec2<i32>(2u * q);
    let x = vec2<i32>(1, 0);
    return merge(pixel_cell(p), pixel_cell(p + x), pixel_cell(p + x.yx), pixel_cell(p + 1));
}

// The invocation a full dispatch would have in the workgroup listed at `tiles[i]`.
fn listed(i: u32, local: vec3<u32>) -> vec2<u32> {
    return vec2<u32>(tiles[i] & 0xFFFFu, tiles[i] >> 16u) * 8u + local.xy;
}

// Pull, level 2 (its `near` level is level 1) from the pixels: a cell's four level-1 cells. Only
// workgroups with a sample run; the rest of the staging buffers stay zero (an empty cell).
@compute @workgroup_size(8, 8)
fn pull_pixels(@builtin(workgroup_id) g: vec3<u32>, @builtin(local_invocation_id) l: vec3<u32>) {
    let id = listed(3u * g.x + 1u, l);
    if (any(id.xy >= level.size)) {
        return;
    }
    let q = 2u * id.xy;
    let c0 = level1_cell(q, level.near_size);
    let c1 = level1_cell(q + vec2<u32>(1u, 0u), level.near_size);
    let c2 = level1_cell(q + vec2<u32>(0u, 1u), level.near_size);
    let c3 = level1_cell(q + vec2<u32>(1u, 1u), level.near_size);
    store_cell(id.xy, merge(c0, c1, c2, c3));
}

// Child `i` (0..3, row-major) of cell `id` one level down (`near`), or empty past its border.
fn child_cell(id: vec2<u32>, i: u32) -> Cell {
    let q = 2u * id + vec2<u32>(i & 1u, i >> 1u);
    if (all(q < level.near_size)) {
        return load_cell(level.near_origin + q);
    }
    return empty_cell();
}

// Pull, level l ≥ 2 from level l − 1.
@compute @workgroup_size(8, 8)
fn pull(@builtin(global_invocation_id) id: vec3<u32>) {
    if (any(id.xy >= level.size)) {
        return;
    }
    let m = merge(child_cell(id.xy, 0u), child_cell(id.xy, 1u), child_cell(id.xy, 2u), child_cell(id.xy, 3u));
    store_cell(id.xy, m);
}

// What a parent lends its children: its plane, depth, sample range, and its centre (pixels).
struct Plane {
    c: vec3<f32>, depth: f32, material: f32, depth_var: f32, material_var: f32,
    tx: vec3<f32>, ty: vec3<f32>, lo: f32, hi: f32, centre: vec2<f32>,
}

// A completed cell of the level above, clamped into it (edge cells stand in past the border).
fn load_plane(q: vec2<i32>, ps: f32) -> Plane {
    let c = clamp(q, vec2<i32>(0), vec2<i32>(level.near_size) - 1);
    let p = c + vec2<i32>(level.near_origin);
    let a = textureLoad(planes_in, p, 0, 0);
    let x = textureLoad(planes_in, p, 1, 0);
    let t = textureLoad(planes_in, p, 2, 0);
    let e = textureLoad(planes_in, p, 3, 0);
    return Plane(a.rgb, t.a, e.z, e.w, a.a, x.rgb, t.rgb, e.x, e.y, (vec2<f32>(c) + 0.5) * ps);
}

// Bilinear position of a level-`l` centre among the parents: the first parent and the weights.
fn parent_base(centre: vec2<f32>, l: u32) -> vec4<f32> {
    let u = centre / f32(2u << l) - 0.5;
    let base = floor(u);
    return vec4<f32>(base, u - base);
}

// Sums of the blend: depth-weighted (b), plain bilinear (k: if every parent lies elsewhere).
struct Blend {
    c: vec3<f32>, tx: vec3<f32>, ty: vec3<f32>, b: f32,
    ck: vec3<f32>, txk: vec3<f32>, tyk: vec3<f32>, lo: f32, hi: f32,
}

fn blend_start() -> Blend {
    let z = vec3<f32>(0.0);
    return Blend(z, z, z, 0.0, z, z, z, BIG, -BIG);
}

// Adds parent `p`'s plane at `centre`, weight k over the expected squared difference of depth
// and material between `aim` and a sample under it (means' difference² plus its spread).
fn blend_add(acc: ptr<function, Blend>, p: Plane, k: f32, centre: vec2<f32>, aim: vec2<f32>) {
    let d = centre - p.centre;
    let v = p.c + p.tx * d.x + p.ty * d.y;
    let scale = max(level.depth_tolerance * abs(aim.x), 1e-12);
    let r2 = ((p.depth - aim.x) * (p.depth - aim.x) + p.depth_var) / (scale * scale);
    let m2 = ((p.material - aim.y) * (p.material - aim.y) + p.material_var)
        / (level.material_tolerance * level.material_tolerance);
    let b = k / ((1.0 + r2) * (1.0 + m2));
    (*acc).c += b * v;
    (*acc).tx += b * p.tx;
    (*acc).ty += b * p.ty;
    (*acc).b += b;
    (*acc).ck += k * v;
    (*acc).txk += k * p.tx;
    (*acc).tyk += k * p.ty;
    (*acc).lo = min((*acc).lo, p.lo);
    (*acc).hi = max((*acc).hi, p.hi);
}

// The blend as a plane: each parent's is exact for a linear function, so any such blend is.
fn blend_end(acc: Blend, aim: vec2<f32>) -> Cell {
    var out = empty_cell();
    out.depth = aim.x;
    out.material = aim.y;
    out.lo = acc.lo;
    out.hi = acc.hi;
    if (acc.b > 1e-6) {
        out.c = acc.c / acc.b;
        out.tx = acc.tx / acc.b;
        out.ty = acc.ty / acc.b;
    } else {
        out.c = acc.ck;
        out.tx = acc.txk;
        out.ty = acc.tyk;
    }
    return out;
}

fn bilinear_weight(f: vec2<f32>, j: i32) -> f32 {
    let wxy = mix(1.0 - f, f, vec2<f32>(vec2<i32>(j & 1, j >> 1)));
    return wxy.x * wxy.y;
}

// The four parents around a cell, in bilinear order from the one with the smallest x and y.
struct Parents { p0: Plane, p1: Plane, p2: Plane, p3: Plane }

// The coarse plane at a level-`l` centre from its parents (loaded by the caller), blended by
// bilinear weight and closeness to `key` = (depth, material) (depth < 0: the parents' blend).
fn coarse_plane(par: Parents, centre: vec2<f32>, l: u32, key: vec2<f32>) -> Cell {
    if (level.has_parent == 0u) {
        return empty_cell();
    }
    let at = parent_base(centre, l);
    let k0 = bilinear_weight(at.zw, 0);
    let k1 = bilinear_weight(at.zw, 1);
    let k2 = bilinear_weight(at.zw, 2);
    let k3 = bilinear_weight(at.zw, 3);
    var aim = key;
    if (aim.x < 0.0) {
        aim = vec2<f32>(
            k0 * par.p0.depth + k1 * par.p1.depth + k2 * par.p2.depth + k3 * par.p3.depth,
            k0 * par.p0.material + k1 * par.p1.material + k2 * par.p2.material + k3 * par.p3.material,
        );
    }
    var acc = blend_start();
    blend_add(&acc, par.p0, k0, centre, aim);
    blend_add(&acc, par.p1, k1, centre, aim);
    blend_add(&acc, par.p2, k2, centre, aim);
    blend_add(&acc, par.p3, k3, centre, aim);
    return blend_end(acc, aim);
}

// A push invocation does 2×2 quads of cells, ids 2·id + (0|1, 0|1). A quad's cells (2·q − 1) +
// (0|1, 0|1) share their parents (q − 1) + (0|1, 0|1); four quads' parents are 3×3 planes, read
// once: 36 texels for 16 cells, not 256 (looping over quads, or workgroup memory, was slower).
fn quad_origin(q: vec2<u32>) -> vec2<i32> {
    return vec2<i32>(q) * 2 - 1;
}

struct Block {
    p00: Plane, p10: Plane, p20: Plane, p01: Plane, p11: Plane, p21: Plane,
    p02: Plane, p12: Plane, p22: Plane,
}

// The parent at (dx, dy) from `b` on the level above.
fn parent(b: vec2<i32>, dx: i32, dy: i32) -> Plane {
    return load_plane(b + vec2<i32>(dx, dy), f32(2u << level.level));
}

// The 3×3 parents of the four quads from `q`, or nothing to load for the top cell.
fn load_block(q: vec2<u32>) -> Block {
    if (level.has_parent == 0u) {
        let z = vec3<f32>(0.0);
        let n = Plane(z, 0.0, 0.0, 0.0, 0.0, z, z, 0.0, 0.0, vec2<f32>(0.0));
        return Block(n, n, n, n, n, n, n, n, n);
    }
    let b = vec2<i32>(q) - 1;
    return Block(
        parent(b, 0, 0), parent(b, 1, 0), parent(b, 2, 0),
        parent(b, 0, 1), parent(b, 1, 1), parent(b, 2, 1),
        parent(b, 0, 2), parent(b, 1, 2), parent(b, 2, 2),
    );
}

// Push at this level (0: the pixels), the four quads from `q`.
fn push_block(q: vec2<u32>, kind: u32) {
    let o = quad_origin(q);
    if (any(o >= vec2<i32>(level.size))) {
        return;
    }
    let k = load_block(q);
    push_quad(o, Parents(k.p00, k.p10, k.p01, k.p11), kind);
    push_quad(o + vec2<i32>(2, 0), Parents(k.p10, k.p20, k.p11, k.p21), kind);
    push_quad(o + vec2<i32>(0, 2), Parents(k.p01, k.p11, k.p02, k.p12), kind);
    push_quad(o + vec2<i32>(2, 2), Parents(k.p11, k.p21, k.p12, k.p22), kind);
}

fn push_quad(o: vec2<i32>, par: Parents, kind: u32) {
    if (kind == PUSH_PIXELS) {
        push_pixel(o, par);
        push_pixel(o + vec2<i32>(1, 0), par);
        push_pixel(o + vec2<i32>(0, 1), par);
        push_pixel(o + vec2<i32>(1, 1), par);
    } else {
        push_cell(o, par, kind);
        push_cell(o + vec2<i32>(1, 0), par, kind);
        push_cell(o + vec2<i32>(0, 1), par, kind);
        push_cell(o + vec2<i32>(1, 1), par, kind);
    }
}

// `v` at a level-`l` centre (a pixel, an empty level-1 cell) inside its parents' square, off the
// border: within their values per channel. CPU twin: foveation::pull_push::within_corners.
fn within_corners(v: vec3<f32>, par: Parents, centre: vec2<f32>, l: u32) -> vec3<f32> {
    let b = parent_base(centre, l).xy;
    if (any(b < vec2<f32>(0.0)) || any(b + 1.0 >= vec2<f32>(level.near_size))) {
        return v;
    }
    let lo = min(min(par.p0.c, par.p1.c), min(par.p2.c, par.p3.c));
    return clamp(v, lo, max(max(par.p0.c, par.p1.c), max(par.p2.c, par.p3.c)));
}

// What a push computes (a constant per entry point): planes from moments, level 1's, pixels.
const PUSH_CELLS: u32 = 0u;
const PUSH_LEVEL1: u32 = 1u;
const PUSH_PIXELS: u32 = 2u;

// Push, level l ≥ 2 (the top cell too): each cell's plane from its moments and the coarse plane.
@compute @workgroup_size(8, 8)
fn push(@builtin(global_invocation_id) id: vec3<u32>) {
    push_block(id.xy * 2u, PUSH_CELLS);
}

// Push, level 1: as `push`, its moments from the pixels (never stored); where the fill reads it.
@compute @workgroup_size(8, 8)
fn push_level1(@builtin(workgroup_id) g: vec3<u32>, @builtin(local_invocation_id) l: vec3<u32>) {
    push_block(listed(3u * g.x + 2u, l) * 2u, PUSH_LEVEL1);
}

fn push_cell(c: vec2<i32>, par: Parents, kind: u32) {
    if (any(c < vec2<i32>(0)) || any(c >= vec2<i32>(level.size))) {
        return;
    }
    let side = f32(1u << level.level);
    let centre = (vec2<f32>(c) + 0.5) * side;
    var cell: Cell;
    if (kind == PUSH_LEVEL1) {
        cell = level1_cell(vec2<u32>(c), level.size);
    } else {
        cell = load_cell(level.origin + vec2<u32>(c));
    }
    var aim = vec2<f32>(-1.0, 0.0);
    if (cell.w > 0.0) {
        aim = vec2<f32>(cell.depth, cell.material);
    }
    let coarse = coarse_plane(par, centre, level.level, aim);
    if (cell.w <= 0.0) {
        var bounded = coarse;
        if (kind == PUSH_LEVEL1) {
            bounded.c = within_corners(coarse.c, par, centre, 1u);
        }
        store_plane(vec2<u32>(c), bounded);
        return;
    }
    let lambda = level.ridge * cell.w * side * side;
    let a = cell.s.x + lambda;
    let b = cell.s.y;
    let d = cell.s.z + lambda;
    let det = a * d - b * b;
    let rx = cell.tx + lambda * coarse.tx;
    let ry = cell.ty + lambda * coarse.ty;
    var gx = coarse.tx;
    var gy = coarse.ty;
    if (det > 0.0) {
        gx = (d * rx - b * ry) / det;
        gy = (a * ry - b * rx) / det;
    }
    let off = centre - cell.mean;
    let own = cell.c + gx * off.x + gy * off.y;
    var out = empty_cell();
    out.c = cell.w * own + (1.0 - cell.w) * coarse.c;
    out.w = 1.0;
    out.mean = centre;
    out.tx = gx;
    out.ty = gy;
    out.depth = cell.depth;
    out.material = cell.material;
    out.depth_var = cell.depth_var;
    out.material_var = cell.material_var;
    out.lo = min(cell.lo, coarse.lo);
    out.hi = max(cell.hi, coarse.hi);
    store_plane(vec2<u32>(c), out);
}

// Every pixel without a sample: level 1's planes times its proxy; only workgroups with one.
@compute @workgroup_size(8, 8)
fn push_pixels(@builtin(workgroup_id) g: vec3<u32>, @builtin(local_invocation_id) l: vec3<u32>) {
    push_block(listed(3u * g.x, l) * 2u, PUSH_PIXELS);
}

fn push_pixel(p: vec2<i32>, par: Parents) {
    if (!in_frame(p)) {
        return;
    }
    // The background and the samples are in place already (the sampling pass wrote the one,
    // shading and reuse the other): only pixels without a sample are written.
    let k = index_of(p);
    let f = flags[k];
    if ((f & FLAG_COVERED) == 0u || (f & (FLAG_SAMPLED | FLAG_REUSED)) != 0u) {
        return;
    }
    let nd = textureLoad(normal_distance, p, 0);
    let albedo = textureLoad(albedo_tex, p, 0);
    let key = vec2<f32>(nd.w, material_of(albedo));
    let coarse = coarse_plane(par, vec2<f32>(p) + 0.5, 0u, key);
    var lit = within_corners(coarse.c, par, vec2<f32>(p) + 0.5, 0u);
    if (coarse.lo <= coarse.hi) {
        lit = clamp(lit, vec3<f32>(coarse.lo), vec3<f32>(coarse.hi));
    }
    color[k] = vec4<f32>(max(lit * proxy(nd, albedo), vec3<f32>(0.0)), 1.0);
}
