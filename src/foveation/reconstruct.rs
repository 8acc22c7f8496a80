//! CPU twins of the reconstruction passes (`shaders/jfa.wgsl`, `shaders/resolve.wgsl`): jump
//! flooding for each pixel's nearest shaded sample, and the windowed approximate Sibson
//! (natural-neighbour) interpolation of the thesis (Listing 4, in gather form).
//!
//! Seeds are packed pixel coordinates `x | y << 16`; `NO_SEED` marks a pixel with none.
//! Distances are squared integers, so the GPU and CPU agree bit for bit.

pub const NO_SEED: u32 = u32::MAX;

pub fn pack(x: u32, y: u32) -> u32 {
    x | (y << 16)
}

pub fn unpack(s: u32) -> (i32, i32) {
    ((s & 0xFFFF) as i32, (s >> 16) as i32)
}

fn dist2(s: u32, x: i32, y: i32) -> i64 {
    if s == NO_SEED {
        return i64::MAX;
    }
    let (sx, sy) = unpack(s);
    let (dx, dy) = (i64::from(sx - x), i64::from(sy - y));
    dx * dx + dy * dy
}

/// Jump sizes of a frame's JFA passes: fewer when ξ (never below `min_xi`) bounds the holes.
/// The count keeps the parity of the full list, so the extra unit step the full list would end
/// on is kept (it refines the result) and frames stay comparable across ξ.
pub fn frame_jfa_steps(width: u32, height: u32, min_probability: f32, min_xi: f32) -> Vec<u32> {
    let full = jfa_steps(width, height);
    let mut steps = jfa_steps_within(width, height, max_gap_for(min_probability.max(min_xi)));
    if steps.len() % 2 != full.len() % 2 {
        steps.push(1);
    }
    steps
}

/// Jump sizes: N/2, N/4, …, 1 with N the power of two ≥ the larger side, then one more pass of
/// step 1 ("JFA+1", Rong & Tan 2006), which removes most of plain JFA's rare errors.
pub fn jfa_steps(width: u32, height: u32) -> Vec<u32> {
    jfa_steps_within(width, height, u32::MAX)
}

/// Like [`jfa_steps`], but starting no higher than needed to reach a seed `max_gap` pixels away:
/// when sampling guarantees a seed at least that close, the long jumps find nothing new.
/// Pixels farther than the reach are left without a seed (the resolve pass shades them).
pub fn jfa_steps_within(width: u32, height: u32, max_gap: u32) -> Vec<u32> {
    let n = width.max(height).max(1).next_power_of_two();
    // The first jump reaches max_gap: the smallest power of two ≥ it (at least 2).
    let reach = max_gap.max(2).checked_next_power_of_two().unwrap_or(n);
    let mut steps = Vec::new();
    let mut k = (n / 2).min(reach);
    while k >= 1 {
        steps.push(k);
        k /= 2;
    }
    steps.push(1);
    steps
}

/// One JFA pass: each pixel keeps the nearest of the seeds known to itself and to the 8
/// pixels `step` away. Ties keep the earlier candidate (the shader scans in the same order).
pub fn jfa_pass(width: u32, height: u32, step: u32, seeds: &[u32]) -> Vec<u32> {
    let (w, h, k) = (width as i32, height as i32, step as i32);
    let mut out = vec![NO_SEED; seeds.len()];
    for y in 0..h {
        for x in 0..w {
            let mut best = seeds[(y * w + x) as usize];
            let mut best_d = dist2(best, x, y);
            for j in -1..=1 {
                for i in -1..=1 {
                    let (qx, qy) = (x + i * k, y + j * k);
                    if qx < 0 || qy < 0 || qx >= w || qy >= h {
                        continue;
                    }
                    let s = seeds[(qy * w + qx) as usize];
                    let d = dist2(s, x, y);
                    if d < best_d {
                        best = s;
                        best_d = d;
                    }
                }
            }
            out[(y * w + x) as usize] = best;
        }
    }
    out
}

/// Nearest seed of every pixel by jump flooding.
pub fn jfa(width: u32, height: u32, seeds: &[u32]) -> Vec<u32> {
    jfa_with_steps(width, height, seeds, &jfa_steps(width, height))
}

pub fn jfa_with_steps(width: u32, height: u32, seeds: &[u32], steps: &[u32]) -> Vec<u32> {
    steps
        .iter()
        .fold(seeds.to_vec(), |s, &k| jfa_pass(width, height, k, &s))
}

/// The largest distance to the nearest seed that sampling at minimum probability ξ leaves,
/// with margin: blue noise at density ξ keeps holes below about 1.5 sample spacings (1/√ξ);
/// twice the spacing is used.
pub fn max_gap_for(xi: f32) -> u32 {
    let xi = xi.clamp(1e-6, 1.0);
    (2.0 / xi.sqrt()).ceil() as u32
}

/// Nearest seed of every pixel by exhaustive search: the ground truth JFA is tested against.
pub fn brute_force_nearest(width: u32, height: u32, seeds: &[u32]) -> Vec<u32> {
    let sites: Vec<u32> = seeds.iter().copied().filter(|&s| s != NO_SEED).collect();
    (0..width * height)
        .map(|k| {
            let (x, y) = ((k % width) as i32, (k / width) as i32);
            sites
                .iter()
                .copied()
                .min_by_key(|&s| dist2(s, x, y))
                .unwrap_or(NO_SEED)
        })
        .collect()
}

/// Squared distance from pixel `k` to its seed (`i64::MAX` without one), for error bounds.
pub fn seed_distance2(width: u32, k: usize, seed: u32) -> i64 {
    dist2(seed, (k as u32 % width) as i32, (k as u32 / width) as i32)
}

/// The Sibson window at a pixel: the ξ-derived bound `max_window`, shrunk to twice the distance
/// to the pixel's nearest sample (natural neighbours lie about that far away), at least 1.
pub fn sibson_window(max_window: u32, nearest_dist2: i64) -> i32 {
    if nearest_dist2 == i64::MAX {
        return 0;
    }
    let d = (nearest_dist2 as f64).sqrt();
    ((2.0 * d).ceil() as i32).clamp(1, max_window.max(1) as i32)
}

/// Fills every covered pixel from the shaded seeds. `values[k]` is meaningful where pixel k is
/// a seed. Nearest mode copies the nearest seed's value (Voronoi cells); Sibson mode averages,
/// over every covered pixel q in the window whose empty circle (radius |q − s(q)|) contains p,
/// the value of q's nearest seed. Seeds keep their own value. Pixels with no seed at all get
/// `fallback[k]`.
pub fn reconstruct(
    width: u32,
    height: u32,
    nearest: &[u32],
    covered: &[bool],
    values: &[[f32; 4]],
    fallback: &[[f32; 4]],
    sibson_max_window: Option<u32>,
) -> Vec<[f32; 4]> {
    let (w, h) = (width as i32, height as i32);
    let value_of = |s: u32| {
        let (sx, sy) = unpack(s);
        values[(sy * w + sx) as usize]
    };
    (0..(w * h) as usize)
        .map(|k| {
            let (x, y) = (k as i32 % w, k as i32 / w);
            let s = nearest[k];
            if s == NO_SEED {
                return fallback[k];
            }
            let d2 = dist2(s, x, y);
            let Some(max_window) = sibson_max_window else {
                return value_of(s);
            };
            if d2 == 0 || !covered[k] {
                return value_of(s);
            }
            let j = sibson_window(max_window, d2);
            let (mut sum, mut count) = ([0.0f32; 4], 0u32);
            for qy in (y - j).max(0)..=(y + j).min(h - 1) {
                for qx in (x - j).max(0)..=(x + j).min(w - 1) {
                    let q = (qy * w + qx) as usize;
                    if !covered[q] || nearest[q] == NO_SEED {
                        continue;
                    }
                    let r2 = dist2(nearest[q], qx, qy);
                    let (dx, dy) = (i64::from(qx - x), i64::from(qy - y));
                    if dx * dx + dy * dy > r2 {
                        continue;
                    }
                    let v = value_of(nearest[q]);
                    for c in 0..4 {
                        sum[c] += v[c];
                    }
                    count += 1;
                }
            }
            if count == 0 {
                value_of(s)
            } else {
                sum.map(|v| v / count as f32)
            }
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    fn random_seeds(w: u32, h: u32, density: f64, mut state: u64) -> Vec<u32> {
        (0..w * h)
            .map(|k| {
                state = state
                    .wrapping_mul(6364136223846793005)
                    .wrapping_add(1442695040888963407);
                let r = (state >> 33) as f64 / (1u64 << 31) as f64;
                if r < density {
                    pack(k % w, k / w)
                } else {
                    NO_SEED
                }
            })
            .collect()
    }

    #[test]
    fn jfa_agrees_with_brute_force_on_random_seed_sets() {
        for (w, h, density, seed) in [
            (96, 64, 0.01, 1),
            (61, 47, 0.05, 2),
            (128, 128, 0.002, 3),
            (40, 90, 0.3, 4),
        ] {
            let seeds = random_seeds(w, h, density, seed);
            let fast = jfa(w, h, &seeds);
            let exact = brute_force_nearest(w, h, &seeds);
            let mut wrong = 0;
            for k in 0..seeds.len() {
                let (df, de) = (
                    seed_distance2(w, k, fast[k]),
                    seed_distance2(w, k, exact[k]),
                );
                if df != de {
                    wrong += 1;
                    // JFA+1's errors are near-ties: the seed found is at most a pixel farther.
                    let (df, de) = ((df as f64).sqrt(), (de as f64).sqrt());
                    assert!(
                        df - de <= 1.5,
                        "{w}x{h}: pixel {k} got a seed {df:.2} away, nearest is {de:.2}"
                    );
                }
            }
            assert!(
                wrong * 100 <= seeds.len(),
                "{w}x{h} density {density}: {wrong} wrong pixels"
            );
        }
    }

    #[test]
    fn no_seeds_leave_every_pixel_without_one_and_fallback_fills_it() {
        let seeds = vec![NO_SEED; 12];
        let near = jfa(4, 3, &seeds);
        assert!(near.iter().all(|&s| s == NO_SEED));
        let fb = vec![[0.25; 4]; 12];
        let out = reconstruct(4, 3, &near, &[true; 12], &[[9.0; 4]; 12], &fb, Some(4));
        assert!(out.iter().all(|v| *v == [0.25; 4]));
    }

    #[test]
    fn a_single_seed_floods_the_whole_frame() {
        let mut seeds = vec![NO_SEED; 50 * 30];
        seeds[17 * 50 + 3] = pack(3, 17);
        assert!(jfa(50, 30, &seeds).iter().all(|&s| s == pack(3, 17)));
    }

    /// Mean absolute error of reconstructing f(x, y) = 0.02x − 0.013y + 0.5 from random samples,
    /// over interior non-seed pixels.
    fn ramp_error(sibson: Option<u32>) -> f64 {
        let (w, h) = (96u32, 96u32);
        let seeds = random_seeds(w, h, 0.03, 11);
        let f = |k: usize| 0.02 * (k as u32 % w) as f32 - 0.013 * (k as u32 / w) as f32 + 0.5;
        let values: Vec<[f32; 4]> = (0..seeds.len()).map(|k| [f(k); 4]).collect();
        let near = jfa(w, h, &seeds);
        let out = reconstruct(
            w,
            h,
            &near,
            &vec![true; seeds.len()],
            &values,
            &values,
            sibson,
        );
        let mut err = 0.0;
        let mut n = 0;
        for k in 0..seeds.len() {
            let (x, y) = (k as u32 % w, k as u32 / w);
            if seeds[k] == NO_SEED && (16..80).contains(&x) && (16..80).contains(&y) {
                err += f64::from((out[k][0] - f(k)).abs());
                n += 1;
            }
        }
        err / n as f64
    }

    #[test]
    fn sibson_nearly_reproduces_a_linear_function() {
        let nearest = ramp_error(None);
        let sibson = ramp_error(Some(16));
        // Natural-neighbour interpolation has linear precision; the discrete, windowed version
        // keeps most of it. Nearest-seed copies are off by about a cell radius times the slope.
        assert!(
            sibson < 0.35 * nearest,
            "sibson {sibson:.4} vs nearest {nearest:.4}"
        );
        assert!(
            sibson < 0.01,
            "sibson mean error {sibson:.4} on a ramp of slope 0.02/px"
        );
    }

    #[test]
    fn seeds_keep_their_own_value() {
        let (w, h) = (20, 20);
        let seeds = random_seeds(w, h, 0.1, 5);
        let values: Vec<[f32; 4]> = (0..400).map(|k| [k as f32; 4]).collect();
        let out = reconstruct(
            w,
            h,
            &jfa(w, h, &seeds),
            &[true; 400],
            &values,
            &values,
            Some(8),
        );
        for (k, s) in seeds.iter().enumerate() {
            if *s != NO_SEED {
                assert_eq!(out[k], values[k]);
            }
        }
    }
}
