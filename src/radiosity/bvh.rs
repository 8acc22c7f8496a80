//! Shadow rays for the radiosity solver: a bounding-volume hierarchy over the scene's triangles
//! answering "is anything between these two points?". Built once per solve; the solver asks
//! one question per receiving vertex per shot.

use glam::Vec3;

#[derive(Debug, Clone, Copy)]
struct Node {
    lo: Vec3,
    hi: Vec3,
    /// Leaf: first triangle; inner: index of the second child (the first follows the node).
    start: u32,
    /// Triangles in a leaf; 0 for an inner node.
    count: u32,
}

pub struct Bvh {
    nodes: Vec<Node>,
    /// Triangles as (a, b − a, c − a), reordered so every leaf's triangles are contiguous.
    tris: Vec<[Vec3; 3]>,
}

const LEAF_SIZE: usize = 4;

impl Bvh {
    pub fn new(triangles: &[[Vec3; 3]]) -> Bvh {
        let mut order: Vec<u32> = (0..triangles.len() as u32).collect();
        let centroids: Vec<Vec3> = triangles
            .iter()
            .map(|t| (t[0] + t[1] + t[2]) / 3.0)
            .collect();
        let mut nodes = Vec::with_capacity(2 * triangles.len().max(1));
        build(&mut nodes, &mut order, 0, triangles, &centroids);
        let tris = order
            .iter()
            .map(|&i| {
                let [a, b, c] = triangles[i as usize];
                [a, b - a, c - a]
            })
            .collect();
        Bvh { nodes, tris }
    }

    /// Whether any triangle crosses the open segment from `from` to `to`, leaving `margin`
    /// (scene units) clear at both ends so the surfaces the segment joins do not block it.
    pub fn occluded(&self, from: Vec3, to: Vec3, margin: f32) -> bool {
        let d = to - from;
        let len = d.length();
        if len <= 2.0 * margin || self.nodes.is_empty() {
            return false;
        }
        let dir = d / len;
        let inv = dir.recip();
        let (t_min, t_max) = (margin, len - margin);
        let mut stack = [0u32; 64];
        let mut sp = 1;
        while sp > 0 {
            sp -= 1;
            let index = stack[sp];
            let node = self.nodes[index as usize];
            if !slab_hit(node.lo, node.hi, from, inv, t_min, t_max) {
                continue;
            }
            if node.count > 0 {
                let tris = &self.tris[node.start as usize..(node.start + node.count) as usize];
                if tris
                    .iter()
                    .any(|t| ray_triangle(from, dir, t).is_some_and(|t| t > t_min && t < t_max))
                {
                    return true;
                }
            } else {
                // Depth is bounded by the median split (log2 of the triangle count), far
                // below the stack's size.
                stack[sp] = index + 1;
                stack[sp + 1] = node.start;
                sp += 2;
            }
        }
        false
    }
}

fn build(
    nodes: &mut Vec<Node>,
    order: &mut [u32],
    offset: u32,
    triangles: &[[Vec3; 3]],
    centroids: &[Vec3],
) -> u32 {
    let (mut lo, mut hi) = (Vec3::splat(f32::MAX), Vec3::splat(f32::MIN));
    for &i in order.iter() {
        for p in triangles[i as usize] {
            lo = lo.min(p);
            hi = hi.max(p);
        }
    }
    let index = nodes.len() as u32;
    nodes.push(Node {
        lo,
        hi,
        start: offset,
        count: order.len() as u32,
    });
    if order.len() <= LEAF_SIZE {
        return index;
    }
    // Median split on the longest axis of the centroids' box.
    let (mut clo, mut chi) = (Vec3::splat(f32::MAX), Vec3::splat(f32::MIN));
    for &i in order.iter() {
        clo = clo.min(centroids[i as usize]);
        chi = chi.max(centroids[i as usize]);
    }
    let axis = (chi - clo).max_position();
    let mid = order.len() / 2;
    order.select_nth_unstable_by(mid, |a, b| {
        centroids[*a as usize][axis].total_cmp(&centroids[*b as usize][axis])
    });
    let (left, right) = order.split_at_mut(mid);
    build(nodes, left, offset, triangles, centroids);
    let second = build(nodes, right, offset + mid as u32, triangles, centroids);
    nodes[index as usize].start = second;
    nodes[index as usize].count = 0;
    index
}

fn slab_hit(lo: Vec3, hi: Vec3, origin: Vec3, inv: Vec3, t_min: f32, t_max: f32) -> bool {
    let t0 = (lo - origin) * inv;
    let t1 = (hi - origin) * inv;
    // NaN from 0 × ∞ (a ray in a box face's plane) must not reject the box: min/max skip NaN.
    let near = t0.min(t1).max_element().max(t_min);
    let far = t0.max(t1).min_element().min(t_max);
    near <= far
}

/// Möller–Trumbore: distance along the unit ray to the triangle, either face.
fn ray_triangle(origin: Vec3, dir: Vec3, t: &[Vec3; 3]) -> Option<f32> {
    let [a, e1, e2] = *t;
    let p = dir.cross(e2);
    let det = e1.dot(p);
    if det.abs() < 1e-12 {
        return None;
    }
    let inv_det = 1.0 / det;
    let s = origin - a;
    let u = s.dot(p) * inv_det;
    if !(0.0..=1.0).contains(&u) {
        return None;
    }
    let q = s.cross(e1);
    let v = dir.dot(q) * inv_det;
    if v < 0.0 || u + v > 1.0 {
        return None;
    }
    Some(e2.dot(q) * inv_det)
}
