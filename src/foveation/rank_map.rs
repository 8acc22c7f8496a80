//! A progressive blue-noise rank map over a toroidal tile, by weighted sample elimination
//! (Yuksel 2015; seed 001 #1). Every pixel of the tile gets a rank; the pixels ranked below
//! k form a Poisson-disk-like set for every k, so thresholding the rank against any sampling
//! probability picks a well-spread subset.

use std::sync::OnceLock;

/// Side of the square tile, in pixels. The map repeats across the frame (toroidal distances
/// make the repetition seamless) and is offset every frame.
pub const TILE: u32 = 64;

/// Weight exponent α (Yuksel's default, "you will probably never change it").
const ALPHA: f64 = 8.0;
/// Weight limiting β and its dependence on the elimination ratio, γ (the reference code's defaults).
const BETA: f64 = 0.65;
const GAMMA: f64 = 1.5;

/// Ranks 0..TILE² of every pixel of the tile, row-major. Built once per process (~0.1 s).
pub fn rank_map() -> &'static [u32] {
    static MAP: OnceLock<Vec<u32>> = OnceLock::new();
    MAP.get_or_init(|| build(TILE, 0x5eed_f0e4))
}

/// Ranks normalised to thresholds in (0, 1): pixel k is sampled at probability p iff
/// `threshold[k] < p`. The +0.5 centres each rank in its bin, so p = 1 samples every pixel and
/// p = 0 none.
pub fn thresholds() -> Vec<f32> {
    let n = (TILE * TILE) as f32;
    rank_map().iter().map(|&r| (r as f32 + 0.5) / n).collect()
}

/// Splitmix64: a tiny deterministic generator for the symmetry-breaking jitter.
fn next(state: &mut u64) -> f64 {
    *state = state.wrapping_add(0x9E37_79B9_7F4A_7C15);
    let mut z = *state;
    z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
    z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
    ((z ^ (z >> 31)) >> 11) as f64 / (1u64 << 53) as f64
}

/// Builds the rank map of a `side`×`side` torus. Input samples are the pixel centres, jittered
/// by ±0.01 px only to break the ties a perfectly regular grid would put in every weight (more
/// jitter lets elimination keep pairs that are adjacent on the grid).
pub fn build(side: u32, seed: u64) -> Vec<u32> {
    let n = (side * side) as usize;
    let mut rng = seed;
    let pts: Vec<[f64; 2]> = (0..n)
        .map(|k| {
            let (x, y) = ((k as u32 % side) as f64, (k as u32 / side) as f64);
            [
                x + 0.5 + 0.02 * (next(&mut rng) - 0.5),
                y + 0.5 + 0.02 * (next(&mut rng) - 0.5),
            ]
        })
        .collect();
    let size = f64::from(side);
    let dist = |a: [f64; 2], b: [f64; 2]| {
        let mut dx = (a[0] - b[0]).abs();
        let mut dy = (a[1] - b[1]).abs();
        dx = dx.min(size - dx);
        dy = dy.min(size - dy);
        (dx * dx + dy * dy).sqrt()
    };
    let mut rank = vec![0u32; n];
    // Survivors of the current stage; each stage halves them, and the ones it removes take the
    // ranks just above the survivors (removed first = highest rank).
    let mut alive: Vec<usize> = (0..n).collect();
    while alive.len() > 1 {
        let from = alive.len();
        let to = from / 2;
        // Maximal Poisson-disk radius for `to` samples on an area of side², in 2-D.
        let r_max = ((size * size / to as f64) / (2.0 * 3f64.sqrt())).sqrt();
        let d_max = 2.0 * r_max;
        let d_min = d_max * (1.0 - (to as f64 / from as f64).powf(GAMMA)) * BETA;
        let weight = |d: f64| (1.0 - d.max(d_min) / d_max).powf(ALPHA);
        // Neighbour lists within d_max (brute force: at most 4096² distance checks, once).
        let neighbours: Vec<Vec<(usize, f64)>> = alive
            .iter()
            .map(|&i| {
                alive
                    .iter()
                    .enumerate()
                    .filter(|&(_, &j)| j != i)
                    .filter_map(|(slot, &j)| {
                        let d = dist(pts[i], pts[j]);
                        (d < d_max).then(|| (slot, weight(d)))
                    })
                    .collect()
            })
            .collect();
        let mut w: Vec<f64> = neighbours
            .iter()
            .map(|nb| nb.iter().map(|(_, wij)| wij).sum())
            .collect();
        let mut removed = vec![false; from];
        for r in (to..from).rev() {
            // The sample most crowded by its neighbours goes first.
            let (slot, _) = w.iter().enumerate().filter(|(s, _)| !removed[*s]).fold(
                (usize::MAX, f64::NEG_INFINITY),
                |best, (s, &v)| if v > best.1 { (s, v) } else { best },
            );
            removed[slot] = true;
            rank[alive[slot]] = r as u32;
            for &(other, wij) in &neighbours[slot] {
                w[other] -= wij;
            }
        }
        alive = alive
            .iter()
            .zip(&removed)
            .filter(|(_, r)| !**r)
            .map(|(&i, _)| i)
            .collect();
    }
    if let Some(&last) = alive.first() {
        rank[last] = 0;
    }
    rank
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Smallest toroidal distance between any two selected pixels.
    fn min_distance(side: u32, selected: &[usize]) -> f64 {
        let s = f64::from(side);
        let mut best = f64::MAX;
        for (a, &i) in selected.iter().enumerate() {
            for &j in &selected[a + 1..] {
                let (xi, yi) = ((i as u32 % side) as f64, (i as u32 / side) as f64);
                let (xj, yj) = ((j as u32 % side) as f64, (j as u32 / side) as f64);
                let dx = (xi - xj).abs().min(s - (xi - xj).abs());
                let dy = (yi - yj).abs().min(s - (yi - yj).abs());
                best = best.min((dx * dx + dy * dy).sqrt());
            }
        }
        best
    }

    #[test]
    fn ranks_are_a_permutation() {
        let mut r = rank_map().to_vec();
        r.sort_unstable();
        assert!(r.iter().enumerate().all(|(i, &v)| i as u32 == v));
    }

    #[test]
    fn every_density_is_better_spread_than_white_noise() {
        let ranks = rank_map();
        let n = (TILE * TILE) as usize;
        let mut rng = 7u64;
        for density in [0.25, 1.0 / 8.0, 1.0 / 16.0, 1.0 / 64.0, 1.0 / 256.0] {
            let k = (n as f64 * density) as usize;
            let blue: Vec<usize> = (0..n).filter(|&i| (ranks[i] as usize) < k).collect();
            assert_eq!(blue.len(), k);
            // White noise: the same count, chosen uniformly at random.
            let mut order: Vec<(f64, usize)> = (0..n).map(|i| (next(&mut rng), i)).collect();
            order.sort_by(|a, b| a.0.total_cmp(&b.0));
            let white: Vec<usize> = order[..k].iter().map(|(_, i)| *i).collect();
            let (b, w) = (min_distance(TILE, &blue), min_distance(TILE, &white));
            // The mean spacing is 1/√density. Measured here: blue noise keeps 0.67–0.71 of it
            // between the closest two samples; white noise lets samples touch (distance 1)
            // down to 1/64 and reaches only 5.1 px at 1/256 where blue keeps 11.2.
            let spacing = 1.0 / density.sqrt();
            assert!(
                b >= 0.65 * spacing,
                "density {density}: blue min distance {b}, spacing {spacing}"
            );
            assert!(b >= 1.4 * w, "density {density}: blue {b} vs white {w}");
        }
    }

    #[test]
    fn thresholds_select_exactly_the_requested_share() {
        let t = thresholds();
        assert_eq!(
            t.iter().filter(|&&v| v < 1.0).count(),
            t.len(),
            "p = 1 samples every pixel"
        );
        assert_eq!(
            t.iter().filter(|&&v| v < 0.0).count(),
            0,
            "p = 0 samples none"
        );
        assert_eq!(t.iter().filter(|&&v| v < 0.25).count(), t.len() / 4);
    }
}
