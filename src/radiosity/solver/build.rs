//! Turning surfaces into patches, elements and receiving samples.

use glam::Vec3;

use super::*;

/// A mesh's geometry as the solver reads it.
pub(super) struct MeshSource<'a> {
    pub positions: &'a [Vec3],
    pub normals: &'a [Vec3],
    pub indices: &'a [u32],
}

impl Solver {
    pub(super) fn add_quad(
        &mut self,
        index: usize,
        corners: [Vec3; 4],
        cells: [u32; 2],
        max_depth: u32,
        reflectance: Vec3,
        emission: Vec3,
    ) -> Result<(), RadiosityError> {
        check_values(index, reflectance, emission)?;
        let (u, v) = (corners[1] - corners[0], corners[3] - corners[0]);
        let normal = u.cross(v);
        let closes = (corners[0] + u + v - corners[2]).length() <= 1e-4 * (u.length() + v.length());
        if !(normal.length() > 1e-12 && closes && cells[0] > 0 && cells[1] > 0 && max_depth <= 8) {
            return Err(RadiosityError::BadQuad(index));
        }
        let normal = normal.normalize();
        let surface = index as u32;
        let info = QuadInfo {
            corners,
            normal,
            lattice: lattice(cells, max_depth),
            max_depth,
            first_out: self.outputs,
            points: HashMap::new(),
        };
        self.quads.insert(surface, info);
        let size = 1u32 << max_depth;
        let emitter = luminance(emission) > 0.0;
        let cell_area = u.cross(v).length() / (cells[0] * cells[1]) as f32;
        for j in 0..cells[1] {
            for i in 0..cells[0] {
                let cell = Cell {
                    surface,
                    i0: i * size,
                    j0: j * size,
                    size,
                    depth: 0,
                };
                let verts = self.cell_vertices(cell, None);
                let patch = self.patches.len() as u32;
                let element = self.elements.len() as u32;
                let centre = self.cell_centre(cell);
                let sample = self.sample(centre, normal);
                self.elements.push(Element {
                    patch,
                    verts,
                    centre: sample,
                    area: cell_area,
                    // Emitters absorb what reaches them: a lamp is not a mirror for its room.
                    reflectance: if emitter { Vec3::ZERO } else { reflectance },
                    radiosity: Vec3::ZERO,
                    unshot: emission,
                    cell: Some(cell),
                });
                let (c0, cu, cv) = (
                    self.lattice_point(surface, cell.i0 as f32, cell.j0 as f32),
                    self.lattice_point(surface, (cell.i0 + size) as f32, cell.j0 as f32),
                    self.lattice_point(surface, cell.i0 as f32, (cell.j0 + size) as f32),
                );
                let facets = vec![Facet {
                    centre,
                    normal,
                    area: cell_area,
                    corners: [c0, cu, cu + cv - c0, cv],
                    sides: 4,
                }];
                self.patches.push(Patch {
                    leaves: vec![element],
                    area: cell_area,
                    target: centre + normal * (2.0 * self.margin),
                    facets,
                    emitter,
                });
                self.emitted += luminance(emission) * f64::from(cell_area);
            }
        }
        Ok(())
    }

    /// The key light's first bounce as unshot radiosity: each element it reaches (its centre
    /// facing the light, a shadow ray to it unblocked) reflects ρ·E·cos θ. The light itself
    /// counts as emitted power, so convergence is judged against what it brought in.
    pub(super) fn seed_sun(&mut self, sun: super::super::Sun) {
        let l = sun.to_light.normalize_or_zero();
        // Four times the scene's size (the margin is 1e-4 of it): the ray leaves its bounds.
        let reach = 4.0 * self.margin * 1e4;
        let mut seeded = Vec::new();
        for (i, e) in self.elements.iter().enumerate() {
            let centre = &self.vertices[e.centre as usize];
            let cos = centre.normal.dot(l);
            if !(cos > 0.0) || e.reflectance == Vec3::ZERO {
                continue;
            }
            if self
                .bvh
                .occluded(centre.origin, centre.origin + l * reach, self.margin)
            {
                continue;
            }
            seeded.push((i, e.reflectance * sun.irradiance * cos));
        }
        for (i, b) in seeded {
            let e = &mut self.elements[i];
            e.radiosity += b;
            e.unshot += b;
            self.emitted += luminance(b) * f64::from(e.area);
        }
    }

    pub(super) fn add_mesh(
        &mut self,
        index: usize,
        mesh: MeshSource,
        reflectance: Vec3,
        emission: Vec3,
        per_patch: usize,
    ) -> Result<(), RadiosityError> {
        check_values(index, reflectance, emission)?;
        let MeshSource {
            positions,
            normals,
            indices,
        } = mesh;
        let emitter = luminance(emission) > 0.0;
        if normals.len() != positions.len()
            || indices.iter().any(|&i| i as usize >= positions.len())
        {
            return Err(RadiosityError::BadMesh(index));
        }
        let first = self.vertices.len() as u32;
        let inward = boundary_inward(positions, indices);
        for (k, (p, n)) in positions.iter().zip(normals).enumerate() {
            let normal = n.try_normalize().unwrap_or(Vec3::Y);
            let along = inward[k] - normal * inward[k].dot(normal);
            self.vertices.push(Vertex {
                pos: *p,
                normal,
                total: Vec3::ZERO,
                direct: Vec3::ZERO,
                out: self.outputs + k,
                origin: *p + along * BOUNDARY_NUDGE + normal * self.margin,
            });
        }
        // Neighbouring triangles shoot together: sort by a Morton code of the centroid.
        let (lo, hi) = positions.iter().fold(
            (Vec3::splat(f32::MAX), Vec3::splat(f32::MIN)),
            |(l, h), p| (l.min(*p), h.max(*p)),
        );
        let extent = (hi - lo).max(Vec3::splat(1e-12));
        let mut tris: Vec<(u64, [u32; 3])> = indices
            .chunks_exact(3)
            .map(|t| {
                let c = (positions[t[0] as usize]
                    + positions[t[1] as usize]
                    + positions[t[2] as usize])
                    / 3.0;
                let q = ((c - lo) / extent * 1023.0).clamp(Vec3::ZERO, Vec3::splat(1023.0));
                (
                    morton(q.x as u32, q.y as u32, q.z as u32),
                    [t[0], t[1], t[2]],
                )
            })
            .collect();
        tris.sort_by_key(|t| t.0);
        for group in tris.chunks(per_patch.max(1)) {
            let patch = self.patches.len() as u32;
            let mut facets = Vec::new();
            let mut leaves = Vec::new();
            let mut centroid = Vec3::ZERO;
            let mut area = 0.0;
            for (_, t) in group {
                let [a, b, c] = t.map(|i| positions[i as usize]);
                let n = (b - a).cross(c - a);
                let tri_area = 0.5 * n.length();
                if !(tri_area > 0.0) {
                    continue;
                }
                leaves.push(self.elements.len() as u32);
                let centre = self.sample((a + b + c) / 3.0, n.normalize());
                self.elements.push(Element {
                    patch,
                    verts: [first + t[0], first + t[1], first + t[2], first + t[2]],
                    centre,
                    area: tri_area,
                    // As a quad lamp: an emitting mesh absorbs what reaches it.
                    reflectance: if emitter { Vec3::ZERO } else { reflectance },
                    radiosity: Vec3::ZERO,
                    unshot: emission,
                    cell: None,
                });
                facets.push(Facet {
                    centre: (a + b + c) / 3.0,
                    corners: [a, b, c, c],
                    sides: 3,
                    normal: n.normalize(),
                    area: tri_area,
                });
                centroid += (a + b + c) / 3.0 * tri_area;
                area += tri_area;
                self.emitted += luminance(emission) * f64::from(tri_area);
            }
            if leaves.is_empty() {
                continue;
            }
            centroid /= area;
            // Aim at the member triangle nearest the centroid: a curved cluster's centroid lies
            // inside the object, where every shadow ray would hit the surface first.
            let (mut best, mut best_d) = (Vec3::ZERO, f32::MAX);
            for &e in &leaves {
                let el = &self.elements[e as usize];
                let c = self.vertices[el.centre as usize].pos;
                let n = facets[leaves.iter().position(|x| *x == e).unwrap_or(0)].normal;
                if c.distance(centroid) < best_d {
                    best_d = c.distance(centroid);
                    best = c + n * (2.0 * self.margin);
                }
            }
            self.patches.push(Patch {
                leaves,
                area,
                target: best,
                facets,
                emitter,
            });
        }
        Ok(())
    }

    pub(super) fn lattice_point(&self, surface: u32, i: f32, j: f32) -> Vec3 {
        let q = &self.quads[&surface];
        let [c0, c1, _, c3] = q.corners;
        c0 + (c1 - c0) * (i / q.lattice[0] as f32) + (c3 - c0) * (j / q.lattice[1] as f32)
    }

    pub(super) fn cell_centre(&self, c: Cell) -> Vec3 {
        let half = c.size as f32 / 2.0;
        self.lattice_point(c.surface, c.i0 as f32 + half, c.j0 as f32 + half)
    }

    /// A receiving sample that is not a display vertex.
    pub(super) fn sample(&mut self, pos: Vec3, normal: Vec3) -> u32 {
        self.vertices.push(Vertex {
            pos,
            normal,
            total: Vec3::ZERO,
            direct: Vec3::ZERO,
            out: NO_OUTPUT,
            origin: pos + normal * self.margin,
        });
        (self.vertices.len() - 1) as u32
    }

    /// The vertex at lattice point (i, j), created on first use with the irradiance a parent
    /// element's bilinear interpolation gives there.
    pub(super) fn lattice_vertex(
        &mut self,
        surface: u32,
        i: u32,
        j: u32,
        parent: Option<(&[u32; 4], f32, f32)>,
    ) -> u32 {
        if let Some(&v) = self.quads[&surface].points.get(&(i, j)) {
            return v;
        }
        let (total, direct) = match parent {
            Some((c, s, t)) => {
                let lerp = |f: &dyn Fn(&Vertex) -> Vec3| {
                    let [a, b, cc, d] = c.map(|k| f(&self.vertices[k as usize]));
                    (a * (1.0 - s) + b * s) * (1.0 - t) + (d * (1.0 - s) + cc * s) * t
                };
                (lerp(&|v| v.total), lerp(&|v| v.direct))
            }
            None => (Vec3::ZERO, Vec3::ZERO),
        };
        let pos = self.lattice_point(surface, i as f32, j as f32);
        let q = &self.quads[&surface];
        let out = q.first_out + (j * (q.lattice[0] + 1) + i) as usize;
        let id = self.vertices.len() as u32;
        let [c0, _, c2, _] = q.corners;
        let inward = ((c0 + c2) / 2.0 - pos).normalize_or_zero();
        self.vertices.push(Vertex {
            pos,
            normal: q.normal,
            total,
            direct,
            out,
            origin: pos + (q.normal + inward * 2.0) * self.margin,
        });
        if let Some(q) = self.quads.get_mut(&surface) {
            q.points.insert((i, j), id);
        }
        id
    }

    /// Corner vertices of a cell, counter-clockwise from (i0, j0).
    pub(super) fn cell_vertices(&mut self, c: Cell, parent: Option<(&[u32; 4], Cell)>) -> [u32; 4] {
        let corners = [
            (c.i0, c.j0),
            (c.i0 + c.size, c.j0),
            (c.i0 + c.size, c.j0 + c.size),
            (c.i0, c.j0 + c.size),
        ];
        corners.map(|(i, j)| {
            let at = parent.map(|(pv, p)| {
                let s = (i - p.i0) as f32 / p.size as f32;
                let t = (j - p.j0) as f32 / p.size as f32;
                (pv, s, t)
            });
            self.lattice_vertex(c.surface, i, j, at)
        })
    }
}

/// How far towards its triangles' centroids a vertex on an open mesh's boundary receives.
const BOUNDARY_NUDGE: f32 = 0.25;

/// Per vertex: from it to the mean centroid of its triangles if it lies on the mesh's boundary
/// (an edge only one triangle uses), else zero. A wall's edge vertex sits in the plane of the
/// wall it meets, which it sees edge-on: received there, its light lacked that whole wall and
/// the frame drew a dark seam a cell wide along every joint of a glTF room. Nudged inside, it
/// receives what the strip of wall it stands for receives. A closed mesh has no boundary.
fn boundary_inward(positions: &[Vec3], indices: &[u32]) -> Vec<Vec3> {
    let mut uses: HashMap<(u32, u32), u32> = HashMap::new();
    for t in indices.chunks_exact(3) {
        for (a, b) in [(t[0], t[1]), (t[1], t[2]), (t[2], t[0])] {
            *uses.entry((a.min(b), a.max(b))).or_default() += 1;
        }
    }
    let mut boundary = vec![false; positions.len()];
    for ((a, b), n) in uses {
        if n == 1 {
            boundary[a as usize] = true;
            boundary[b as usize] = true;
        }
    }
    let mut sum = vec![(Vec3::ZERO, 0u32); positions.len()];
    for t in indices.chunks_exact(3) {
        let c =
            (positions[t[0] as usize] + positions[t[1] as usize] + positions[t[2] as usize]) / 3.0;
        for &v in t {
            let s = &mut sum[v as usize];
            s.0 += c;
            s.1 += 1;
        }
    }
    positions
        .iter()
        .zip(sum)
        .zip(boundary)
        .map(|((p, (c, n)), edge)| {
            if edge && n > 0 {
                c / n as f32 - *p
            } else {
                Vec3::ZERO
            }
        })
        .collect()
}

fn check_values(index: usize, reflectance: Vec3, emission: Vec3) -> Result<(), RadiosityError> {
    let ok = reflectance.is_finite()
        && emission.is_finite()
        && reflectance.min_element() >= 0.0
        && reflectance.max_element() <= 1.0
        && emission.min_element() >= 0.0;
    if ok {
        Ok(())
    } else {
        Err(RadiosityError::BadValue(index))
    }
}

fn morton(x: u32, y: u32, z: u32) -> u64 {
    let spread = |v: u32| {
        let mut v = u64::from(v) & 0x3ff;
        v = (v | (v << 16)) & 0x030000ff;
        v = (v | (v << 8)) & 0x0300f00f;
        v = (v | (v << 4)) & 0x030c30c3;
        (v | (v << 2)) & 0x09249249
    };
    spread(x) | (spread(y) << 1) | (spread(z) << 2)
}
