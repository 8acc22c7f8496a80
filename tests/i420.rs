//! The GPU's RGB → I420 pass against its CPU twin (`encode::yuv::rgba_to_i420`) on rendered
//! frames, including a size whose chroma planes need padding, and the readback it saves.
//! Software Vulkan adapter; no adapter is a failure.

use fovea::encode::yuv::rgba_to_i420;
use fovea::render::{FrameRequest, Readback, Renderer};
use fovea::settings::{Preset, RenderSettings};

#[test]
fn the_gpu_planes_match_the_cpu_conversion_of_the_same_frame() {
    let mut r = Renderer::new().unwrap_or_else(|e| panic!("GPU tests need an adapter: {e}"));
    // 322×242: 19 481 chroma samples a plane, not a whole number of words.
    for (w, h) in [(320u32, 240u32), (322, 242), (1280, 720)] {
        let request = |stream: u64, readback: Readback| {
            let mut q = FrameRequest::new("gallery", w, h);
            q.settings = RenderSettings::of(Preset::Full);
            q.gaze = [0.4, 0.55];
            q.marker = true;
            q.stream = stream;
            q.readback = readback;
            q
        };
        let rgb = r.render(&request(1, Readback::Rgba)).unwrap();
        let gpu = r.render(&request(2, Readback::I420)).unwrap();
        assert!(
            gpu.rgba.is_empty(),
            "an I420 frame is read back as planes only"
        );
        let planes = gpu.i420.expect("planes");
        let (wu, hu) = (w as usize, h as usize);
        assert_eq!(planes.len(), wu * hu * 3 / 2, "1.5 bytes a pixel");
        let (mut y, mut u, mut v) = (vec![0; wu * hu], vec![0; wu * hu / 4], vec![0; wu * hu / 4]);
        rgba_to_i420(&rgb.rgba, wu, hu, &mut y, &mut u, &mut v);
        let cpu = [y, u, v].concat();
        let (mut off_by_one, mut worse) = (0, 0);
        for (g, c) in planes.iter().zip(&cpu) {
            match g.abs_diff(*c) {
                0 => {}
                1 => off_by_one += 1,
                _ => worse += 1,
            }
        }
        // f32 on either side may round a value sitting on .5 differently; nothing more.
        assert_eq!(worse, 0, "{w}x{h}: samples more than one code apart");
        assert!(
            off_by_one * 1000 < cpu.len(),
            "{w}x{h}: {off_by_one} of {} samples one code apart",
            cpu.len()
        );
        eprintln!(
            "{w}x{h}: readback {:.2} ms as I420 ({} bytes) against {:.2} ms as RGBA ({} bytes); \
             the i420 pass {:?} ms, output {:?} ms",
            gpu.readback_ms,
            planes.len(),
            rgb.readback_ms,
            rgb.rgba.len(),
            gpu.passes_ms.get("i420"),
            gpu.passes_ms.get("output"),
        );
    }
}
