//! The GPU's foveated-encoding low-pass (the `low_pass` pass) against its CPU twin
//! (`encode::foveated::low_pass`) on rendered frames: odd sizes, a gaze near a corner (every
//! level read), the fovea left bit for bit, the I420 conversion of the filtered image, and when
//! the renderer leaves the filter to the encoder. Software Vulkan adapter; no adapter is a
//! failure.

use std::time::Instant;

use fovea::encode::foveated::{level_map, low_pass, LowPass, MAX_LEVEL};
use fovea::encode::yuv::rgba_to_i420;
use fovea::render::{FrameRequest, GpuLowPass, Readback, Renderer};
use fovea::settings::{Preset, RenderSettings};
use fovea::viewing::{Display, Viewing};

fn renderer() -> Renderer {
    Renderer::new().unwrap_or_else(|e| panic!("GPU tests need an adapter: {e}"))
}

fn request(w: u32, h: u32, gaze: [f32; 2], stream: u64, lp: GpuLowPass) -> FrameRequest {
    let mut q = FrameRequest::new("gallery", w, h);
    q.settings = RenderSettings::of(Preset::Full);
    q.gaze = gaze;
    q.stream = stream;
    q.low_pass = lp;
    q
}

/// Bytes more than one code apart, and bytes exactly one apart.
fn differences(a: &[u8], b: &[u8]) -> (usize, usize) {
    a.iter()
        .zip(b)
        .fold((0, 0), |(worse, one), (x, y)| match x.abs_diff(*y) {
            0 => (worse, one),
            1 => (worse, one + 1),
            _ => (worse + 1, one),
        })
}

#[test]
fn the_gpu_filter_matches_the_cpu_filter_and_leaves_the_fovea_alone() {
    let mut r = renderer();
    // 97×61: every pyramid level has a repeated edge; on a 5 cm display with a steep acuity
    // slope the gaze near its corner reaches the coarsest level within the frame. 720p: the
    // defaults, a wide untouched fovea.
    let small = Display {
        width_cm: 5.0,
        distance_cm: 60.0,
    };
    let cases = [
        (
            320u32,
            240u32,
            [0.4f32, 0.55f32],
            2.0,
            0.022,
            Display::default(),
        ),
        (97, 61, [0.05, 0.1], 0.5, 0.5, small),
        (1280, 720, [0.5, 0.5], 5.0, 0.022, Display::default()),
    ];
    for (stream, &(w, h, gaze, guard_deg, mar_slope, display)) in (1u64..).step_by(2).zip(&cases) {
        let p = LowPass {
            guard_deg,
            mar_slope,
            ..LowPass::default()
        };
        let frame = |stream, lp| {
            let mut q = request(w, h, gaze, stream, lp);
            q.display = display;
            q
        };
        let plain = r.render(&frame(stream, GpuLowPass::Off)).unwrap();
        let gpu = r.render(&frame(stream + 1, GpuLowPass::Always(p))).unwrap();
        assert!(gpu.low_passed && !plain.low_passed);
        let viewing = Viewing::new(display, w, h);
        let levels = level_map(w, h, gaze.map(f64::from), &viewing, &p);
        let top = levels.iter().fold(0.0f32, |m, l| m.max(*l));
        let g = gaze.map(f64::from);
        let started = Instant::now();
        let cpu = low_pass(&plain.rgba, w, h, g, &viewing, &p);
        let cpu_ms = started.elapsed().as_secs_f64() * 1e3;
        assert_ne!(cpu, plain.rgba, "{w}x{h}: the periphery is filtered");
        let (worse, one) = differences(&gpu.rgba, &cpu);
        // f32 on either side may round a value sitting on .5 differently; nothing more.
        assert_eq!(
            worse, 0,
            "{w}x{h}: bytes more than one code from the CPU filter"
        );
        assert!(
            one * 1000 < cpu.len(),
            "{w}x{h}: {one} of {} bytes one code apart",
            cpu.len()
        );
        // Within the guard the image is the output pass's, bit for bit.
        let gaze_px = viewing.to_pixels(g);
        let mut inside = 0;
        for (i, (a, b)) in gpu.rgba.chunks(4).zip(plain.rgba.chunks(4)).enumerate() {
            let at = [(i as u32 % w) as f64, (i as u32 / w) as f64];
            if viewing.eccentricity_deg(gaze_px, at) <= guard_deg {
                inside += 1;
                assert_eq!(a, b, "{w}x{h}: pixel {at:?} in the guard changed");
            }
        }
        assert!(inside > 20, "{w}x{h}: only {inside} pixels in the guard");
        eprintln!(
            "{w}x{h}: low_pass pass {:?} ms on the GPU, {cpu_ms:.2} ms on the CPU; {one} bytes \
             one code apart; levels up to {top:.2}",
            gpu.passes_ms.get("low_pass"),
        );
        if w == 97 {
            assert!(top >= MAX_LEVEL as f32, "the coarsest level is read: {top}");
        }
    }
}

#[test]
fn an_i420_frame_is_filtered_before_conversion_and_a_cpu_adapter_leaves_rgba_to_the_encoder() {
    let mut r = renderer();
    let (w, h, gaze) = (320u32, 240u32, [0.3f32, 0.6f32]);
    let p = LowPass::default();
    let plain = r.render(&request(w, h, gaze, 1, GpuLowPass::Off)).unwrap();
    // I420 cannot be filtered by the encoder, so the renderer filters whatever the adapter.
    let mut q = request(w, h, gaze, 2, GpuLowPass::Preferred(p));
    q.readback = Readback::I420;
    let planes = r.render(&q).unwrap();
    assert!(planes.low_passed);
    let viewing = Viewing::new(Display::default(), w, h);
    let cpu = low_pass(&plain.rgba, w, h, gaze.map(f64::from), &viewing, &p);
    let (wu, hu) = (w as usize, h as usize);
    let (mut y, mut u, mut v) = (vec![0; wu * hu], vec![0; wu * hu / 4], vec![0; wu * hu / 4]);
    rgba_to_i420(&cpu, wu, hu, &mut y, &mut u, &mut v);
    let (mut py, mut pu, mut pv) = (vec![0; wu * hu], vec![0; wu * hu / 4], vec![0; wu * hu / 4]);
    rgba_to_i420(&plain.rgba, wu, hu, &mut py, &mut pu, &mut pv);
    let got = planes.i420.expect("planes");
    let want = [y, u, v].concat();
    assert_ne!(want, [py, pu, pv].concat(), "the filter changes the planes");
    // A byte one code off before conversion may move a plane's sample by one more.
    let (worse, _) = differences(&got, &want);
    let far = got
        .iter()
        .zip(&want)
        .filter(|(a, b)| a.abs_diff(**b) > 2)
        .count();
    assert_eq!(
        far, 0,
        "{worse} samples over one code apart, {far} over two"
    );
    assert!(
        worse * 1000 < want.len(),
        "{worse} samples over one code apart"
    );
    // On a CPU adapter an RGBA frame comes back unfiltered: the encoder thread, beside the
    // render thread, filters it (docs/encoding.md, "The low-pass on the GPU").
    let software = r.is_software();
    let rgba = r
        .render(&request(w, h, gaze, 3, GpuLowPass::Preferred(p)))
        .unwrap();
    assert_eq!(rgba.low_passed, !software);
    if software {
        assert_eq!(rgba.rgba, plain.rgba);
    }
}
