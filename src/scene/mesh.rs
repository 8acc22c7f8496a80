use glam::Vec3;

/// A triangle mesh ready for the GPU: one normal per vertex, counter-clockwise front faces.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct Mesh {
    pub positions: Vec<Vec3>,
    pub normals: Vec<Vec3>,
    /// Normals averaged over the material's subsurface reach, not renormalised: the shortening
    /// is what softens the lighting (seed 001, normal-blur SSS).
    pub blurred_normals: Vec<Vec3>,
    /// Material id of each vertex.
    pub material: Vec<u32>,
    /// Linear RGBA multiplying the material's base colour per vertex (glTF vertex colours and
    /// base colour textures sampled at the vertices); white elsewhere.
    pub tint: Vec<[f32; 4]>,
    /// Texture coordinates (zero without): xy for the material's base colour map, zw for its
    /// normal and occlusion maps.
    pub uv: Vec<[f32; 4]>,
    /// Tangent (xyz) and bitangent sign (w) for normal maps; zero where there is none.
    pub tangent: Vec<[f32; 4]>,
    pub indices: Vec<u32>,
}

impl Mesh {
    /// Smooth normals weighted by triangle area (the unnormalised cross product), so tiny sliver
    /// triangles from the scan do not tilt the shading.
    pub fn with_smooth_normals(positions: Vec<Vec3>, indices: Vec<u32>) -> Mesh {
        let mut normals = vec![Vec3::ZERO; positions.len()];
        for tri in indices.chunks_exact(3) {
            let [a, b, c] = [tri[0], tri[1], tri[2]].map(|i| positions[i as usize]);
            let n = (b - a).cross(c - a);
            for &i in tri {
                normals[i as usize] += n;
            }
        }
        // A vertex used by no triangle (or only by zero-area ones) gets a harmless up vector
        // instead of a NaN from normalising zero.
        let normals: Vec<Vec3> = normals
            .into_iter()
            .map(|n| n.try_normalize().unwrap_or(Vec3::Y))
            .collect();
        Mesh::with_normals(positions, normals, indices)
    }

    /// A mesh whose normals are given (unit length, one per position).
    pub fn with_normals(positions: Vec<Vec3>, normals: Vec<Vec3>, indices: Vec<u32>) -> Mesh {
        let n = positions.len();
        Mesh {
            positions,
            blurred_normals: normals.clone(),
            normals,
            material: vec![0; n],
            tint: vec![[1.0; 4]; n],
            uv: vec![[0.0; 4]; n],
            tangent: vec![[0.0; 4]; n],
            indices,
        }
    }

    /// Averages each vertex's normal with its neighbours within `radius` (weights fall as
    /// (1 − d/radius)²). A radius below the mesh's detail leaves the normals as they are.
    pub fn with_blurred_normals(mut self, radius: f32) -> Mesh {
        if radius <= 0.0 || !radius.is_finite() {
            return self;
        }
        self.blurred_normals = self
            .positions
            .iter()
            .map(|p| {
                let mut sum = Vec3::ZERO;
                let mut weight = 0.0;
                for (q, n) in self.positions.iter().zip(&self.normals) {
                    let d = p.distance(*q);
                    if d < radius {
                        let w = (1.0 - d / radius).powi(2);
                        sum += w * *n;
                        weight += w;
                    }
                }
                if weight > 0.0 {
                    sum / weight
                } else {
                    Vec3::ZERO
                }
            })
            .collect();
        self
    }

    /// Appends another mesh, tagging its vertices with `material`.
    pub fn append(&mut self, other: Mesh, material: u32) {
        let base = self.positions.len() as u32;
        self.indices.extend(other.indices.iter().map(|i| i + base));
        self.material
            .extend(std::iter::repeat_n(material, other.positions.len()));
        self.positions.extend(other.positions);
        self.normals.extend(other.normals);
        self.blurred_normals.extend(other.blurred_normals);
        self.tint.extend(other.tint);
        self.uv.extend(other.uv);
        self.tangent.extend(other.tangent);
    }

    pub fn triangle_count(&self) -> u32 {
        (self.indices.len() / 3) as u32
    }

    pub fn bounds(&self) -> (Vec3, Vec3) {
        self.positions.iter().fold(
            (Vec3::splat(f32::MAX), Vec3::splat(f32::MIN)),
            |(lo, hi), &p| (lo.min(p), hi.max(p)),
        )
    }
}

/// Per-vertex tangents from texture coordinates (each triangle's ∂p/∂u, area-weighted, then
/// made orthogonal to the vertex normal of the triangle fan; w is the bitangent's handedness).
/// Vertices with degenerate UVs get a zero tangent (their normal map is then ignored).
pub fn tangents(positions: &[Vec3], uv: &[[f32; 2]], indices: &[u32]) -> Vec<[f32; 4]> {
    let n = positions.len();
    let (mut t, mut b, mut normal) = (
        vec![Vec3::ZERO; n],
        vec![Vec3::ZERO; n],
        vec![Vec3::ZERO; n],
    );
    for tri in indices.chunks_exact(3) {
        let [i0, i1, i2] = [tri[0], tri[1], tri[2]].map(|i| i as usize);
        let (e1, e2) = (positions[i1] - positions[i0], positions[i2] - positions[i0]);
        let (du1, dv1) = (uv[i1][0] - uv[i0][0], uv[i1][1] - uv[i0][1]);
        let (du2, dv2) = (uv[i2][0] - uv[i0][0], uv[i2][1] - uv[i0][1]);
        let det = du1 * dv2 - du2 * dv1;
        if det.abs() < 1e-12 || !det.is_finite() {
            continue;
        }
        let r = 1.0 / det;
        let (tt, bb) = ((e1 * dv2 - e2 * dv1) * r, (e2 * du1 - e1 * du2) * r);
        let face = e1.cross(e2);
        for i in [i0, i1, i2] {
            t[i] += tt;
            b[i] += bb;
            normal[i] += face;
        }
    }
    (0..n)
        .map(|i| {
            let nn = normal[i].normalize_or_zero();
            let tan = (t[i] - nn * nn.dot(t[i])).normalize_or_zero();
            let w = if nn.cross(tan).dot(b[i]) < 0.0 {
                -1.0
            } else {
                1.0
            };
            [tan.x, tan.y, tan.z, w]
        })
        .collect()
}

/// Triangulates the polygon `corners` as a fan into `out`, leaving out triangles that repeat a
/// corner or have no area (they would only make NaN normals and nothing visible).
pub fn push_fan(corners: &[u32], positions: &[Vec3], out: &mut Vec<u32>) {
    for k in 1..corners.len().saturating_sub(1) {
        let t = [corners[0], corners[k], corners[k + 1]];
        if t[0] == t[1] || t[1] == t[2] || t[0] == t[2] {
            continue;
        }
        let [a, b, c] = t.map(|i| positions[i as usize]);
        let area = (b - a).cross(c - a).length();
        if area > 0.0 && area.is_finite() {
            out.extend_from_slice(&t);
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn flat_triangle_normals_point_out_of_its_ccw_face() {
        let m = Mesh::with_smooth_normals(
            vec![Vec3::ZERO, Vec3::X, Vec3::Y, Vec3::Z * 5.0],
            vec![0, 1, 2],
        );
        assert_eq!(&m.normals[..3], &[Vec3::Z; 3]);
        assert_eq!(
            m.normals[3],
            Vec3::Y,
            "unused vertex gets a finite fallback normal"
        );
    }

    #[test]
    fn blurring_shortens_normals_on_curved_surfaces_only() {
        // Two triangles folded 90° along x: blurred normals at the fold lean between the faces.
        let p = vec![
            Vec3::ZERO,
            Vec3::X,
            Vec3::new(0.0, 0.0, -1.0),
            Vec3::new(0.0, -1.0, 0.0),
        ];
        let m = Mesh::with_smooth_normals(p, vec![0, 1, 2, 0, 3, 1]).with_blurred_normals(3.0);
        for n in &m.blurred_normals {
            assert!(
                n.is_finite() && n.length() < 1.0 && n.length() > 0.5,
                "{n:?}"
            );
        }
        let flat = Mesh::with_smooth_normals(vec![Vec3::ZERO, Vec3::X, Vec3::Y], vec![0, 1, 2])
            .with_blurred_normals(5.0);
        assert!(flat
            .blurred_normals
            .iter()
            .all(|n| (*n - Vec3::Z).length() < 1e-6));
    }
}
