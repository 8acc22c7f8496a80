//! Surfaces for the radiosity tests: parallelograms, grids of triangles, Hottel's closed form.

use fovea::radiosity::{Options, Surface};
use glam::Vec3;

/// A parallelogram with corner `o`, edges `u`, `v`; its front faces u × v.
pub fn quad(o: Vec3, u: Vec3, v: Vec3, cells: u32, depth: u32, rho: f32, emission: f32) -> Surface {
    Surface::Quad {
        corners: [o, o + u, o + u + v, o + v],
        cells: [cells, cells],
        max_depth: depth,
        reflectance: Vec3::splat(rho),
        emission: Vec3::splat(emission),
    }
}

pub fn serial() -> Options {
    Options {
        threads: 1,
        ..Options::default()
    }
}

/// Hottel's closed form for two directly opposed parallel rectangles a × b, distance c apart.
pub fn opposed_rectangles(a: f64, b: f64, c: f64) -> f64 {
    let (x, y) = (a / c, b / c);
    let (x1, y1) = ((1.0 + x * x).sqrt(), (1.0 + y * y).sqrt());
    2.0 / (std::f64::consts::PI * x * y)
        * ((x1 * x1 * y1 * y1 / (1.0 + x * x + y * y)).sqrt().ln()
            + x * y1 * (x / y1).atan()
            + y * x1 * (y / x1).atan()
            - x * x.atan()
            - y * y.atan())
}

/// A grid of n × n cells spanning `o + s·u + t·v`, s, t ∈ [0, 1], facing u × v, as a mesh.
pub fn grid_mesh(o: Vec3, u: Vec3, v: Vec3, n: u32, rho: f32) -> Surface {
    let mut positions = Vec::new();
    for j in 0..=n {
        for i in 0..=n {
            positions.push(o + u * (i as f32 / n as f32) + v * (j as f32 / n as f32));
        }
    }
    let mut indices = Vec::new();
    for j in 0..n {
        for i in 0..n {
            let (a, b) = (j * (n + 1) + i, (j + 1) * (n + 1) + i);
            indices.extend([a, a + 1, b + 1, a, b + 1, b]);
        }
    }
    Surface::Mesh {
        normals: vec![u.cross(v).normalize(); positions.len()],
        positions,
        indices,
        reflectance: Vec3::splat(rho),
        emission: Vec3::ZERO,
        triangles_per_patch: 4,
    }
}
