//! RGB → I420 (BT.601, full range, 4:2:0) for the H.264 encoder, rounded to nearest.
//!
//! openh264's own converter truncates every sample towards zero: half a code value lost on
//! average in each of Y, U and V, a bias and banding that FLIP counts. Measured on a 1280×720
//! `gallery` frame, the round trip RGB → I420 → RGB alone (no encoding) scored foveal FLIP
//! 0.056 with truncation and 0.032 rounded, the same conversion otherwise (`docs/encoding.md`).
//!
//! Y = 0.299 R + 0.587 G + 0.114 B; Cb, Cr = 128 + (B − Y, R − Y)/k with k = 1.772 and 1.402
//! (JFIF's full range, signalled in the stream's VUI): limited range (Y 16–235) has 16% coarser
//! steps, and on `bunny-marble` its round trip alone scored worse in the fovea than JPEG q85
//! (docs/encoding.md). Chroma from the mean of each 2×2 block's RGB.

pub use super::picture::I420;

/// Writes the I420 planes of `rgba` (`width`×`height`, both even) into `y` (w·h), `u` and `v`
/// (w/2 · h/2 each).
///
/// Fixed point, two rows at a time: the float version of the same formulas took 3.6 ms a
/// 720p frame, more than openh264's own P-frame encode (2–3 ms). The coefficients carry 24
/// fractional bits (chroma's 22, applied to sums of four), so a result differs from exact
/// arithmetic only where the exact value lies within ~1e-5 of a rounding boundary, as f32
/// arithmetic (the GPU pass's) does; `tests` bound it against an f64 reference. On a CPU
/// with AVX2 the same arithmetic is compiled for it: 1.1 → 0.8 ms a 720p frame here.
pub fn rgba_to_i420(
    rgba: &[u8],
    width: usize,
    height: usize,
    y: &mut [u8],
    u: &mut [u8],
    v: &mut [u8],
) {
    #[cfg(target_arch = "x86_64")]
    if std::arch::is_x86_feature_detected!("avx2") {
        // SAFETY: the CPU has AVX2, checked just above; the function is otherwise safe.
        unsafe { rgba_to_i420_avx2(rgba, width, height, y, u, v) };
        return;
    }
    convert(rgba, width, height, y, u, v, false);
}

#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2")]
fn rgba_to_i420_avx2(
    rgba: &[u8],
    width: usize,
    height: usize,
    y: &mut [u8],
    u: &mut [u8],
    v: &mut [u8],
) {
    convert(rgba, width, height, y, u, v, true);
}

/// [`rgba_to_i420`]'s body, inlined into each caller so it is compiled for its CPU features.
/// With `luma_by_rows` luma runs as a plain loop over each row, which AVX2 vectorises (8
/// pixels a step; 0.9 → 0.3 ms a 720p frame); without AVX2 that loop is slower than luma
/// computed inside the chroma's 2×2 blocks (1.4 against 1.1 ms for the whole conversion).
#[inline(always)]
fn convert(
    rgba: &[u8],
    width: usize,
    height: usize,
    y: &mut [u8],
    u: &mut [u8],
    v: &mut [u8],
    luma_by_rows: bool,
) {
    let luma_row = |row: &[u8], out: &mut [u8]| {
        for (o, p) in out.iter_mut().zip(row.chunks_exact(4)) {
            *o = luma(p);
        }
    };
    let hw = width / 2;
    let mut rows = rgba.chunks_exact(4 * width);
    for by in 0..height / 2 {
        let (Some(top), Some(bottom)) = (rows.next(), rows.next()) else {
            return;
        };
        let y_rows = &mut y[2 * by * width..(2 * by + 2) * width];
        let (y_top, y_bottom) = y_rows.split_at_mut(width);
        if luma_by_rows {
            luma_row(top, y_top);
            luma_row(bottom, y_bottom);
        }
        let u_row = &mut u[by * hw..(by + 1) * hw];
        let v_row = &mut v[by * hw..(by + 1) * hw];
        let blocks = top
            .chunks_exact(8)
            .zip(bottom.chunks_exact(8))
            .zip(y_top.chunks_exact_mut(2).zip(y_bottom.chunks_exact_mut(2)))
            .zip(u_row.iter_mut().zip(v_row.iter_mut()));
        for (((t, b), (yt, yb)), (cu, cv)) in blocks {
            if !luma_by_rows {
                yt[0] = luma(&t[0..4]);
                yt[1] = luma(&t[4..8]);
                yb[0] = luma(&b[0..4]);
                yb[1] = luma(&b[4..8]);
            }
            let sum = |c: usize| {
                i64::from(t[c]) + i64::from(t[c + 4]) + i64::from(b[c]) + i64::from(b[c + 4])
            };
            (*cu, *cv) = block_chroma(sum(0), sum(1), sum(2));
        }
    }
}

/// Y = 0.299 R + 0.587 G + 0.114 B of one pixel (its first three bytes), rounded.
#[inline(always)]
fn luma(p: &[u8]) -> u8 {
    // u32 holds 255 · 2^24 + 2^23.
    let (r, g, b) = (u32::from(p[0]), u32::from(p[1]), u32::from(p[2]));
    ((5_016_388 * r + 9_848_226 * g + 1_912_603 * b + (1 << 23)) >> 24) as u8
}

/// Cb = 128 + (B − Y)/1.772 and Cr = 128 + (R − Y)/1.402 of the mean of four pixels, from
/// their sums of R, G and B.
#[inline(always)]
fn block_chroma(r: i64, g: i64, b: i64) -> (u8, u8) {
    const ONE: i64 = 1 << 24;
    let code = |x: i64| ((128 * ONE + x + ONE / 2) >> 24).clamp(0, 255) as u8;
    (
        code(2_097_152 * b - 707_730 * r - 1_389_422 * g),
        code(2_097_152 * r - 1_756_103 * g - 341_049 * b),
    )
}

/// `rgba` converted to 8-bit YCbCr with the arithmetic of [`rgba_to_i420`] but chroma kept at
/// every pixel (4:4:4), and back as [`i420_to_rgba`] shows it: what 8-bit YCbCr costs a
/// picture before any chroma is subsampled (the codec sweep's floor rows).
pub fn ycbcr444_round_trip(rgba: &[u8], width: usize, height: usize) -> Vec<u8> {
    let n = width * height;
    let (mut y, mut u, mut v) = (vec![0; n], vec![0; n], vec![0; n]);
    for (i, p) in rgba.chunks_exact(4).take(n).enumerate() {
        let [r, g, b] = [0, 1, 2].map(|c| i64::from(p[c]));
        y[i] = luma(p);
        // The chroma of a 2×2 block of four copies of the pixel.
        (u[i], v[i]) = block_chroma(4 * r, 4 * g, 4 * b);
    }
    to_rgba(&y, width, height, |px, py| {
        let c = py * width + px;
        (f32::from(u[c]), f32::from(v[c]))
    })
}

/// A decoded picture (any strides) as RGBA, rounded as `i420_to_rgba`.
pub fn picture_to_rgba(pic: &impl openh264::formats::YUVSource) -> Vec<u8> {
    let (w, h) = pic.dimensions();
    let (y, u, v) = planes(pic);
    i420_to_rgba(&y, &u, &v, w, h)
}

/// A decoded picture as RGBA, chroma filtered as `i420_to_rgba_filtered`.
pub fn picture_to_rgba_filtered(pic: &impl openh264::formats::YUVSource) -> Vec<u8> {
    let (w, h) = pic.dimensions();
    let (y, u, v) = planes(pic);
    i420_to_rgba_filtered(&y, &u, &v, w, h)
}

/// A picture's planes, tightly packed.
fn planes(pic: &impl openh264::formats::YUVSource) -> (Vec<u8>, Vec<u8>, Vec<u8>) {
    use openh264::formats::YUVSource;
    let (w, h) = pic.dimensions();
    let mut tight = I420::new(w, h);
    tight.copy_from_source(pic);
    (tight.y().to_vec(), tight.u().to_vec(), tight.v().to_vec())
}

/// The inverse, for tests and measurements (what a BT.601 full-range decoder shows), each
/// chroma sample repeated over its 2×2 block.
pub fn i420_to_rgba(y: &[u8], u: &[u8], v: &[u8], width: usize, height: usize) -> Vec<u8> {
    let hw = width / 2;
    to_rgba(y, width, height, |px, py| {
        let c = (py / 2) * hw + px / 2;
        (f32::from(u[c]), f32::from(v[c]))
    })
}

/// The inverse with chroma interpolated bilinearly between block centres (where
/// `rgba_to_i420` takes each block's mean), as a decoder that filters its chroma shows it.
pub fn i420_to_rgba_filtered(y: &[u8], u: &[u8], v: &[u8], width: usize, height: usize) -> Vec<u8> {
    let (hw, hh) = (width / 2, height / 2);
    // Block centre i sits at luma coordinate 2i + 0.5: pixel x reads chroma at (x − 0.5)/2.
    let taps = |x: usize, n: usize| {
        let last = n.max(1) - 1;
        let c = ((x as f32 - 0.5) * 0.5).clamp(0.0, last as f32);
        let i = (c.floor() as usize).min(last);
        (i, (i + 1).min(last), c - i as f32)
    };
    to_rgba(y, width, height, |px, py| {
        let (x0, x1, fx) = taps(px, hw);
        let (y0, y1, fy) = taps(py, hh);
        let at = |plane: &[u8]| {
            let p = |i: usize, j: usize| f32::from(plane[j * hw + i]);
            let top = p(x0, y0) + fx * (p(x1, y0) - p(x0, y0));
            let bottom = p(x0, y1) + fx * (p(x1, y1) - p(x0, y1));
            top + fy * (bottom - top)
        };
        (at(u), at(v))
    })
}

/// BT.601 full range to RGBA, rounded, with each pixel's (Cb, Cr) codes from `chroma`.
fn to_rgba(
    y: &[u8],
    width: usize,
    height: usize,
    chroma: impl Fn(usize, usize) -> (f32, f32),
) -> Vec<u8> {
    let mut out = Vec::with_capacity(width * height * 4);
    for py in 0..height {
        for px in 0..width {
            let l = f32::from(y[py * width + px]);
            let (u, v) = chroma(px, py);
            let cb = (u - 128.0) * 1.772;
            let cr = (v - 128.0) * 1.402;
            let (r, b) = (l + cr, l + cb);
            let g = (l - 0.299 * r - 0.114 * b) / 0.587;
            out.extend([r, g, b].map(|x| (x + 0.5).clamp(0.0, 255.0) as u8));
            out.push(255);
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    fn planes_of(rgba: &[u8], w: usize, h: usize) -> (Vec<u8>, Vec<u8>, Vec<u8>) {
        let (mut y, mut u, mut v) = (vec![0; w * h], vec![0; w * h / 4], vec![0; w * h / 4]);
        rgba_to_i420(rgba, w, h, &mut y, &mut u, &mut v);
        (y, u, v)
    }

    #[test]
    fn black_white_and_grey_land_on_the_standards_codes() {
        for (grey, luma) in [(0u8, 0u8), (255, 255), (128, 128)] {
            let (y, u, v) = planes_of(&[grey, grey, grey, 255].repeat(4), 2, 2);
            assert_eq!((y[0], u[0], v[0]), (luma, 128, 128), "grey {grey}");
        }
        // Saturated primaries reach the chroma extremes without wrapping.
        let (_, u, v) = planes_of(&[0, 0, 255, 255].repeat(4), 2, 2);
        assert_eq!(u[0], 255);
        let (_, _, v_red) = planes_of(&[255, 0, 0, 255].repeat(4), 2, 2);
        assert_eq!((v[0] < 128, v_red[0]), (true, 255));
    }

    /// The exact formulas in f64, rounded to nearest: what the fixed point must match.
    fn exact(rgba: &[u8], w: usize, h: usize) -> (Vec<u8>, Vec<u8>, Vec<u8>) {
        let px = |x: usize, y: usize, c: usize| f64::from(rgba[(y * w + x) * 4 + c]);
        let luma = |r: f64, g: f64, b: f64| 0.299 * r + 0.587 * g + 0.114 * b;
        let q = |x: f64| (x + 0.5).floor().clamp(0.0, 255.0) as u8;
        let mut y = vec![0; w * h];
        let (mut u, mut v) = (vec![0; w * h / 4], vec![0; w * h / 4]);
        for j in 0..h {
            for i in 0..w {
                y[j * w + i] = q(luma(px(i, j, 0), px(i, j, 1), px(i, j, 2)));
            }
        }
        for j in 0..h / 2 {
            for i in 0..w / 2 {
                let m = |c| {
                    (px(2 * i, 2 * j, c)
                        + px(2 * i + 1, 2 * j, c)
                        + px(2 * i, 2 * j + 1, c)
                        + px(2 * i + 1, 2 * j + 1, c))
                        / 4.0
                };
                let (r, g, b) = (m(0), m(1), m(2));
                let l = luma(r, g, b);
                u[j * w / 2 + i] = q(128.0 + (b - l) / 1.772);
                v[j * w / 2 + i] = q(128.0 + (r - l) / 1.402);
            }
        }
        (y, u, v)
    }

    #[test]
    fn the_fixed_point_matches_exact_arithmetic_but_at_rounding_ties() {
        // Every byte value in every channel, scrambled over a 256×256 picture.
        let (w, h) = (256, 256);
        let rgba = crate::encode::noise_rgba(w * h, 0x2545_f491);
        let (got, want) = (planes_of(&rgba, w, h), exact(&rgba, w, h));
        let (mut off, mut n) = (0usize, 0usize);
        for (a, b) in [(&got.0, &want.0), (&got.1, &want.1), (&got.2, &want.2)] {
            for (x, e) in a.iter().zip(b.iter()) {
                let d = (i32::from(*x) - i32::from(*e)).abs();
                assert!(d <= 1, "{x} against {e}");
                off += usize::from(d == 1);
                n += 1;
            }
        }
        // Exact ties (chroma of four pixels can land on x.5) go either way.
        assert!(off * 2_000 < n, "{off} of {n} one code value off");
    }

    #[test]
    fn both_loop_orders_give_the_same_bytes() {
        // Odd-sized in blocks, every byte value: luma by rows (the AVX2 build) and luma inside
        // the 2×2 blocks (any other CPU) are the same arithmetic.
        let (w, h) = (198, 66);
        let rgba = crate::encode::noise_rgba(w * h, 0x9e37_79b9);
        let planes = |by_rows| {
            let (mut y, mut u, mut v) = (vec![0; w * h], vec![0; w * h / 4], vec![0; w * h / 4]);
            convert(&rgba, w, h, &mut y, &mut u, &mut v, by_rows);
            (y, u, v)
        };
        assert!(planes(true) == planes(false));
        assert!(planes(true) == planes_of(&rgba, w, h));
    }

    #[test]
    fn a_flat_colour_round_trips_within_two_code_values() {
        // Every colour on a coarse grid, each a flat 2×2 block (no chroma subsampling loss).
        for r in (0..=255).step_by(15) {
            for g in (0..=255).step_by(15) {
                for b in (0..=255).step_by(15) {
                    let px = [r as u8, g as u8, b as u8, 255].repeat(4);
                    let (y, u, v) = planes_of(&px, 2, 2);
                    let back = i420_to_rgba(&y, &u, &v, 2, 2);
                    for k in 0..3 {
                        let d = (i32::from(back[k]) - i32::from(px[k])).abs();
                        assert!(d <= 2, "({r}, {g}, {b}) → {:?}", &back[..3]);
                    }
                }
            }
        }
    }

    #[test]
    fn full_chroma_keeps_each_pixels_colour_where_subsampling_mixes_them() {
        // Red and blue pixels in a checkerboard: every 2×2 block mixes them.
        let (w, h) = (6, 4);
        let px: Vec<u8> = (0..w * h)
            .flat_map(|i| {
                let red = (i % w + i / w) % 2 == 0;
                if red {
                    [230, 20, 10, 255]
                } else {
                    [15, 30, 220, 255]
                }
            })
            .collect();
        let worst = |back: &[u8]| {
            let diff = |(a, b): (&u8, &u8)| (i32::from(*a) - i32::from(*b)).abs();
            back.iter().zip(&px).map(diff).max().unwrap_or(0)
        };
        let full = ycbcr444_round_trip(&px, w, h);
        assert_eq!(full.len(), px.len());
        assert!(worst(&full) <= 2, "4:4:4 off by {}", worst(&full));
        let (y, u, v) = planes_of(&px, w, h);
        assert!(worst(&i420_to_rgba(&y, &u, &v, w, h)) > 50);
        // A flat picture comes back as the 4:2:0 one does, to the byte.
        let flat = [90, 160, 40, 255].repeat(w * h);
        let (y, u, v) = planes_of(&flat, w, h);
        assert_eq!(
            ycbcr444_round_trip(&flat, w, h),
            i420_to_rgba(&y, &u, &v, w, h)
        );
    }

    #[test]
    fn rounding_leaves_no_bias() {
        // A smooth ramp: the mean error over many pixels is ~0 (truncation would give ≈ −0.5
        // code values in Y, about −0.6 in RGB).
        let (w, h) = (256, 16);
        let rgba: Vec<u8> = (0..w * h)
            .flat_map(|i| {
                let x = (i % w) as u8;
                [x, x / 2 + 40, 255 - x, 255]
            })
            .collect();
        let (y, u, v) = planes_of(&rgba, w, h);
        let back = i420_to_rgba(&y, &u, &v, w, h);
        let bias: f64 = back
            .chunks_exact(4)
            .zip(rgba.chunks_exact(4))
            .map(|(a, b)| {
                (0..3)
                    .map(|k| f64::from(a[k]) - f64::from(b[k]))
                    .sum::<f64>()
            })
            .sum::<f64>()
            / (w * h * 3) as f64;
        assert!(bias.abs() < 0.1, "mean error {bias}");
    }

    #[test]
    fn filtered_chroma_agrees_on_flat_colour_and_ramps_across_a_colour_edge() {
        let (w, h) = (8, 4);
        // Left half red, right half blue: one chroma edge between blocks 1 and 2.
        let rgba: Vec<u8> = (0..w * h)
            .flat_map(|i| {
                if i % w < 4 {
                    [200u8, 30, 30, 255]
                } else {
                    [30, 30, 200, 255]
                }
            })
            .collect();
        let (y, u, v) = planes_of(&rgba, w, h);
        let nearest = i420_to_rgba(&y, &u, &v, w, h);
        let filtered = i420_to_rgba_filtered(&y, &u, &v, w, h);
        // Far from the edge both are the same; next to it the filtered one blends.
        for x in [0, 7] {
            assert_eq!(
                &nearest[x * 4..x * 4 + 3],
                &filtered[x * 4..x * 4 + 3],
                "x {x}"
            );
        }
        let red_at = |img: &[u8], x: usize| img[x * 4];
        assert!(red_at(&filtered, 3) < red_at(&nearest, 3));
        assert!(red_at(&filtered, 4) > red_at(&nearest, 4));
        // Odd sizes of one block and edge blocks stay in range.
        let one = i420_to_rgba_filtered(&[100; 4], &[128], &[128], 2, 2);
        assert_eq!(one.len(), 16);
    }
}
