//! The alternative visibility of the seeds, for comparison with shadow rays: the scene
//! rasterised around the shooter into a cube of depth maps (the hemicube's item buffer, storing
//! depth like a shadow map instead of element ids: our receivers are points, not polygons). A
//! receiving point is visible when it is no farther than the nearest surface in its texel.
//! All six faces are drawn; receivers below the shooter's horizon have a zero form factor anyway.

use glam::Vec3;

pub struct DepthCube {
    origin: Vec3,
    res: usize,
    /// Per face, per texel: 1/z of the nearest surface (0: nothing), z along the face's axis.
    faces: Vec<Vec<f32>>,
}

/// Relative depth tolerance: a receiver is its own occluder in the map.
const BIAS: f32 = 0.03;

/// Face-local coordinates (x, y, z) of a vector for face k (axis k / 2, sign by k % 2).
fn local(k: usize, r: Vec3) -> Vec3 {
    let a = k / 2;
    let s = if k.is_multiple_of(2) { 1.0 } else { -1.0 };
    Vec3::new(r[(a + 1) % 3], r[(a + 2) % 3], s * r[a])
}

impl DepthCube {
    pub fn new(origin: Vec3, triangles: &[[Vec3; 3]], res: usize, near: f32) -> DepthCube {
        let mut faces = vec![vec![0.0f32; res * res]; 6];
        for (k, face) in faces.iter_mut().enumerate() {
            for t in triangles {
                let v = t.map(|p| local(k, p - origin));
                if v.iter().all(|p| p.z < near) {
                    continue;
                }
                raster(face, res, &clip_near(&v, near));
            }
        }
        DepthCube { origin, res, faces }
    }

    /// Whether `p` is no farther than the nearest surface the cube saw in its direction.
    pub fn visible(&self, p: Vec3, margin: f32) -> bool {
        let r = p - self.origin;
        let a = r.abs().max_position();
        let k = 2 * a + usize::from(r[a] < 0.0);
        let l = local(k, r);
        if l.z <= 0.0 {
            return true;
        }
        let n = self.res as f32;
        let px = (((l.x / l.z + 1.0) * 0.5 * n) as usize).min(self.res - 1);
        let py = (((l.y / l.z + 1.0) * 0.5 * n) as usize).min(self.res - 1);
        let w = self.faces[k][py * self.res + px];
        w == 0.0 || l.z <= (1.0 + BIAS) / w + margin
    }
}

/// The polygon's part in front of the near plane (Sutherland–Hodgman, one plane).
fn clip_near(v: &[Vec3; 3], near: f32) -> Vec<Vec3> {
    let mut out = Vec::with_capacity(4);
    for i in 0..3 {
        let (a, b) = (v[i], v[(i + 1) % 3]);
        if a.z >= near {
            out.push(a);
        }
        if (a.z >= near) != (b.z >= near) {
            out.push(a + (b - a) * ((near - a.z) / (b.z - a.z)));
        }
    }
    out
}

/// Fills a convex polygon (fan-triangulated) keeping the largest 1/z per texel.
fn raster(face: &mut [f32], res: usize, poly: &[Vec3]) {
    let n = res as f32;
    let s: Vec<Vec3> = poly
        .iter()
        .map(|p| {
            Vec3::new(
                (p.x / p.z + 1.0) * 0.5 * n,
                (p.y / p.z + 1.0) * 0.5 * n,
                1.0 / p.z,
            )
        })
        .collect();
    for i in 1..s.len().saturating_sub(1) {
        let (a, b, c) = (s[0], s[i], s[i + 1]);
        let area = (b.x - a.x) * (c.y - a.y) - (b.y - a.y) * (c.x - a.x);
        if area.abs() < 1e-12 {
            continue;
        }
        let lo = a.min(b).min(c);
        let hi = a.max(b).max(c);
        if hi.x < 0.0 || hi.y < 0.0 || lo.x >= n || lo.y >= n {
            continue;
        }
        let (x0, y0) = (lo.x.max(0.0) as usize, lo.y.max(0.0) as usize);
        let (x1, y1) = (hi.x.min(n - 1.0) as usize, hi.y.min(n - 1.0) as usize);
        for y in y0..=y1 {
            for x in x0..=x1 {
                let (px, py) = (x as f32 + 0.5, y as f32 + 0.5);
                let w0 = ((b.x - px) * (c.y - py) - (b.y - py) * (c.x - px)) / area;
                let w1 = ((c.x - px) * (a.y - py) - (c.y - py) * (a.x - px)) / area;
                let w2 = 1.0 - w0 - w1;
                if w0 < 0.0 || w1 < 0.0 || w2 < 0.0 {
                    continue;
                }
                let w = w0 * a.z + w1 * b.z + w2 * c.z;
                let slot = &mut face[y * res + x];
                if w > *slot {
                    *slot = w;
                }
            }
        }
    }
}
