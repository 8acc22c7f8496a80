// Photon pyramid (seed 000's quad-tree light hierarchy): level 0 holds one node per photon with
// its flux Φ = F_t(η, n·l) I A⊥ (the cosine cancels for an orthographic light: the texel's
// footprint on the surface grows as 1/cos while the irradiance falls as cos); each coarser
// level sums four children's flux, places the node at their flux-weighted mean position, and
// records its extent: the radius around that point containing the children's extents.

// Binding 0 is the shared prelude's frame uniform, unused here.
// x: level being built; y: its side; z: offset of its first node; w: offset of the level below.
@group(0) @binding(1) var<uniform> level: vec4<u32>;
@group(0) @binding(2) var<uniform> photons: Photons;
@group(0) @binding(3) var<storage, read> materials: array<Material>;
@group(0) @binding(4) var photon_position: texture_2d<f32>;
@group(0) @binding(5) var photon_normal: texture_2d<f32>;
@group(0) @binding(6) var<storage, read_write> nodes: array<PhotonNode>;
@group(0) @binding(7) var photon_irradiance: texture_2d<f32>;
@group(0) @binding(8) var shadow_map: texture_2d<f32>;

// How much of the key light reaches a photon: an opaque object between the light and a
// translucent one keeps its light out (the photon map itself only holds translucent surfaces).
fn photon_visibility(x: vec3<f32>, n: vec3<f32>) -> f32 {
    let sp = photons.shadow_params;
    if (sp.z == 0.0) {
        return 1.0;
    }
    let p = photons.shadow_view_proj * vec4<f32>(x + n * sp.y, 1.0);
    let uv = vec2<f32>(p.x * 0.5 + 0.5, 0.5 - p.y * 0.5) * sp.w - 0.5;
    return pcf(shadow_map, uv, p.z - sp.x, vec2<i32>(0), vec2<i32>(i32(sp.w) - 1));
}

@compute @workgroup_size(8, 8)
fn leaves(@builtin(global_invocation_id) id: vec3<u32>) {
    let side = level.y;
    if (id.x >= side || id.y >= side) {
        return;
    }
    let p = vec2<i32>(id.xy);
    let pos = textureLoad(photon_position, p, 0);
    let nrm = textureLoad(photon_normal, p, 0);
    var node: PhotonNode;
    node.pos_extent = vec4<f32>(pos.xyz, 0.0);
    node.flux = vec4<f32>(0.0);
    node.area = vec4<f32>(0.0);
    if (pos.w > 0.5 && nrm.w > 0.5) {
        let m = materials[u32(round(nrm.w)) - 1u];
        let cos_i = dot(nrm.xyz, photons.to_light.xyz);
        let seen = photon_visibility(pos.xyz, nrm.xyz);
        var flux = photons.light.rgb * seen * transmitted_always(m, cos_i) * photons.params.y;
        // Radiosity's irradiance arrives from every direction: it enters the texel's whole
        // footprint on the surface (A⊥ / cos, the slant bounded as for the extent), through
        // the interface's transmission at 60° incidence, the cosine-weighted hemisphere's median.
        let gi = textureLoad(photon_irradiance, p, 0).rgb;
        flux += gi * transmitted_always(m, 0.5) * photons.params.y / max(cos_i, 0.2);
        // Half the texel diagonal, stretched by the slant of the surface under the light.
        let extent = 0.7071 * photons.params.z / max(cos_i, 0.2);
        node.pos_extent = vec4<f32>(pos.xyz, extent);
        node.flux = vec4<f32>(flux, dot(flux, vec3<f32>(0.2126, 0.7152, 0.0722)));
        node.area = vec4<f32>(photons.params.y / max(cos_i, 0.2), 0.0, 0.0, 0.0);
    }
    nodes[level.z + id.y * side + id.x] = node;
}

@compute @workgroup_size(8, 8)
fn reduce(@builtin(global_invocation_id) id: vec3<u32>) {
    let side = level.y;
    if (id.x >= side || id.y >= side) {
        return;
    }
    let child_side = side * 2u;
    var children: array<PhotonNode, 4>;
    var flux = vec4<f32>(0.0);
    var area = vec4<f32>(0.0);
    var centre = vec3<f32>(0.0);
    for (var k = 0u; k < 4u; k++) {
        let c = id.xy * 2u + vec2<u32>(k & 1u, k >> 1u);
        children[k] = nodes[level.w + c.y * child_side + c.x];
        flux += children[k].flux;
        area += children[k].area;
        centre += children[k].pos_extent.xyz * children[k].flux.w;
    }
    var node: PhotonNode;
    node.flux = flux;
    node.area = area;
    node.pos_extent = vec4<f32>(0.0);
    if (flux.w > 0.0) {
        centre /= flux.w;
        var extent = 0.0;
        for (var k = 0u; k < 4u; k++) {
            if (children[k].flux.w > 0.0) {
                extent = max(extent, distance(children[k].pos_extent.xyz, centre) + children[k].pos_extent.w);
            }
        }
        node.pos_extent = vec4<f32>(centre, extent);
    }
    nodes[level.z + id.y * side + id.x] = node;
}
