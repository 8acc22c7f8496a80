use glam::Vec3;

/// A triangle mesh ready for the GPU: one normal per vertex, counter-clockwise front faces.
#[derive(Debug, Clone, PartialEq)]
pub struct Mesh {
    pub positions: Vec<Vec3>,
    pub normals: Vec<Vec3>,
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
        let normals = normals.into_iter().map(|n| n.try_normalize().unwrap_or(Vec3::Y)).collect();
        Mesh { positions, normals, indices }
    }

    pub fn triangle_count(&self) -> u32 {
        (self.indices.len() / 3) as u32
    }

    pub fn bounds(&self) -> (Vec3, Vec3) {
        self.positions.iter().fold((Vec3::splat(f32::MAX), Vec3::splat(f32::MIN)), |(lo, hi), &p| {
            (lo.min(p), hi.max(p))
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn flat_triangle_normals_point_out_of_its_ccw_face() {
        let m = Mesh::with_smooth_normals(vec![Vec3::ZERO, Vec3::X, Vec3::Y, Vec3::Z * 5.0], vec![0, 1, 2]);
        assert_eq!(&m.normals[..3], &[Vec3::Z; 3]);
        assert_eq!(m.normals[3], Vec3::Y, "unused vertex gets a finite fallback normal");
    }
}
