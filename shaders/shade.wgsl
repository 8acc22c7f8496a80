// Shading pass: the frame's shading, run only where it is needed. `shade_list` runs over the
// compacted list (one invocation per sampled pixel, dispatched indirectly); `shade_grid` over
// the whole frame, shading every pixel in full mode and only sampled ones otherwise (the
// uncompacted variant the compaction is measured against).
//
// Every surface: GGX specular from the key light (shadowed) and the extra punctual lights
// (unshadowed), with the diffuse part scaled by what crosses the interface (common.wgsl).
// Opaque materials: Lambert + GGX, base colour tinted per vertex. Translucent materials, by
// the frame's rung (all from the same physical inputs σ's, σa, η and the same light):
//   opaque       the dipole's total diffuse reflectance as a BRDF albedo, the rough interface's
//                transmission in and out;
//   normal blur  the same with normals pre-blurred over the subsurface reach (seed 001 #6);
//   screen       irradiance blurred in screen space by the dipole profile (screen_diffusion);
//   hierarchical the dipole summed over a cut through the light-space photon pyramid (seed 000
//                eq. 10): a cluster is used when its extent < ε × its distance, or at the cut level;
//   brute force  the dipole summed over every photon (eq. 8): the model's reference.
// Radiance is reported ×π like the Lambert term (a white surface facing a unit light is 1).

@group(0) @binding(1) var normal_distance: texture_2d<f32>;
@group(0) @binding(2) var albedo_tex: texture_2d<f32>;
@group(0) @binding(3) var<storage, read> flags: array<u32>;
@group(0) @binding(4) var<storage, read> list: array<u32>;
// compact.wgsl's: [0] the samples listed, [4] where the band being shaded starts.
@group(0) @binding(5) var<storage, read> counter: array<u32, 8>;
@group(0) @binding(6) var<storage, read_write> out_color: array<vec4<f32>>;
@group(0) @binding(7) var<storage, read> materials: array<Material>;
@group(0) @binding(8) var blurred_normal_tex: texture_2d<f32>;
// The photon pyramid, three texels a node in rows of 256 nodes (pyramid::copy_to_texels).
@group(0) @binding(9) var node_texels: texture_2d<f32>;
@group(0) @binding(10) var<storage, read> diffused: array<vec4<f32>>;
@group(0) @binding(11) var irradiance_tex: texture_2d<f32>;
@group(0) @binding(12) var shadow_tex: texture_2d<f32>;
@group(0) @binding(13) var<storage, read> lights: array<PunctualLight>;
@group(0) @binding(14) var light_shadows: texture_2d<f32>;
// The coarse lattice's gathers (MODE_COARSE_GATHER): per sample the light with w = 1 where
// one was gathered, then the coverage.
@group(0) @binding(15) var<storage, read_write> coarse: array<vec4<f32>>;
@group(0) @binding(16) var tile_views: texture_2d<f32>;

// Diffuse `diffuse` and specular light from every extra punctual light (spot and point lights
// with shadow tiles are shadowed).
fn extra_lights(m: Material, f0: vec3<f32>, diffuse: vec3<f32>, n: vec3<f32>, v: vec3<f32>, x: vec3<f32>) -> vec3<f32> {
    var sum = vec3<f32>(0.0);
    for (var i = 0u; i < frame.light_count; i++) {
        let li = lights[i];
        let le = punctual_light(li, x);
        if (any(le[1] > vec3<f32>(0.0))) {
            sum += le[1] * punctual_shadow(light_shadows, tile_views, li, x, n) * surface_light(m, f0, diffuse, n, v, le[0]);
        }
    }
    return sum;
}

// Index of the first node of pyramid level `level` (level 0: the photon map itself).
fn level_offset(level: u32) -> u32 {
    let n = frame.photon_side;
    var offset = 0u;
    var side = n;
    for (var l = 0u; l < level; l++) {
        offset += side * side;
        side = max(side / 2u, 1u);
    }
    return offset;
}

fn level_side(level: u32) -> u32 {
    return max(frame.photon_side >> level, 1u);
}

// Distance (mm) at which a cluster's R_d is evaluated. A photon stands for the light entering a
// whole texel footprint, not a point: evaluating R_d at the distance to the footprint (centre
// distance softened by the photon's own radius) keeps shading points near a photon from seeing
// R_d's 1/r³ peak, which would turn a photon map coarser than the mean free path into dots.
// CPU twin: optics::dipole::softened_distance.
fn cluster_distance_mm(node: PhotonNode, x_o: vec3<f32>) -> f32 {
    let r = distance(node.pos_extent.xyz, x_o) * frame.mm_per_unit;
    let soft = PHOTON_SOFTENING * frame.photon_radius_mm;
    return sqrt(r * r + soft * soft);
}

// R_d is softened over this many photon radii: a kernel narrower than the photons' spacing
// sums to dots at the photons (CPU twin: optics::dipole::PHOTON_SOFTENING).
const PHOTON_SOFTENING: f32 = 1.77245385;
// Normals closer than ~25° count as one smooth patch for the coarse gather (CPU twin:
// optics::coarse_gather::COHERENT_COS).
const COHERENT_COS: f32 = 0.9;
// How far a lattice point may lie from the pixel's surface point, in softening lengths
// (CPU twin: optics::coarse_gather::REACH_OF_SOFTENING).
const REACH_OF_SOFTENING: f32 = 0.5;

// A single photon's softening radius (mm): its texel's footprint stretched by the surface's
// slant under the light (CPU twin: optics::dipole::leaf_softening).
fn leaf_softening_mm(node: PhotonNode) -> f32 {
    let radius = frame.photon_radius_mm;
    let extent_mm = node.pos_extent.w * frame.mm_per_unit;
    return PHOTON_SOFTENING * max(sqrt(radius * extent_mm / (0.70710678 * 1.77245385)), radius);
}

// One photon's R_d at x_o, softened by its own footprint and scaled back to its full energy.
fn leaf_rd(m: Material, node: PhotonNode, x_o: vec3<f32>) -> vec3<f32> {
    let r = distance(node.pos_extent.xyz, x_o) * frame.mm_per_unit;
    let soft = leaf_softening_mm(node);
    return dipole_rd(m, sqrt(r * r + soft * soft)) * softening_gain(m, soft);
}

// The light R_d returns beyond radius s (mm) of the entry point, per channel, closed form
// (CPU twin: optics::dipole::Dipole::reflectance_beyond).
fn reflectance_beyond(m: Material, s: f32) -> vec3<f32> {
    let dr = sqrt(s * s + m.z_r.xyz * m.z_r.xyz);
    let dv = sqrt(s * s + m.z_v.xyz * m.z_v.xyz);
    return 0.5 * m.alpha.xyz * (m.z_r.xyz * exp(-m.sigma_tr.xyz * dr) / dr + m.z_v.xyz * exp(-m.sigma_tr.xyz * dv) / dv);
}

// What a softened R_d is scaled by to keep its energy: R_d at √(r² + s²) returns only the
// light beyond s, so total / beyond (CPU twin: optics::dipole::Dipole::softening_gain).
fn softening_gain(m: Material, s: f32) -> vec3<f32> {
    let beyond = reflectance_beyond(m, s);
    let total = reflectance_beyond(m, 0.0);
    return select(vec3<f32>(1.0), max(total / beyond, vec3<f32>(1.0)), beyond > vec3<f32>(0.0));
}

// A gather's light, Σ R_d Φ, and how much of R_d's reach around the point the photons cover,
// Σ R_d A over the total diffuse reflectance (1 inside a lit region, ~½ at its edge, 0 far
// from it): radiosity's irradiance enters locally where they do not (see `shade`).
struct Gathered {
    light: vec3<f32>,
    coverage: vec3<f32>,
}

fn gathered(m: Material, light: vec3<f32>, rd_area: vec3<f32>) -> Gathered {
    let total = reflectance_beyond(m, 0.0);
    let coverage = select(vec3<f32>(1.0), rd_area / total, total > vec3<f32>(0.0));
    return Gathered(light, coverage);
}

fn node_at(i: u32) -> PhotonNode {
    let p = vec2<i32>(i32(3u * (i & 255u)), i32(i >> 8u));
    let a = textureLoad(node_texels, p, 0);
    let b = textureLoad(node_texels, p + vec2<i32>(1, 0), 0);
    return PhotonNode(a, b, textureLoad(node_texels, p + vec2<i32>(2, 0), 0));
}

// Σ R_d(|x_c − x_o|) Φ_c over every photon (eq. 8).
fn gather_all(x_o: vec3<f32>, m: Material) -> Gathered {
    let n = frame.photon_side;
    var sum = vec3<f32>(0.0);
    var rd_area = vec3<f32>(0.0);
    for (var i = 0u; i < n * n; i++) {
        let node = node_at(i);
        if (node.flux.w > 0.0) {
            let rd = leaf_rd(m, node, x_o);
            sum += rd * node.flux.rgb;
            rd_area += rd * node.area.x;
        }
    }
    return gathered(m, sum, rd_area);
}

// Σ R_d Φ over a cut through the pyramid (eq. 10), depth first from the start level.
fn gather_cut(x_o: vec3<f32>, m: Material) -> Gathered {
    let start = frame.photon_start_level;
    let cut_level = frame.cut_level;
    let eps = frame.cut_epsilon;
    let roots = level_side(start) * level_side(start);
    // Every cluster is softened by the same photon radius: one gain for all of them.
    let cluster_gain = softening_gain(m, PHOTON_SOFTENING * frame.photon_radius_mm);
    var sum = vec3<f32>(0.0);
    var rd_area = vec3<f32>(0.0);
    // Depth first without a stack: the quad-tree is implicit, so the next node is the previous
    // sibling (children are visited 3, 2, 1, 0, the order a stack of 0..3 pops them) or an
    // ancestor's. A per-pixel stack array costs a software adapter a gather and a scatter per
    // push and pop.
    let root_side = level_side(start);
    for (var r = 0u; r < roots; r++) {
        var level = start;
        var q = vec2<u32>(r % root_side, r / root_side);
        var walking = true;
        while (walking) {
            let node = node_at(level_offset(level) + q.y * level_side(level) + q.x);
            var descend = false;
            if (node.flux.w > 0.0) {
                let d = distance(node.pos_extent.xyz, x_o);
                if (level == 0u) {
                    let rd = leaf_rd(m, node, x_o);
                    sum += rd * node.flux.rgb;
                    rd_area += rd * node.area.x;
                } else if (level <= cut_level || node.pos_extent.w < eps * d) {
                    let rd = dipole_rd(m, cluster_distance_mm(node, x_o)) * cluster_gain;
                    sum += rd * node.flux.rgb;
                    rd_area += rd * node.area.x;
                } else {
                    descend = true;
                }
            }
            if (descend) {
                level -= 1u;
                q = 2u * q + vec2<u32>(1u);
                continue;
            }
            loop {
                if (level == start) {
                    walking = false;
                    break;
                }
                let k = (q.x & 1u) + 2u * (q.y & 1u);
                if (k > 0u) {
                    q = (q & vec2<u32>(~1u)) + vec2<u32>((k - 1u) & 1u, (k - 1u) >> 1u);
                    break;
                }
                q /= 2u;
                level += 1u;
            }
        }
    }
    return gathered(m, sum, rd_area);
}

// The rung a material is shaded on this frame: opaque without subsurface light, or before
// the photon pyramid is ready for the photon rungs.
fn rung_for(m: Material) -> u32 {
    if (m.subsurface == 0u || (frame.rung >= RUNG_HIERARCHICAL && frame.pyramid_ready == 0u)) {
        return RUNG_OPAQUE;
    }
    return frame.rung;
}

// A photon rung's gather at x, per pixel.
fn gather_at(x: vec3<f32>, m: Material, rung: u32) -> Gathered {
    if (rung == RUNG_BRUTE_FORCE && on_rung(RUNG_BRUTE_FORCE)) {
        return gather_all(x, m);
    }
    return gather_cut(x, m);
}

// Seed 000's screen-space hierarchy on the photon gathers. The gather is a function of the
// surface point alone, Σ R_d(|x_c − x|) Φ_c, smooth over the photons' softening length, so
// where the pixels of a 2×2 block lie on one smooth patch of one material it is gathered at
// the lattice point (2i, 2j) and interpolated between lattice points; elsewhere (silhouettes,
// creases, material edges, a lattice point on another surface) the pixel gathers itself.
// CPU twin of the coherence test: `optics::coarse_gather`.

fn coarse_width() -> i32 {
    return (i32(frame.width) + 1) / 2;
}

// What pixel `q` sees: the surface point, its normal and its material id (−1: background).
struct SurfacePoint {
    x: vec3<f32>,
    n: vec3<f32>,
    id: i32,
}

fn surface_at(q: vec2<i32>) -> SurfacePoint {
    let a = textureLoad(albedo_tex, q, 0);
    if (a.a <= 0.0) {
        return SurfacePoint(vec3<f32>(0.0), vec3<f32>(0.0), -1);
    }
    let nd = textureLoad(normal_distance, q, 0);
    let x = frame.eye + view_ray(vec2<f32>(q) + 0.5) * nd.w;
    return SurfacePoint(x, nd.xyz, i32(material_id(a.a)));
}

@compute @workgroup_size(8, 8)
fn gather_coarse(@builtin(global_invocation_id) id: vec3<u32>) {
    // Lattice rows for the pixel rows shade_rows.x.. (see shade::coarse_dispatch).
    let c = vec2<i32>(id.xy) + vec2<i32>(0, i32(frame.shade_rows.x / 2u));
    let last = min(i32((max(frame.shade_rows.y, 1u) - 1u) / 2u) + 1, (i32(frame.height) + 1) / 2 - 1);
    if (c.x >= coarse_width() || c.y > last) {
        return;
    }
    let k = 2u * u32(c.y * coarse_width() + c.x);
    coarse[k] = vec4<f32>(0.0);
    coarse[k + 1u] = vec4<f32>(0.0);
    let s = surface_at(2 * c);
    if (s.id < 0) {
        return;
    }
    let m = materials[u32(s.id)];
    let rung = rung_for(m);
    if (m.kind == 0u || m.kind == 2u || rung < RUNG_HIERARCHICAL) {
        return;
    }
    let g = gather_at(s.x, m, rung);
    coarse[k] = vec4<f32>(g.light, 1.0);
    coarse[k + 1u] = vec4<f32>(g.coverage, 0.0);
}

// The gather at pixel p (surface point x, normal n, material `id`) from the lattice, when
// every lattice point it interpolates from was gathered on the same material within the
// photons' softening length (× REACH_OF_SOFTENING) of x with a normal within ~25° of n;
// `ok` false otherwise.
struct Interpolated {
    g: Gathered,
    ok: bool,
}

fn interpolated(p: vec2<i32>, x: vec3<f32>, n: vec3<f32>, id: u32) -> Interpolated {
    var out = Interpolated(Gathered(vec3<f32>(0.0), vec3<f32>(0.0)), false);
    let base = p / 2;
    let odd = p - 2 * base;
    // Bilinear on the lattice: a pixel between two lattice points weighs each ½, one inside a
    // cell each of four ¼; a pixel on a lattice point is that point's own gather.
    let w = select(1.0, 0.5, odd.x == 1) * select(1.0, 0.5, odd.y == 1);
    // Lattice points within half the photons' softening length of x: the gather changes
    // little over that, so a straight blend misses by ~2% at worst (tests/coarse_gather.rs).
    let reach = max(REACH_OF_SOFTENING * PHOTON_SOFTENING * frame.photon_radius_mm / frame.mm_per_unit, 1e-12);
    for (var j = 0; j < 4; j++) {
        let o = vec2<i32>(j & 1, j >> 1);
        if (o.x > odd.x || o.y > odd.y) {
            continue;
        }
        let c = base + o;
        if (2 * c.x >= i32(frame.width) || 2 * c.y >= i32(frame.height)) {
            return out;
        }
        let k = 2u * u32(c.y * coarse_width() + c.x);
        let light = coarse[k];
        let s = surface_at(2 * c);
        if (light.w == 0.0 || s.id != i32(id) || distance(s.x, x) > reach || dot(s.n, n) < COHERENT_COS) {
            return out;
        }
        out.g.light += w * light.rgb;
        out.g.coverage += w * coarse[k + 1u].rgb;
    }
    out.ok = true;
    return out;
}

// The kinds of material the scene has (KIND_* bits; all when not specialised). A kind it has
// none of is compiled out: the software adapter runs every branch of `shade` for each row of 8
// pixels whether or not one takes it, and the translucent one was half of an opaque scene's
// shading (`opaque`, 1280×720: 136–140 → 67 ms without it).
override SCENE_KINDS: u32 = 7u;

fn scene_has(kind: u32) -> bool {
    return (SCENE_KINDS & kind) != 0u;
}

// The frame's rung (`frame.rung`; NOT_SPECIALISED: any). A material is shaded on it or on the
// opaque rung (`rung_for`), so the other rungs' branches are compiled out: about 3% of
// gallery's shading at 1280×720, `full` and `balanced`, on the software adapter (noisy).
override FRAME_RUNG: u32 = NOT_SPECIALISED;

fn on_rung(r: u32) -> bool {
    return FRAME_RUNG == NOT_SPECIALISED || FRAME_RUNG == r;
}

fn shade(p: vec2<i32>) {
    let a = textureLoad(albedo_tex, p, 0);
    var rgb = frame.background;
    if (a.a > 0.0) {
        let nd = textureLoad(normal_distance, p, 0);
        let m = materials[material_id(a.a)];
        let n = nd.xyz;
        let ray = view_ray(vec2<f32>(p) + 0.5);
        let v = -ray;
        let x = frame.eye + ray * nd.w;
        let l = frame.to_light;
        let key = frame.light * shadow_factor(shadow_tex, x, n);
        let cos_i = dot(n, l);
        // Radiosity's irradiance (direct from area lights + interreflected), zero without it;
        // and the occlusion map's ambient occlusion (1 without one), which dims the ambient sky.
        let irr = textureLoad(irradiance_tex, p, 0);
        let gi = irr.rgb;
        let sky = frame.ambient * irr.a;
        let rung = rung_for(m);
        if (m.kind == 2u) {
            // An area light shows its own exitance.
            rgb = m.albedo.rgb;
        } else if (m.kind == 0u && scene_has(KIND_OPAQUE)) {
            // The G-buffer's albedo is the base colour times the vertex tint.
            let diffuse = a.rgb * (1.0 - m.surface.y);
            let f0 = specular_f0(m, a.rgb);
            // The ambient light is a uniform sky: the lobe returns E(μ_o) of it, the diffuse
            // part what crosses the interface both ways, 1 − E(μ_o) out and the hemisphere's
            // average 1 − E_avg in (so metals are not black where no light hits).
            let e_o = lobe_albedo(m, f0, dot(n, v));
            let through = diffuse * (1.0 - e_o) * (1.0 - lobe_average(m, f0));
            let ambient = frame.light * sky * (through + e_o);
            // Radiosity's irradiance is treated like the sky: the lobe reflects E(μ_o) of it (a
            // glossy object shows the lit floor under it), the diffuse part what crosses.
            rgb = key * surface_light(m, f0, diffuse, n, v, l) + extra_lights(m, f0, diffuse, n, v, x)
                + gi * (through + e_o) + ambient;
        } else if (m.kind == 1u && scene_has(KIND_TRANSLUCENT)) {
            let f0 = vec3<f32>(m.surface.z);
            let e_o = lobe_albedo(m, f0, dot(n, v));
            // The lobe reflects the sky and radiosity's irradiance alike (see the opaque case).
            let ambient = (m.albedo.rgb + e_o) * frame.light * sky + e_o * gi;
            let t_out = transmitted(m, dot(n, v));
            // The interface's reflection of the key light; the extra lights' reflection and
            // diffuse part below (the photon rungs carry some of the latter).
            let surface = key * max(cos_i, 0.0) * specular_lobe(m, f0, n, v, l);
            var extra_diffuse = m.albedo.rgb;
            var body: vec3<f32>;
            if (rung == RUNG_OPAQUE) {
                body = m.albedo.rgb * (key * max(cos_i, 0.0) * transmitted(m, cos_i) + gi) * t_out;
            } else if (rung == RUNG_NORMAL_BLUR && on_rung(RUNG_NORMAL_BLUR)) {
                let nb = textureLoad(blurred_normal_tex, p, 0).xyz * 2.0 - 1.0;
                let len = max(length(nb), 1e-6);
                let cos_b = dot(nb, l);
                body = m.albedo.rgb * (key * max(cos_b, 0.0) * transmitted(m, cos_b / len) + gi) * t_out;
            } else if (rung == RUNG_SCREEN && on_rung(RUNG_SCREEN)) {
                body = m.albedo.rgb * (diffused[index_of(p)].rgb + gi) * t_out;
            } else if (on_rung(RUNG_HIERARCHICAL) || on_rung(RUNG_BRUTE_FORCE)) {
                // The photons carry radiosity's irradiance only where they enter, on the side
                // facing the key light; what R_d's reach around x they do not cover (a floor's
                // bounce onto an object's underside) enters locally, through the total diffuse
                // reflectance as on the opaque rung, so the two meet without a seam.
                var g: Gathered;
                var from_lattice = false;
                if (has_mode(MODE_COARSE_GATHER)) {
                    let i = interpolated(p, x, n, material_id(a.a));
                    g = i.g;
                    from_lattice = i.ok;
                }
                if (!from_lattice) {
                    g = gather_at(x, m, rung);
                }
                // The extra lights' diffuse part likewise: the photons carry what enters where
                // they are (photons.wgsl), the rest enters locally.
                let uncovered = clamp(vec3<f32>(1.0) - g.coverage, vec3<f32>(0.0), vec3<f32>(1.0));
                body = (g.light + m.albedo.rgb * gi * uncovered) * t_out;
                extra_diffuse = m.albedo.rgb * uncovered;
            }
            rgb = body + ambient + surface + extra_lights(m, f0, extra_diffuse, n, v, x);
        }
    }
    out_color[index_of(p)] = vec4<f32>(rgb, 0.0);
}

@compute @workgroup_size(64)
fn shade_list(@builtin(global_invocation_id) id: vec3<u32>) {
    let start = counter[4];
    if (id.x >= counter[0] - start) {
        return;
    }
    shade(unpack_seed(list[start + id.x]));
}

@compute @workgroup_size(8, 8)
fn shade_grid(@builtin(global_invocation_id) id: vec3<u32>) {
    // A slice's dispatch covers rows shade_rows.x.. (the whole frame when it is not sliced).
    let p = vec2<i32>(id.xy + vec2<u32>(0u, frame.shade_rows.x));
    if (!in_frame(p) || u32(p.y) >= frame.shade_rows.y) {
        return;
    }
    if (has_mode(MODE_FOVEATED) && (flags[index_of(p)] & FLAG_SAMPLED) == 0u) {
        return;
    }
    shade(p);
}
