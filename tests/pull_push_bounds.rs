//! The pixel bound of pull-push's CPU twin on a highlight's steep flank (the GPU's fill applies
//! the same bound: `tests/pull_push.rs` holds the two together).

use fovea::foveation::pull_push::{level_size, pyramid, Key};

#[test]
fn no_pixel_on_a_steep_flank_is_darker_than_its_parents() {
    // Ratio 1 to 100 over a few pixels (a specular highlight over the Lambert proxy), sampled
    // at 1 in 5: planes fitted to the flank, evaluated a pixel away, fall far below every
    // value around (dark dots beside the highlight). A filled pixel inside the frame may not
    // fall below the lowest of its four level-1 parents' values.
    let (w, h) = (40u32, 30u32);
    let f = |x: f32, y: f32| 1.0 + 99.0 * (-((x - 20.0).powi(2) + (y - 15.0).powi(2)) / 8.0).exp();
    let samples: Vec<Option<[f32; 3]>> = (0..w * h)
        .map(|k| ((k * 7919) % 5 == 0).then(|| [f((k % w) as f32 + 0.5, (k / w) as f32 + 0.5); 3]))
        .collect();
    let keys = vec![
        Key {
            depth: 1.0,
            material: 1.0
        };
        (w * h) as usize
    ];
    let levels = pyramid(w, h, &samples, &keys);
    let (pw, _) = level_size(w, h, 1);
    let mut checked = 0;
    for y in 1..h - 1 {
        for x in 1..w - 1 {
            let k = (y * w + x) as usize;
            if samples[k].is_some() {
                continue;
            }
            // The parents whose centres surround pixel (x, y): level-1 cells ⌈x/2⌉ − 1 and on.
            let (bx, by) = (x.div_ceil(2) - 1, y.div_ceil(2) - 1);
            let lowest = [(bx, by), (bx + 1, by), (bx, by + 1), (bx + 1, by + 1)]
                .map(|(px, py)| levels[1][(py * pw + px) as usize].c[0])
                .into_iter()
                .fold(f32::INFINITY, f32::min);
            let v = levels[0][k].c[0];
            assert!(
                v >= lowest,
                "pixel ({x}, {y}): {v} below its parents' {lowest}"
            );
            checked += 1;
        }
    }
    assert!(checked > 500, "{checked} pixels checked");
}
