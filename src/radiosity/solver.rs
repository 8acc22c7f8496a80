//! The shooting loop: pick the patch with the most unshot power, send it to every vertex that
//! sees it, subdivide elements the shot left with a steep gradient, repeat.

use std::collections::HashMap;

use glam::Vec3;

mod build;
mod factors;
use build::MeshSource;
mod readout;

use super::bvh::Bvh;
use super::form_factor::{point_to_patch, Facet};
use super::hemicube::DepthCube;
use super::{lattice, luminance, Options, RadiosityError, Surface, Visibility};
use std::sync::{Arc, Mutex};

#[derive(Debug, Clone)]
struct Vertex {
    pos: Vec3,
    normal: Vec3,
    /// Irradiance received so far, all shots; and from emitters' shots alone (direct light).
    total: Vec3,
    direct: Vec3,
    /// Index into the output (the display mesh's vertex); `NO_OUTPUT` for an element's centre.
    out: usize,
    /// Where it is evaluated and its shadow rays start: off the surface along the normal and,
    /// on a quad's edge, a hair into the quad. Exactly on the seam where two walls meet, the
    /// other wall is seen edge-on (factor 0, and rays run inside its plane), while a hair
    /// inside it fills half the hemisphere: the seam's vertices would darken the whole row of
    /// elements along it.
    origin: Vec3,
}

/// Elements closer to the shooter than this many areas (r² < k · A) average a grid of
/// samples instead of reading their centre.
const NEAR_SAMPLES: f32 = 9.0;
/// Samples per side of that grid in a quad element.
const QUAD_SAMPLES: u32 = 4;

/// Marks the centre sample of an element, which is not a display vertex.
const NO_OUTPUT: usize = usize::MAX;

#[derive(Debug, Clone, Copy)]
struct Cell {
    surface: u32,
    i0: u32,
    j0: u32,
    size: u32,
    depth: u32,
}

#[derive(Debug, Clone)]
struct Element {
    patch: u32,
    verts: [u32; 4],
    /// The sample the element's received energy is measured at: its centre. Corner samples
    /// alone miss most of what an element next to the shooter gets (a wall's bottom edge sees
    /// the floor edge-on, yet the wall just above it is brightly lit).
    centre: u32,
    area: f32,
    reflectance: Vec3,
    /// Reflected radiosity (exitance) accumulated, and the part not yet shot.
    radiosity: Vec3,
    unshot: Vec3,
    cell: Option<Cell>,
}

#[derive(Debug, Clone)]
struct Patch {
    /// Current leaf elements.
    leaves: Vec<u32>,
    area: f32,
    /// Where shadow rays aim: on the patch, nudged off it along its normal.
    target: Vec3,
    facets: Vec<Facet>,
    emitter: bool,
}

#[derive(Debug, Clone)]
struct QuadInfo {
    corners: [Vec3; 4],
    normal: Vec3,
    lattice: [u32; 2],
    max_depth: u32,
    first_out: usize,
    points: HashMap<(u32, u32), u32>,
}

/// What one shot did.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Shot {
    pub patch: usize,
    /// Luminance of the power the patch sent.
    pub power: f64,
    /// Of that, the luminance of what receivers got (≤ power).
    pub received: f64,
    /// Of what was received, the luminance receivers absorbed rather than reflected.
    pub absorbed: f64,
    pub subdivided: usize,
}

/// Where the solution stands.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Stats {
    pub shots: u32,
    pub patches: usize,
    pub elements: usize,
    pub vertices: usize,
    /// Luminance of the power emitters emit.
    pub emitted: f64,
    /// Luminance of the reflected power accumulated so far (the quantity that converges).
    pub reflected: f64,
    /// Unshot power over emitted power.
    pub unshot_fraction: f64,
}

pub struct Solver {
    options: Options,
    bvh: Bvh,
    /// The scene's triangles, for depth-cube visibility.
    tris: Vec<[Vec3; 3]>,
    /// The depth cube of the current shot (patch, shot number), built once per shot.
    cube: Mutex<Option<(usize, u32, Arc<DepthCube>)>>,
    margin: f32,
    vertices: Vec<Vertex>,
    elements: Vec<Element>,
    patches: Vec<Patch>,
    quads: HashMap<u32, QuadInfo>,
    outputs: usize,
    emitted: f64,
    mean_exitance: f64,
    total_area: f64,
    shots: u32,
}

impl Solver {
    pub fn new(surfaces: &[Surface], options: Options) -> Result<Solver, RadiosityError> {
        let mut tris = Vec::new();
        let (mut lo, mut hi) = (Vec3::splat(f32::MAX), Vec3::splat(f32::MIN));
        for s in surfaces {
            match s {
                Surface::Quad { corners: c, .. } => {
                    tris.push([c[0], c[1], c[2]]);
                    tris.push([c[0], c[2], c[3]]);
                }
                Surface::Mesh {
                    positions, indices, ..
                } => {
                    for t in indices.chunks_exact(3) {
                        let p =
                            |k: usize| positions.get(t[k] as usize).copied().unwrap_or_default();
                        tris.push([p(0), p(1), p(2)]);
                    }
                }
            }
        }
        for t in &tris {
            for p in t {
                lo = lo.min(*p);
                hi = hi.max(*p);
            }
        }
        let scale = (hi - lo).max_element().max(1e-6);
        let mut solver = Solver {
            options,
            bvh: Bvh::new(&tris),
            tris,
            cube: Mutex::new(None),
            margin: 1e-4 * scale,
            vertices: Vec::new(),
            elements: Vec::new(),
            patches: Vec::new(),
            quads: HashMap::new(),
            outputs: 0,
            emitted: 0.0,
            mean_exitance: 0.0,
            total_area: 0.0,
            shots: 0,
        };
        for (i, s) in surfaces.iter().enumerate() {
            match s {
                Surface::Quad {
                    corners,
                    cells,
                    max_depth,
                    reflectance,
                    emission,
                } => solver.add_quad(i, *corners, *cells, *max_depth, *reflectance, *emission)?,
                Surface::Mesh {
                    positions,
                    normals,
                    indices,
                    reflectance,
                    emission,
                    triangles_per_patch,
                } => solver.add_mesh(
                    i,
                    MeshSource {
                        positions,
                        normals,
                        indices,
                    },
                    *reflectance,
                    *emission,
                    *triangles_per_patch,
                )?,
            }
            solver.outputs += s.output_len();
        }
        if let Some(sun) = solver.options.sun {
            solver.seed_sun(sun);
        }
        if solver.emitted <= 0.0 {
            return Err(RadiosityError::NoEmitter);
        }
        solver.total_area = solver.elements.iter().map(|e| f64::from(e.area)).sum();
        solver.mean_exitance = solver.emitted / solver.total_area.max(1e-30);
        Ok(solver)
    }

    pub fn stats(&self) -> Stats {
        let leaves = self.patches.iter().map(|p| p.leaves.len()).sum();
        let (mut reflected, mut unshot) = (0.0, 0.0);
        for p in &self.patches {
            for &e in &p.leaves {
                let e = &self.elements[e as usize];
                reflected += luminance(e.radiosity) * f64::from(e.area);
                unshot += luminance(e.unshot) * f64::from(e.area);
            }
        }
        Stats {
            shots: self.shots,
            patches: self.patches.len(),
            elements: leaves,
            vertices: self.vertices.len(),
            emitted: self.emitted,
            reflected,
            unshot_fraction: unshot / self.emitted,
        }
    }

    pub fn converged(&self) -> bool {
        self.shots >= self.options.max_shots
            || self.stats().unshot_fraction < self.options.stop_fraction
    }

    /// Unshot exitance of a patch (area-weighted over its leaves).
    fn patch_unshot(&self, p: &Patch) -> Vec3 {
        p.leaves
            .iter()
            .map(|&e| self.elements[e as usize].unshot * self.elements[e as usize].area)
            .sum::<Vec3>()
            / p.area
    }

    /// Shoots the patch with the most unshot power. `None` when nothing is left to shoot.
    pub fn step(&mut self) -> Option<Shot> {
        let (best, power) = self
            .patches
            .iter()
            .enumerate()
            .map(|(i, p)| (i, luminance(self.patch_unshot(p)) * f64::from(p.area)))
            .max_by(|a, b| a.1.total_cmp(&b.1))?;
        if !(power > 0.0) {
            return None;
        }
        Some(self.shoot(best, power))
    }

    fn shoot(&mut self, p: usize, power: f64) -> Shot {
        let unshot = self.patch_unshot(&self.patches[p]);
        let mut factors = self.vertex_factors(p, 0..self.vertices.len());
        let subdivided = self.subdivide(p, &mut factors, luminance(unshot));
        // Element factors F_p→e = A_e · F̄(e→p) / A_p (reciprocity); the approximations can
        // overshoot in sum, so scale the shot down to conserve energy when they do.
        let patch_area = self.patches[p].area;
        let element_factors = self.element_factors(p, &factors);
        let sent: f64 = element_factors
            .iter()
            .map(|&(e, f)| f64::from(self.elements[e as usize].area * f))
            .sum();
        let scale = if sent > f64::from(patch_area) {
            (f64::from(patch_area) / sent) as f32
        } else {
            1.0
        };
        let emitter = self.patches[p].emitter;
        for &e in &self.patches[p].leaves.clone() {
            self.elements[e as usize].unshot = Vec3::ZERO;
        }
        for (v, f) in self.vertices.iter_mut().zip(&factors) {
            let de = unshot * (*f * scale);
            v.total += de;
            if emitter {
                v.direct += de;
            }
        }
        let (mut received, mut absorbed) = (0.0, 0.0);
        for (e, f) in element_factors {
            let el = &mut self.elements[e as usize];
            let irradiance = unshot * (f * scale);
            received += luminance(irradiance) * f64::from(el.area);
            let db = el.reflectance * irradiance;
            absorbed += luminance(irradiance - db) * f64::from(el.area);
            el.radiosity += db;
            el.unshot += db;
        }
        self.shots += 1;
        Shot {
            patch: p,
            power,
            received,
            absorbed,
            subdivided,
        }
    }

    /// Splits quad elements across which this shot's irradiance changes steeply, recursively
    /// down to each quad's depth bound; new vertices get this shot's factor too.
    fn subdivide(&mut self, shooter: usize, factors: &mut Vec<f32>, unshot_lum: f64) -> usize {
        let floor = f64::from(self.options.subdivide_floor) * self.mean_exitance;
        let mut work: Vec<u32> = self
            .patches
            .iter()
            .flat_map(|q| q.leaves.iter().copied())
            .filter(|&e| self.elements[e as usize].cell.is_some())
            .collect();
        let mut count = 0;
        while let Some(e) = work.pop() {
            let el = self.elements[e as usize].clone();
            let Some(cell) = el.cell else { continue };
            if cell.depth >= self.quads[&cell.surface].max_depth || el.patch as usize == shooter {
                continue;
            }
            let f = [
                el.verts[0],
                el.verts[1],
                el.verts[2],
                el.verts[3],
                el.centre,
            ]
            .map(|v| factors[v as usize]);
            let (lo, hi) = f
                .iter()
                .fold((f32::MAX, f32::MIN), |(l, h), x| (l.min(*x), h.max(*x)));
            let step = f64::from(hi - lo) * unshot_lum * luminance(el.reflectance);
            if !(hi - lo > self.options.subdivide_relative * hi && step > floor) {
                continue;
            }
            let h = cell.size / 2;
            let first_new = self.vertices.len();
            let mut children = Vec::with_capacity(4);
            for (di, dj) in [(0, 0), (h, 0), (h, h), (0, h)] {
                let c = Cell {
                    surface: cell.surface,
                    i0: cell.i0 + di,
                    j0: cell.j0 + dj,
                    size: h,
                    depth: cell.depth + 1,
                };
                let verts = self.cell_vertices(c, Some((&el.verts, cell)));
                let normal = self.quads[&cell.surface].normal;
                let centre = self.sample(self.cell_centre(c), normal);
                children.push(self.elements.len() as u32);
                self.elements.push(Element {
                    verts,
                    centre,
                    area: el.area / 4.0,
                    cell: Some(c),
                    ..el.clone()
                });
            }
            let fresh = self.vertex_factors(shooter, first_new..self.vertices.len());
            factors.extend(fresh);
            let leaves = &mut self.patches[el.patch as usize].leaves;
            leaves.retain(|x| *x != e);
            leaves.extend(&children);
            work.extend(children);
            count += 1;
        }
        count
    }
}
