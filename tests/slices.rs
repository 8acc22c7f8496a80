//! A frame split into parts (shading in bands of rows, other frames in between) gives the same
//! pixels as the frame rendered whole, foveated frames too.

use fovea::render::{FrameRequest, Progress, Renderer};
use fovea::settings::{Preset, Reconstruction, RenderSettings};

fn request(preset: Preset, stream: u64) -> FrameRequest {
    FrameRequest {
        settings: RenderSettings::of(preset),
        stream,
        ..FrameRequest::new("gallery", 200, 150)
    }
}

fn renderer() -> Renderer {
    Renderer::new().unwrap_or_else(|e| panic!("GPU tests need an adapter: {e}"))
}

/// Largest difference of any channel between two images.
fn max_diff(a: &[u8], b: &[u8]) -> u8 {
    assert_eq!(a.len(), b.len());
    a.iter()
        .zip(b)
        .map(|(x, y)| x.abs_diff(*y))
        .max()
        .unwrap_or(0)
}

#[test]
fn a_sliced_frame_with_others_between_its_parts_equals_the_whole_frame() {
    let mut r = renderer();
    // (preset, coarse gather, JFA + Sibson): a band's lattice rows overlap its neighbours', each
    // gathers its own. Foveated: the list of samples shaded band by band, then reconstructed.
    for (preset, coarse, sibson) in [
        (Preset::Full, false, false),
        (Preset::Reference, false, false),
        (Preset::Full, true, false),
        (Preset::Balanced, false, false),
        (Preset::Quality, false, false),
        (Preset::Balanced, false, true),
    ] {
        let req = |stream| {
            let mut q = request(preset, stream);
            q.settings.translucency.coarse_gather = coarse;
            if sibson {
                q.settings.foveation.reconstruction = Reconstruction::Sibson;
            }
            q
        };
        let whole = r.render(&req(1)).unwrap();
        let mut going = match r.begin(&req(2), 5).unwrap() {
            Progress::Going(g) => g,
            Progress::Done(_) => panic!("{preset}: a frame asked for 5 slices is sliced"),
        };
        let mut parts = 1;
        let sliced = loop {
            // Another stream's foveated frame of the same scene runs between every part.
            let other = r.render(&request(Preset::Balanced, 3)).unwrap();
            assert!(other.sampled < 1.0);
            parts += 1;
            if let Some(f) = r.step(&mut going).unwrap() {
                break f;
            }
        };
        // Prefix, five bands, suffix; foveated, the sampling and the reconstruction too (pull-push
        // in three parts, JFA + Sibson in one).
        let foveated = preset == Preset::Balanced || preset == Preset::Quality;
        let expected = match (foveated, sibson) {
            (false, _) => 7,
            (true, false) => 11,
            (true, true) => 9,
        };
        assert_eq!(parts, expected, "{preset} sibson {sibson}");
        let d = max_diff(&whole.rgba, &sliced.rgba);
        assert!(d <= 1, "{preset}: sliced differs from whole by {d}");
        if foveated {
            // The same samples and the same reconstruction: to the byte.
            assert!(
                whole.sampled < 0.5 && whole.sampled == sliced.sampled,
                "{preset}"
            );
            assert_eq!(
                d, 0,
                "{preset}: a foveated frame in parts differs from it whole"
            );
        }
        assert!(sliced.render_ms > 0.0);
    }
}

#[test]
fn single_slice_frames_stay_whole_and_abandoned_frames_free_their_targets() {
    let mut r = renderer();
    assert!(matches!(
        r.begin(&request(Preset::Balanced, 1), 1).unwrap(),
        Progress::Done(_)
    ));
    let going = match r.begin(&request(Preset::Full, 2), 4).unwrap() {
        Progress::Going(g) => g,
        Progress::Done(_) => panic!("not sliced"),
    };
    assert_eq!(going.stream(), 2);
    r.abandon(*going);
    // A released stream's frame in flight fails cleanly instead of touching freed targets.
    let mut going = match r.begin(&request(Preset::Full, 4), 4).unwrap() {
        Progress::Going(g) => g,
        Progress::Done(_) => panic!("not sliced"),
    };
    r.release_stream(4);
    let err = r.step(&mut going).err().map(|e| e.to_string());
    assert!(
        err.as_deref().is_some_and(|e| e.contains("released")),
        "{err:?}"
    );
}

#[test]
fn stream_targets_stay_within_their_memory_budget_except_for_frames_in_flight() {
    let mut r = renderer();
    let one = fovea::render::FrameTargets::bytes_for(200, 150);
    assert!(one > 200 * 150 * 100, "{one} bytes for 200x150");
    r.set_target_memory(one * 5 / 2);
    for stream in 1..=4 {
        r.render(&request(Preset::Balanced, stream)).unwrap();
        assert!(
            r.target_bytes() <= one * 5 / 2,
            "{} after stream {stream}",
            r.target_bytes()
        );
    }
    // A sliced frame's targets are kept even past the budget while it is in flight.
    let mut going = match r.begin(&request(Preset::Full, 9), 3).unwrap() {
        Progress::Going(g) => g,
        Progress::Done(_) => panic!("not sliced"),
    };
    for stream in 10..14 {
        r.render(&request(Preset::Balanced, stream)).unwrap();
    }
    while r.step(&mut going).unwrap().is_none() {}
}
