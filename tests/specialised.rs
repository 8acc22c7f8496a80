//! Pipelines specialised for a frame's mode bits (`graph::Recorder::by_mode`): a
//! stream whose settings change between frames gets the new mode's pipeline, and the
//! still-camera reprojection those bits select reuses what the general test would.

mod common;

use common::frames::{foveated, inspect, renderer};
use fovea::render::uniforms::{FLAG_REUSED, FLAG_SAMPLED};
use fovea::settings::Noise;

#[test]
fn a_stream_that_changes_its_mode_gets_that_modes_pipeline() {
    let mut r = renderer();
    let mut req = foveated("balanced", 96, 72, [0.3, 0.4]);
    req.stream = 1;
    r.render(&req).unwrap();
    let with = inspect(&r, &req).probability;
    // Same stream, saliency off: a pipeline left from the frame before would still add it.
    req.settings.foveation.saliency = false;
    r.render(&req).unwrap();
    let without = inspect(&r, &req).probability;
    let mut fresh = req.clone();
    fresh.stream = 2;
    r.render(&fresh).unwrap();
    assert_eq!(
        without,
        inspect(&r, &fresh).probability,
        "the same settings on a new stream"
    );
    let raised = with.iter().zip(&without).filter(|(a, b)| a > b).count();
    assert!(
        with.iter().zip(&without).all(|(a, b)| a >= b),
        "saliency only raises the probability"
    );
    assert!(raised > 0, "saliency raised no pixel on the bunny");
    // And back: the first mode's pipeline again.
    req.settings.foveation.saliency = true;
    r.render(&req).unwrap();
    assert_eq!(inspect(&r, &req).probability, with);
}

#[test]
fn a_still_camera_reuses_what_a_camera_moved_by_a_hair_reuses() {
    let mut r = renderer();
    let run = |r: &mut fovea::render::Renderer, stream: u64, nudge: f32| {
        let mut req = foveated("balanced", 320, 240, [0.3, 0.4]);
        req.stream = stream;
        r.render(&req).unwrap();
        // The gaze moves, so pixels sampled for the first frame and not the second can be
        // reused. A camera moved by a hair takes the general reprojection and its depth test.
        let scene = fovea::scene::Scene::builtin("bunny").unwrap();
        let mut cam = scene.file.camera;
        cam.eye[0] += nudge;
        req.camera = Some(cam);
        req.gaze = [0.65, 0.45];
        r.render(&req).unwrap();
        let img = inspect(r, &req);
        img.flags
            .iter()
            .map(|f| (f & FLAG_REUSED != 0, f & FLAG_SAMPLED != 0))
            .collect::<Vec<_>>()
    };
    let still = run(&mut r, 1, 0.0);
    let moved = run(&mut r, 2, 1e-4);
    let reused = still.iter().filter(|(u, _)| *u).count();
    assert!(reused * 20 > still.len(), "only {reused} reused");
    let differ = still.iter().zip(&moved).filter(|(a, b)| a != b).count();
    // Only a pixel whose reprojection crosses a pixel edge or a silhouette may differ.
    assert!(
        differ * 200 < still.len(),
        "{differ} of {} pixels decided differently",
        still.len()
    );
}

/// Sixteen modes on one renderer: the first `MAX_SPECIALISED` get their own pipelines, the
/// rest the general one. Rendered in opposite orders on two renderers, every mode is computed
/// specialised on one and general on the other, and both must agree.
#[test]
fn past_the_cap_the_general_pipeline_gives_the_same_frames() {
    // Sixteen modes must reach past the cap; a larger cap fails the build here.
    const { assert!(fovea::render::graph::MAX_SPECIALISED < 16) };
    let modes: Vec<_> = (0..16u32)
        .map(|m| {
            let mut req = foveated("balanced", 200, 150, [0.3, 0.4]);
            // A stream each: no history, so the order of rendering cannot matter.
            req.stream = u64::from(m) + 1;
            let fov = &mut req.settings.foveation;
            fov.saliency = m & 1 != 0;
            fov.edges_at_mar = m & 2 != 0;
            fov.noise = if m & 4 != 0 {
                Noise::White
            } else {
                Noise::Blue
            };
            req.settings.dof = m & 8 != 0;
            req
        })
        .collect();
    let decide = |r: &mut fovea::render::Renderer, req: &fovea::render::FrameRequest| {
        r.render(req).unwrap();
        let img = inspect(r, req);
        (img.probability, img.flags)
    };
    let (mut a, mut b) = (renderer(), renderer());
    let forward: Vec<_> = modes.iter().map(|q| decide(&mut a, q)).collect();
    let mut backward: Vec<_> = modes.iter().rev().map(|q| decide(&mut b, q)).collect();
    backward.reverse();
    for (m, (f, b)) in forward.iter().zip(&backward).enumerate() {
        assert!(
            f == b,
            "mode {m}: specialised and general pipelines disagree"
        );
    }
    assert_ne!(forward[0].0, forward[1].0, "saliency changed nothing");
}

/// With the camera still and the settings unchanged, the sampling pass reads the saliency the
/// first frame kept; the gaze moves over pixels that were in that frame's fovea, so a cache
/// that skipped the fovea would show here.
#[test]
fn kept_saliency_gives_what_computing_it_gives() {
    let mut r = renderer();
    let gazes = [[0.5, 0.5], [0.25, 0.3], [0.75, 0.65], [0.5, 0.45]];
    for (i, gaze) in gazes.into_iter().enumerate() {
        let mut kept = foveated("balanced", 200, 150, gaze);
        kept.stream = 1;
        r.render(&kept).unwrap();
        let mut fresh = kept.clone();
        fresh.stream = 10 + i as u64;
        r.render(&fresh).unwrap();
        assert_eq!(
            inspect(&r, &kept).probability,
            inspect(&r, &fresh).probability,
            "frame {i}, gaze {gaze:?}"
        );
    }
}
