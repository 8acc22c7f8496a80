//! The pixel fill runs only the tiles with a pixel to fill, the pull from the pixels only those
//! with a sample, level 1's push only where the fill reads its planes: the GPU's lists against
//! their CPU twin (`pass::pull_push_tiles::needed`) on frames with background, reused samples
//! and a fully sampled one. That the listed dispatches
//! leave every pixel as full ones would is checked in tests/pull_push.rs (the GPU against the
//! reconstruction's CPU twin, on a frame with tiles of background).

mod common;

use common::frames::{foveated, inspect, renderer};
use fovea::render::pass::pull_push_tiles::{fill_grid, level1_grid, needed, pull_grid};
use fovea::render::uniforms::{FLAG_COVERED, FLAG_REUSED, FLAG_SAMPLED};
use fovea::settings::Reconstruction;

#[test]
fn the_fill_lists_the_tiles_its_cpu_twin_does_and_skips_the_background() {
    let mut r = renderer();
    for (stream, scene, (w, h), frames) in [
        (1, "bunny", (333, 250), 1),
        // A second frame reuses last frame's samples: fewer pixels need filling.
        (2, "bunny-marble", (401, 301), 3),
        (3, "gallery", (257, 190), 2),
    ] {
        let mut req = foveated("balanced", w, h, [0.3, 0.6]);
        req.scene = scene.to_string();
        req.stream = stream;
        req.settings.foveation.reconstruction = Reconstruction::PullPush;
        for _ in 0..frames {
            r.render(&req).unwrap();
        }
        let img = inspect(&r, &req);
        let (fill, pull, level1) = needed(w, h, &img.flags);
        let got = (img.fill_tiles, img.pull_tiles, img.level1_tiles);
        assert_eq!(
            got,
            (fill, pull, level1),
            "{scene} {w}x{h}: listed against the twin"
        );
        let to_fill = |f: &u32| f & FLAG_COVERED != 0 && f & (FLAG_SAMPLED | FLAG_REUSED) == 0;
        assert!(img.flags.iter().any(to_fill), "{scene}: nothing to fill");
        // Every scene here has tiles of background, which need neither.
        let ((gx, gy), (px, py)) = (fill_grid(w, h), pull_grid(w, h));
        let (lx, ly) = level1_grid(w, h);
        assert!(
            fill > 0 && fill < gx * gy,
            "{scene} {w}x{h}: {fill} of {} fill tiles",
            gx * gy
        );
        assert!(
            pull > 0 && pull < px * py,
            "{scene} {w}x{h}: {pull} of {} pull tiles",
            px * py
        );
        assert!(
            level1 > 0 && level1 < lx * ly,
            "{scene} {w}x{h}: {level1} of {} level-1 tiles",
            lx * ly
        );
    }
}

#[test]
fn a_frame_with_every_pixel_sampled_lists_no_tile() {
    let mut r = renderer();
    let mut req = foveated("balanced", 96, 64, [0.5, 0.5]);
    req.settings.foveation.reconstruction = Reconstruction::PullPush;
    // Every pixel's probability clamped to 1: all are shaded, none is filled.
    req.settings.foveation.min_probability = 1.0;
    r.render(&req).unwrap();
    let img = inspect(&r, &req);
    assert!(img
        .flags
        .iter()
        .all(|f| f & FLAG_COVERED == 0 || f & FLAG_SAMPLED != 0));
    assert_eq!((img.fill_tiles, img.level1_tiles), (0, 0));
    assert_eq!(img.pull_tiles, needed(96, 64, &img.flags).1);
    assert!(img.pull_tiles > 0);
}
