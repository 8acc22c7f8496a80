//! `fovea bench --sweep codecs`: every encoder configuration on the same rendered frames along a
//! recorded gaze path, so inter-frame coding and the foveated encodings see moving gaze, not a
//! still frame. Each frame is encoded, decoded as the page would show it, and compared with the
//! lossless frame: FLIP within 5° of that frame's gaze and over the whole frame.

use std::sync::atomic::{AtomicBool, Ordering};
use std::time::{Duration, Instant};

use super::codec_configs::CodecConfig;
use super::codecs_report::{CodecReport, CodecRow, FloorRow};
use super::report::{Machine, Spread};
use super::run::RADIOSITY_WAIT;
use crate::encode::foveated::{low_pass, LowPass};
use crate::encode::h264::{H264Config, H264Stream};
use crate::encode::hold::{self, Hold};
use crate::encode::{encode, inset, inset_packed, yuv, EncodeError};
use crate::protocol::{Codec, Display};
use crate::quality::{flip_map, foveal_mask, pixels_per_degree, pooled_mean};
use crate::render::{FrameRequest, RenderError, Renderer};
use crate::settings::{Preset, RenderSettings};
use crate::viewing::Viewing;

/// The frame rate the gaze path is sampled at and the kbit/s column assumes.
pub const FPS: f64 = 60.0;

#[derive(Debug, Clone)]
pub struct CodecOptions {
    pub scene: String,
    pub width: u32,
    pub height: u32,
    /// One normalised gaze point per frame (see [`gaze_path`]): one stretch of the recording,
    /// or several laid end to end.
    pub path: Vec<[f64; 2]>,
    /// Frames in each stretch of `path`. Each stretch is its own stream, as if a session
    /// started there: a fresh H.264 encoder (a keyframe), fresh render history, the clock from
    /// 0. Several stretches pool one report over more of the recording than one stream's
    /// frames, whose bytes depend on where in it they fall (docs/encoding.md).
    pub stretch_frames: usize,
    /// Where the path came from, for the report.
    pub recording: String,
    pub configs: Vec<CodecConfig>,
    pub display: Display,
    /// Write each configuration's last decoded frame (and the lossless one) as PNG here.
    pub pictures: Option<std::path::PathBuf>,
    /// Turn the camera about its target at this rate (yaw, degrees per second), as a viewer
    /// dragging the view does: the whole picture then changes every frame, not only where
    /// the gaze moves the foveated shading. 0 keeps the scene's camera still.
    pub orbit_deg_per_s: f64,
}

#[derive(Debug, thiserror::Error)]
pub enum CodecBenchError {
    #[error(transparent)]
    Render(#[from] RenderError),
    #[error("{config}: {source}")]
    Encode { config: String, source: EncodeError },
    #[error("{config}: decoding its own frame: {message}")]
    Decode { config: String, message: String },
    #[error("the recording has no gaze the server would show from {from_s} s on")]
    NoGaze { from_s: f64 },
    #[error("{frames} frames cannot be cut into stretches of {stretch}")]
    Stretch { frames: usize, stretch: usize },
    #[error("{frames} frames of {width}x{height}: H.264 needs an even width and height")]
    OddSize {
        frames: usize,
        width: u32,
        height: u32,
    },
    #[error("writing {path}: {message}")]
    Picture { path: String, message: String },
}

/// What one configuration measured.
#[derive(Default)]
struct Tally {
    bytes: Vec<f64>,
    /// Each stretch's first frame.
    keyframe_bytes: Vec<f64>,
    encode_ms: Vec<f64>,
    foveal: Vec<f64>,
    whole: Vec<f64>,
}

/// A frame's gaze and its lossless pixels.
type Frame = ([f64; 2], Vec<u8>);
type Frames = [Frame];

/// Renders the path's frames once, then encodes, decodes and scores them with every
/// configuration. `stop` ends the run early with what was measured.
pub fn run_codecs(
    renderer: &mut Renderer,
    opts: &CodecOptions,
    stop: &AtomicBool,
    progress: super::Progress,
) -> Result<CodecReport, CodecBenchError> {
    let (w, h) = (opts.width, opts.height);
    if opts.configs.iter().any(|c| c.codec == Codec::H264) && (w % 2 == 1 || h % 2 == 1) {
        return Err(CodecBenchError::OddSize {
            frames: opts.path.len(),
            width: w,
            height: h,
        });
    }
    let n = opts.stretch_frames;
    if n == 0 || !opts.path.len().is_multiple_of(n) {
        return Err(CodecBenchError::Stretch {
            frames: opts.path.len(),
            stretch: n,
        });
    }
    let started = Instant::now();
    let viewing = Viewing {
        width: w,
        height: h,
        width_cm: opts.display.width_cm,
        distance_cm: opts.display.distance_cm,
    };
    let base_camera = crate::scene::Scene::builtin(&opts.scene)
        .map_err(RenderError::from)?
        .file
        .camera;
    let total = opts.path.len() * (1 + opts.configs.len());
    let mut done = 0;
    progress(done, total, &format!("radiosity of {}", opts.scene));
    renderer.settle_radiosity(&opts.scene, RADIOSITY_WAIT, &|| {
        stop.load(Ordering::Relaxed)
    })?;
    let mut tick = || {
        done += 1;
        progress(done, total, "rendering the path");
    };
    let frames = render_path(renderer, opts, &base_camera, stop, &mut tick)?;
    let mut rows = Vec::new();
    for config in &opts.configs {
        if stop.load(Ordering::Relaxed) || frames.is_empty() {
            break;
        }
        let mut tick = |k: usize| progress(done + k + 1, total, &config.name);
        let (t, last) = measure(config, &frames, n, &viewing, &mut tick)?;
        done += frames.len();
        if let Some(dir) = &opts.pictures {
            save(dir, &slug(&config.name), &last, w, h)?;
        }
        rows.push(CodecRow {
            name: config.name.clone(),
            family: config.family(),
            config: config.clone(),
            bytes: Spread::of(&t.bytes),
            keyframe_bytes: (!t.keyframe_bytes.is_empty()).then(|| mean(&t.keyframe_bytes)),
            kbps: kbps_at_fps(&t.bytes, &t.keyframe_bytes),
            flip_fovea: mean(&t.foveal),
            flip: mean(&t.whole),
            encode_ms: Spread::of(&t.encode_ms),
        });
    }
    if let (Some(dir), Some((_, rgba))) = (&opts.pictures, frames.last()) {
        save(dir, "lossless", rgba, w, h)?;
    }
    let floors = if stop.load(Ordering::Relaxed) {
        Vec::new()
    } else {
        floors(&frames, &viewing)
    };
    let mut report = CodecReport {
        machine: Machine::describe(renderer),
        scene: opts.scene.clone(),
        preset: Preset::DEFAULT.name().to_string(),
        width: w,
        height: h,
        recording: opts.recording.clone(),
        orbit_deg_per_s: opts.orbit_deg_per_s,
        frames: frames.len(),
        fps: FPS,
        seconds: started.elapsed().as_secs_f64(),
        interrupted: stop.load(Ordering::Relaxed),
        rows,
        floors,
        equal_quality: Vec::new(),
    };
    report.finish();
    Ok(report)
}

fn mean(v: &[f64]) -> f64 {
    v.iter().sum::<f64>() / v.len() as f64
}

/// The path's frames, rendered as a session renders: its default preset, one history stream,
/// the clock at 60 fps (animated lights move), so consecutive frames differ as they do on the
/// wire. Each stretch starts as a new session would.
fn render_path(
    renderer: &mut Renderer,
    opts: &CodecOptions,
    base_camera: &crate::scene::Camera,
    stop: &AtomicBool,
    tick: &mut dyn FnMut(),
) -> Result<Vec<Frame>, CodecBenchError> {
    let n = opts.stretch_frames;
    let mut frames = Vec::new();
    for (k, g) in opts.path.iter().enumerate() {
        if stop.load(Ordering::Relaxed) {
            break;
        }
        if k % n == 0 {
            renderer.release_stream(1);
        }
        let mut req = FrameRequest::new(&opts.scene, opts.width, opts.height);
        req.gaze = [g[0] as f32, g[1] as f32];
        req.settings = RenderSettings::of(Preset::DEFAULT);
        req.stream = 1;
        req.time_s = (k % n) as f64 / FPS;
        if opts.orbit_deg_per_s != 0.0 {
            let yaw = opts.orbit_deg_per_s * req.time_s;
            req.camera = Some(base_camera.orbit(yaw as f32, 0.0));
        }
        frames.push((*g, renderer.render(&req)?.rgba));
        tick();
    }
    Ok(frames)
}

/// Mean FLIP within 5° of the gaze, and over the whole frame.
fn score(viewing: &Viewing, reference: &[u8], shown: &[u8], g: [f64; 2]) -> (f64, f64) {
    let map = flip_map(
        reference,
        shown,
        viewing.width,
        viewing.height,
        pixels_per_degree(viewing),
    );
    let fovea = foveal_mask(viewing, viewing.to_pixels(g), 5.0);
    (pooled_mean(&map, &fovea), mean(&map))
}

/// Encodes every frame with one configuration (one H.264 stream over each `stretch` of them),
/// decodes each as the page would show it and scores it. Returns the tally and the last frame
/// shown.
fn measure(
    config: &CodecConfig,
    frames: &Frames,
    stretch: usize,
    viewing: &Viewing,
    tick: &mut dyn FnMut(usize),
) -> Result<(Tally, Vec<u8>), CodecBenchError> {
    let (w, h) = (viewing.width, viewing.height);
    let encode_err = |source| CodecBenchError::Encode {
        config: config.name.clone(),
        source,
    };
    let decode_err = |message: String| CodecBenchError::Decode {
        config: config.name.clone(),
        message,
    };
    let (mut stream, mut decoder) = (None, None);
    let acuity = LowPass::default();
    let mut t = Tally::default();
    let mut shown = Vec::new();
    for (k, (g, rgba)) in frames.iter().enumerate() {
        let first = k % stretch == 0;
        if first {
            (stream, decoder) = fresh_stream(config)?;
        }
        let start = Instant::now();
        // Borrowed where nothing filters it: a session encodes the readback in place, and a
        // copy (3.7 MB at 720p) would be timed as encoding.
        let filtered;
        let input: &[u8] = if config.low_pass {
            filtered = low_pass(rgba, w, h, *g, viewing, &acuity);
            &filtered
        } else {
            rgba
        };
        // Timed as frames at FPS: the rate control spends the bitrate over that time.
        let ms = ((k % stretch) as f64 * 1e3 / FPS) as u64;
        let mut h264 = |s: &mut H264Stream, picture: &[u8], pw: u32, ph: u32| {
            let f = s.encode_at(picture, pw, ph, ms).map_err(encode_err)?;
            t.encode_ms.push(start.elapsed().as_secs_f64() * 1e3);
            let dec = decoder
                .as_mut()
                .ok_or_else(|| decode_err("no decoder".into()))?;
            let pic = dec
                .decode(&f.bytes)
                .map_err(|e| decode_err(e.to_string()))?
                .ok_or_else(|| decode_err("no picture for a whole frame".into()))?;
            // Rounded, as a browser's decoder shows it (openh264's own truncates).
            Ok::<_, CodecBenchError>((yuv::picture_to_rgba(&pic), f.bytes.len(), f.keyframe))
        };
        let (bytes, keyframe) = match (&mut stream, config.inset_deg) {
            (Some(s), None) => {
                if config.hold {
                    s.hold_next(hold::thresholds(w, h, *g, viewing, &Hold::default()));
                }
                let (picture, n, key) = h264(s, input, w, h)?;
                shown = picture;
                (n, key)
            }
            (Some(s), Some(deg)) => {
                // Both parts in one picture of the stream, as an h264 inset session sends them.
                let plan = inset_packed::follow(s.held_inset(), w, h, *g, viewing, deg, &acuity);
                let (base, crop) = inset::split(input, w, h, &plan);
                let (packed, l) = inset_packed::pack(&base, &crop, &plan, w, h);
                if config.hold {
                    let t = inset_packed::hold_thresholds(
                        &plan,
                        &l,
                        (w, h),
                        *g,
                        viewing,
                        &Hold::default(),
                    );
                    s.hold_next(t);
                }
                let (picture, n, key) = h264(s, &packed, l.width, l.height)?;
                s.hold_inset(plan);
                let (b_px, i_px) = inset_packed::unpack(&picture, &l, &plan, w, h);
                shown = inset::compose(&b_px, &i_px, &plan, w, h);
                (n, key)
            }
            (None, Some(deg)) => {
                let plan = inset::plan(w, h, *g, viewing, deg, &acuity);
                let (base, crop) = inset::split(input, w, h, &plan);
                let (bw, bh) = plan.base_size(w, h);
                let jpeg = |px: &[u8], pw, ph| encode(px, pw, ph, Codec::Jpeg, config.jpeg_q);
                let b = jpeg(&base, bw, bh).map_err(encode_err)?;
                let i = jpeg(&crop, plan.width, plan.height).map_err(encode_err)?;
                t.encode_ms.push(start.elapsed().as_secs_f64() * 1e3);
                let (b_px, i_px) = (decode_image(&b), decode_image(&i));
                let (b_px, i_px) = (b_px.map_err(decode_err)?, i_px.map_err(decode_err)?);
                shown = inset::compose(&b_px, &i_px, &plan, w, h);
                (b.len() + i.len(), false)
            }
            (None, None) => {
                let b = encode(input, w, h, config.codec, config.jpeg_q).map_err(encode_err)?;
                t.encode_ms.push(start.elapsed().as_secs_f64() * 1e3);
                shown = decode_image(&b).map_err(decode_err)?;
                (b.len(), false)
            }
        };
        // A stream's first keyframe is the periodic one the report spreads over 2 s; any later
        // one (the rate guard changing the quantiser's range) is a frame's cost.
        if keyframe && first {
            t.keyframe_bytes.push(bytes as f64);
        } else {
            t.bytes.push(bytes as f64);
        }
        let (f, a) = score(viewing, rgba, &shown, *g);
        t.foveal.push(f);
        t.whole.push(a);
        tick(k);
    }
    Ok((t, shown))
}

/// A new H.264 stream and the decoder that shows it, for a configuration that has one. Its only
/// keyframe is its first: the report adds the session's periodic ones to the bitrate, rather
/// than letting the wall clock of a slow run decide where they fall.
fn fresh_stream(
    config: &CodecConfig,
) -> Result<(Option<H264Stream>, Option<openh264::decoder::Decoder>), CodecBenchError> {
    let Some(kbps) = config.h264_kbps else {
        return Ok((None, None));
    };
    let stream = H264Stream::new(H264Config {
        kbps,
        keyframe_every: Duration::from_secs(24 * 3600),
    });
    let decoder = openh264::decoder::Decoder::new().map_err(|e| CodecBenchError::Decode {
        config: config.name.clone(),
        message: e.to_string(),
    })?;
    Ok((Some(stream), Some(decoder)))
}

fn decode_image(bytes: &[u8]) -> Result<Vec<u8>, String> {
    image::load_from_memory(bytes)
        .map(|d| d.to_rgba8().into_raw())
        .map_err(|e| e.to_string())
}

/// The keyframe period the reports count. Sessions sent a keyframe every 2 s when the
/// committed reports were made (docs/bench/codecs-*); they now send one every 10 s
/// (`h264::DEFAULT_KEYFRAME_S`) and where the rate guard switches ranges, which on a still or
/// steadily moving picture is rare. Counting 2 s keeps new runs comparable with those, and
/// their kbit/s an upper bound on a session's.
pub const REPORT_KEYFRAME_S: f64 = 2.0;

/// Bits per second at [`FPS`] in kbit/s: the P-frames' mean plus a keyframe (the stretches'
/// mean) every [`REPORT_KEYFRAME_S`] seconds.
fn kbps_at_fps(bytes: &[f64], keyframes: &[f64]) -> f64 {
    let m = if bytes.is_empty() { 0.0 } else { mean(bytes) };
    let per_s = if keyframes.is_empty() {
        m * FPS
    } else {
        let n = FPS * REPORT_KEYFRAME_S;
        (mean(keyframes) + (n - 1.0) * m) / REPORT_KEYFRAME_S
    };
    per_s * 8.0 / 1e3
}

fn slug(name: &str) -> String {
    name.chars()
        .map(|c| if c.is_ascii_alphanumeric() { c } else { '_' })
        .collect()
}

fn save(
    dir: &std::path::Path,
    name: &str,
    rgba: &[u8],
    w: u32,
    h: u32,
) -> Result<(), CodecBenchError> {
    let path = dir.join(format!("{name}.png"));
    let fail = |message: String| CodecBenchError::Picture {
        path: path.display().to_string(),
        message,
    };
    std::fs::create_dir_all(dir).map_err(|e| fail(e.to_string()))?;
    let png = encode(rgba, w, h, Codec::Png, 100).map_err(|e| fail(e.to_string()))?;
    std::fs::write(&path, png).map_err(|e| fail(e.to_string()))
}

/// How a floor row shows our conversion: each chroma sample over its block, or filtered
/// between blocks; or chroma at every pixel (4:4:4), what the 8-bit codes alone cost.
enum Floor {
    Rounded,
    Filtered,
    Full,
}

/// The floor under every codec that codes 8-bit 4:2:0 YCbCr: our colour conversion alone, no
/// compression; and under one that kept every chroma sample (4:4:4), which neither openh264
/// nor a browser's H.264 decoder offers.
fn floors(frames: &Frames, viewing: &Viewing) -> Vec<FloorRow> {
    let (w, h) = (viewing.width as usize, viewing.height as usize);
    let mut rows = Vec::new();
    for (name, conversion) in [
        ("I420 round trip, rounded (no codec)", Floor::Rounded),
        (
            "I420 round trip, rounded, chroma filtered when shown (no codec)",
            Floor::Filtered,
        ),
        (
            "YCbCr 4:4:4 round trip, rounded (no codec, no chroma subsampling)",
            Floor::Full,
        ),
    ] {
        let (mut fov, mut whole) = (Vec::new(), Vec::new());
        for (g, rgba) in frames {
            let mut pic = yuv::I420::new(w, h);
            pic.fill(rgba);
            let back = match conversion {
                Floor::Rounded => yuv::picture_to_rgba(&pic),
                Floor::Filtered => yuv::picture_to_rgba_filtered(&pic),
                Floor::Full => yuv::ycbcr444_round_trip(rgba, w, h),
            };
            let (f, a) = score(viewing, rgba, &back, *g);
            fov.push(f);
            whole.push(a);
        }
        rows.push(FloorRow {
            name: name.into(),
            flip_fovea: mean(&fov),
            flip: mean(&whole),
        });
    }
    rows
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_bitrate_spreads_one_keyframe_over_each_two_seconds() {
        // 120 frames in 2 s: one keyframe of 60 000 bytes and 119 P-frames of 1000.
        let kbps = kbps_at_fps(&[1000.0, 1000.0], &[60_000.0]);
        assert!((kbps - (60_000.0 + 119_000.0) * 8.0 / 2.0 / 1e3).abs() < 1e-9);
        // Two stretches' keyframes: their mean.
        let pooled = kbps_at_fps(&[1000.0, 1000.0], &[50_000.0, 70_000.0]);
        assert!((pooled - kbps).abs() < 1e-9);
        assert!((kbps_at_fps(&[1000.0], &[]) - 480.0).abs() < 1e-9);
        assert_eq!(kbps_at_fps(&[], &[]), 0.0);
    }
}
