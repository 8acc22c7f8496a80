//! Form factors with visibility from a shooting patch to every receiver: per vertex (what
//! the frame shows) and per element (what carries energy on).

use std::sync::Arc;

use glam::Vec3;

use super::*;

impl Solver {
    /// F̄(e → p) for every leaf element: the factor at its centre, or, for an element near the
    /// shooter (where irradiance varies across it), the mean over a grid of samples inside it.
    /// One sample per element would break reciprocity by ~20% between touching patches.
    pub(super) fn element_factors(&self, p: usize, factors: &[f32]) -> Vec<(u32, f32)> {
        let patch = &self.patches[p];
        let cube = self.cube_for(p);
        // Sampled a margin off the surface, as vertices are: on it, a point coplanar with the
        // shooter sits on its facets' planes to within rounding, and the sign of that
        // rounding decided whether it saw a whole hemisphere of them.
        let sampled = |pos: Vec3, normal: Vec3| {
            let origin = pos + normal * self.margin;
            let f = point_to_patch(origin, normal, &patch.facets);
            let blocked = f > 0.0 && self.blocked(cube.as_deref(), origin, patch.target);
            if blocked {
                0.0
            } else {
                f
            }
        };
        let mut out = Vec::new();
        for (qi, q) in self.patches.iter().enumerate() {
            // A patch does not light itself (flat, or a mesh cluster nearly so).
            if qi == p {
                out.extend(q.leaves.iter().map(|&e| (e, 0.0)));
                continue;
            }
            for &e in &q.leaves {
                let el = &self.elements[e as usize];
                let centre = &self.vertices[el.centre as usize];
                let r2 = centre.pos.distance_squared(patch.target);
                if r2 >= NEAR_SAMPLES * el.area.max(patch.area) {
                    out.push((e, factors[el.centre as usize]));
                    continue;
                }
                let mean = match el.cell {
                    Some(c) => {
                        let n = QUAD_SAMPLES;
                        let mut sum = 0.0;
                        for k in 0..n * n {
                            let step = c.size as f32 / n as f32;
                            let i = c.i0 as f32 + ((k % n) as f32 + 0.5) * step;
                            let j = c.j0 as f32 + ((k / n) as f32 + 0.5) * step;
                            sum += sampled(self.lattice_point(c.surface, i, j), centre.normal);
                        }
                        sum / (n * n) as f32
                    }
                    None => {
                        let [a, b, c] = [0, 1, 2].map(|k| self.vertices[el.verts[k] as usize].pos);
                        let points = [(a, b, c), (b, c, a), (c, a, b)];
                        points
                            .iter()
                            .map(|(x, y, z)| {
                                sampled(*x * (2.0 / 3.0) + (*y + *z) / 6.0, centre.normal)
                            })
                            .sum::<f32>()
                            / 3.0
                    }
                };
                out.push((e, mean));
            }
        }
        out
    }

    /// The depth cube around patch p for this shot, when that is the visibility in use.
    pub(super) fn cube_for(&self, p: usize) -> Option<Arc<DepthCube>> {
        let Visibility::Cube { resolution } = self.options.visibility else {
            return None;
        };
        let mut slot = self.cube.lock().unwrap_or_else(|e| e.into_inner());
        if let Some((q, shot, cube)) = slot.as_ref() {
            if *q == p && *shot == self.shots {
                return Some(cube.clone());
            }
        }
        let cube = Arc::new(DepthCube::new(
            self.patches[p].target,
            &self.tris,
            resolution,
            self.margin,
        ));
        *slot = Some((p, self.shots, cube.clone()));
        Some(cube)
    }

    pub(super) fn blocked(&self, cube: Option<&DepthCube>, from: Vec3, to: Vec3) -> bool {
        match cube {
            Some(c) => !c.visible(from, 4.0 * self.margin),
            None => self.bvh.occluded(from, to, self.margin),
        }
    }

    /// F(v → patch p) with visibility, for the given vertices, split across threads.
    pub(super) fn vertex_factors(&self, p: usize, range: std::ops::Range<usize>) -> Vec<f32> {
        let patch = &self.patches[p];
        let threads = match self.options.threads {
            0 => std::thread::available_parallelism().map_or(1, |n| n.get()),
            n => n,
        };
        let verts = &self.vertices[range];
        let chunk = verts.len().div_ceil(threads).max(64);
        let cube = self.cube_for(p);
        let one = |v: &Vertex| {
            let f = point_to_patch(v.origin, v.normal, &patch.facets);
            if f > 0.0 && self.blocked(cube.as_deref(), v.origin, patch.target) {
                0.0
            } else {
                f
            }
        };
        if verts.len() <= chunk {
            return verts.iter().map(one).collect();
        }
        std::thread::scope(|s| {
            let handles: Vec<_> = verts
                .chunks(chunk)
                .map(|c| s.spawn(move || c.iter().map(one).collect::<Vec<f32>>()))
                .collect();
            handles
                .into_iter()
                .flat_map(|h| h.join().unwrap_or_default())
                .collect()
        })
    }
}
