//! Progressive refinement radiosity (Cohen et al. 1988; GPU Gems 2 ch. 39; seed 004): diffuse
//! interreflection in enclosed scenes, solved once per scene on the CPU and sampled by every
//! frame as a per-vertex irradiance.
//!
//! Why a patch list on the CPU rather than radiosity textures on the GPU: the solve is a
//! once-per-scene precompute that must not hold up the render thread, which owns the GPU and
//! serves frames from the moment a scene loads; a background CPU thread refines while frames
//! stream, and the frame reads the result at one vertex attribute's cost. Visibility is a
//! shadow ray per receiving vertex against a BVH (seed 002's item buffer answers the same
//! question by rasterising; on a CPU a ray per receiver is the cheaper and alias-free way).
//!
//! Patches shoot and elements receive (seed 004, after Cohen): a wall is a grid of patches, each
//! the root of a quad-tree of elements that subdivides where one shot leaves a steep gradient
//! (shadow edges), down to a bounded depth. A mesh (the translucent bunny) receives at its own
//! vertices and shoots from clusters of neighbouring triangles. Light is received at element
//! vertices (Wallace et al. 1989), so the frame interpolates it smoothly across each element.

mod bvh;
pub mod cache;
pub mod form_factor;
mod hemicube;
mod solver;

pub use cache::{Progress, RadiosityHandle, Snapshot};
pub use solver::{Shot, Solver, Stats};

use glam::Vec3;

/// One surface the solver sees.
#[derive(Debug, Clone, PartialEq)]
pub enum Surface {
    /// A parallelogram `corners[0..4]`, counter-clockwise seen from its front. It is split into
    /// `cells[0] × cells[1]` patches whose elements may halve `max_depth` times; the output
    /// holds one value per point of the finest lattice, row by row from `corners[0]`.
    Quad {
        corners: [Vec3; 4],
        cells: [u32; 2],
        max_depth: u32,
        reflectance: Vec3,
        emission: Vec3,
    },
    /// A triangle mesh: one element per triangle, patches of about `triangles_per_patch`
    /// neighbouring triangles; the output holds one value per mesh vertex. A mesh emits
    /// (a glTF's emissive lamp) when `emission` is non-zero.
    Mesh {
        positions: Vec<Vec3>,
        normals: Vec<Vec3>,
        indices: Vec<u32>,
        reflectance: Vec3,
        emission: Vec3,
        triangles_per_patch: usize,
    },
}

impl Surface {
    /// Output values this surface contributes (vertices of its display mesh).
    pub fn output_len(&self) -> usize {
        match self {
            Surface::Quad {
                cells, max_depth, ..
            } => {
                let [lu, lv] = lattice(*cells, *max_depth);
                ((lu + 1) * (lv + 1)) as usize
            }
            Surface::Mesh { positions, .. } => positions.len(),
        }
    }
}

/// Points per side of a quad's finest lattice, minus one.
pub fn lattice(cells: [u32; 2], max_depth: u32) -> [u32; 2] {
    [cells[0] << max_depth, cells[1] << max_depth]
}

/// When to subdivide and when to stop.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Options {
    /// Subdivide an element when one shot's irradiance across its corners varies by more than
    /// this fraction of its largest corner value…
    pub subdivide_relative: f32,
    /// …and the resulting radiosity step exceeds this fraction of the scene's mean exitance
    /// (emitted power / total area), so dim corners do not split on noise.
    pub subdivide_floor: f32,
    /// Converged when the unshot power falls below this fraction of the emitted power.
    pub stop_fraction: f64,
    /// Hard bound on shots: with reflectance near 1 the unshot energy decays very slowly.
    pub max_shots: u32,
    /// Worker threads for the receivers of one shot (0: all cores).
    pub threads: usize,
    pub visibility: Visibility,
    /// The scene's directional key light, whose first bounce the solve carries: every element
    /// it reaches starts with ρ·E·cos θ unshot (no emitter needed).
    pub sun: Option<Sun>,
}

/// A directional light for radiosity's first bounce: direction towards it (unit) and the
/// irradiance it gives a surface facing it. Its direct light is not in the solve's output (the
/// frame shades it with its shadow map); what it bounces is.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Sun {
    pub to_light: Vec3,
    pub irradiance: Vec3,
}

/// How a shot finds which receivers see the shooter.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Visibility {
    /// One shadow ray per receiving sample against a BVH (the default).
    Rays,
    /// The scene rasterised around the shooter into a cube of depth maps, `resolution`² texels
    /// per face (the seeds' hemicube, as a depth map): kept to measure against the rays.
    Cube { resolution: usize },
}

impl Default for Options {
    fn default() -> Options {
        Options {
            subdivide_relative: 0.35,
            subdivide_floor: 0.05,
            stop_fraction: 0.001,
            max_shots: 20_000,
            threads: 0,
            visibility: Visibility::Rays,
            sun: None,
        }
    }
}

#[derive(Debug, thiserror::Error, PartialEq)]
pub enum RadiosityError {
    #[error("surface {0}: a quad needs a parallelogram with non-zero area")]
    BadQuad(usize),
    #[error(
        "surface {0}: reflectance and emission must be finite, reflectance in [0, 1], emission ≥ 0"
    )]
    BadValue(usize),
    #[error("surface {0}: mesh arrays disagree (indices past the vertices or normals missing)")]
    BadMesh(usize),
    #[error("nothing emits light: radiosity needs an emitting surface or a key light that reaches a surface")]
    NoEmitter,
}

/// The fraction of directions from `from` in which a ray meets one of the triangles: how
/// enclosed a point is (1 inside a closed room, ~5/6 inside a box open on one side, small in
/// an open scene). 256 directions on a Fibonacci sphere.
pub fn enclosure(triangles: &[[Vec3; 3]], from: Vec3, reach: f32) -> f64 {
    const RAYS: usize = 256;
    let bvh = bvh::Bvh::new(triangles);
    let golden = std::f32::consts::PI * (3.0 - 5f32.sqrt());
    let hits = (0..RAYS)
        .filter(|&k| {
            let y = 1.0 - 2.0 * (k as f32 + 0.5) / RAYS as f32;
            let r = (1.0 - y * y).sqrt();
            let phi = golden * k as f32;
            let dir = Vec3::new(r * phi.cos(), y, r * phi.sin());
            bvh.occluded(from, from + dir * reach, 0.0)
        })
        .count();
    hits as f64 / RAYS as f64
}

/// Linear RGB → luminance (Rec. 709), the scalar used to rank and measure power.
pub fn luminance(c: Vec3) -> f64 {
    f64::from(c.dot(Vec3::new(0.2126, 0.7152, 0.0722)))
}
