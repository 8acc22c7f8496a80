//! Reading a solve out: the ambient preview, per-vertex irradiance for the display mesh, and
//! per-patch figures for reports and tests.

use glam::Vec3;

use super::*;

impl Solver {
    /// The display-only ambient irradiance of seed 004: the unshot energy, spread evenly over
    /// the scene's area and multiplied by the interreflection series 1/(1 − ρ̄). ρ̄ is capped at
    /// 0.99 so a scene of near-white walls gets a large but finite preview.
    pub fn ambient(&self) -> Vec3 {
        let (mut unshot, mut rho) = (Vec3::ZERO, Vec3::ZERO);
        for p in &self.patches {
            for &e in &p.leaves {
                let e = &self.elements[e as usize];
                unshot += e.unshot * e.area;
                rho += e.reflectance * e.area;
            }
        }
        let area = self.total_area.max(1e-30) as f32;
        let series = (Vec3::ONE - (rho / area).min(Vec3::splat(0.99))).recip();
        series * unshot / area
    }

    /// Irradiance per output vertex: (direct, indirect + ambient preview). Quad lattice points
    /// no element has a vertex at take the bilinear value of the finest element over them.
    pub fn irradiance(&self, with_ambient: bool) -> (Vec<Vec3>, Vec<Vec3>) {
        let ambient = if with_ambient {
            self.ambient()
        } else {
            Vec3::ZERO
        };
        let mut direct = vec![Vec3::ZERO; self.outputs];
        let mut indirect = vec![ambient; self.outputs];
        let mut cells: Vec<(Cell, [u32; 4])> = self
            .patches
            .iter()
            .flat_map(|p| p.leaves.iter())
            .filter_map(|&e| {
                self.elements[e as usize]
                    .cell
                    .map(|c| (c, self.elements[e as usize].verts))
            })
            .collect();
        cells.sort_by_key(|(c, _)| c.depth);
        for (c, verts) in cells {
            let q = &self.quads[&c.surface];
            let [a, b, cc, d] = verts.map(|v| &self.vertices[v as usize]);
            for j in 0..=c.size {
                for i in 0..=c.size {
                    let (s, t) = (i as f32 / c.size as f32, j as f32 / c.size as f32);
                    let mix = |f: fn(&Vertex) -> Vec3| {
                        (f(a) * (1.0 - s) + f(b) * s) * (1.0 - t)
                            + (f(d) * (1.0 - s) + f(cc) * s) * t
                    };
                    let out = q.first_out + ((c.j0 + j) * (q.lattice[0] + 1) + c.i0 + i) as usize;
                    direct[out] = mix(|v| v.direct);
                    indirect[out] = mix(|v| v.total - v.direct) + ambient;
                }
            }
        }
        for v in self.vertices.iter().filter(|v| v.out != NO_OUTPUT) {
            direct[v.out] = v.direct;
            indirect[v.out] = v.total - v.direct + ambient;
        }
        (direct, indirect)
    }

    /// F_p→e for every current element (visibility included, before any energy scaling): the
    /// form factors the solver uses, for checking against closed forms.
    /// (patch of the element, element area, F_p→e) per leaf element.
    pub fn patch_factors(&self, p: usize) -> Vec<(usize, f32, f32)> {
        let factors = self.vertex_factors(p, 0..self.vertices.len());
        let area = self.patches[p].area;
        self.element_factors(p, &factors)
            .into_iter()
            .map(|(e, f)| {
                let el = &self.elements[e as usize];
                (el.patch as usize, el.area, el.area * f / area)
            })
            .collect()
    }

    pub fn patch_area(&self, p: usize) -> f32 {
        self.patches[p].area
    }

    /// Radiosity (emission excluded) per patch, area-weighted over its leaves.
    pub fn patch_radiosity(&self, p: usize) -> Vec3 {
        let patch = &self.patches[p];
        patch
            .leaves
            .iter()
            .map(|&e| self.elements[e as usize].radiosity * self.elements[e as usize].area)
            .sum::<Vec3>()
            / patch.area
    }
}
