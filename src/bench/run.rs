//! Runs a sweep: for each scene, size and gaze, every configuration renders the same frames,
//! interleaved, and each measured frame is compared with the reference render of that frame.

use std::collections::BTreeMap;
use std::sync::atomic::{AtomicBool, Ordering};
use std::time::Instant;

use super::configs::BenchConfig;
use super::report::{BenchRecord, BenchReport, Machine, Spread};
use crate::encode;
use crate::protocol::Display;
use crate::quality::{self, Errors, Weighting};
use crate::render::{FrameRequest, RenderError, Renderer};
use crate::settings::{Preset, RenderSettings};
use crate::viewing::Viewing;

#[derive(Debug, Clone)]
pub struct BenchOptions {
    pub scenes: Vec<String>,
    pub sizes: Vec<(u32, u32)>,
    /// Fixed gaze points; with `moving` each group sweeps from its point across the frame.
    pub gazes: Vec<[f32; 2]>,
    pub moving: bool,
    pub warmup: u32,
    pub frames: u32,
    pub configs: Vec<BenchConfig>,
    pub display: Display,
    pub pupil_mm: f32,
    /// Physical ground truth to compare with too (groups of its size only).
    pub against: Option<super::GroundTruth>,
}

/// How long a sweep waits for a scene's radiosity to converge before measuring it (`cornell`
/// takes ~7 s here).
pub const RADIOSITY_WAIT: std::time::Duration = std::time::Duration::from_secs(3600);

/// Receives (frames done, frames in all, what is running) after every frame.
pub type Progress<'a> = &'a mut dyn FnMut(usize, usize, &str);

/// One configuration's measurements within one group.
#[derive(Default)]
struct Samples {
    frame_ms: Vec<f64>,
    encode_ms: Vec<f64>,
    bytes: Vec<f64>,
    sampled: Vec<f64>,
    passes: BTreeMap<String, Vec<f64>>,
    errors: Vec<Errors>,
    /// Against the ground truth image, when there is one.
    truth: Vec<Errors>,
    /// Against `full`'s render of the same frame (foveated configurations).
    vs_full: Vec<Errors>,
}

/// One configuration's frame compared with the reference, the ground truth and `full`.
struct Compared {
    errors: Errors,
    truth: Option<Errors>,
    vs_full: Option<Errors>,
}

/// One frame's renders, to compare once every configuration of it has rendered.
struct FrameToCompare<'a> {
    /// Each configuration's image (None: not measured this frame).
    frames: Vec<Option<Vec<u8>>>,
    reference: Vec<u8>,
    truth: Option<&'a super::GroundTruth>,
    full: Option<usize>,
    viewing: &'a Viewing,
    gaze_px: [f64; 2],
}

/// What one frame's comparisons give: the reference against the ground truth, and each
/// configuration's [`Compared`].
type FrameCompared = (Option<Errors>, Vec<Option<Compared>>);

/// The comparisons of one frame, one thread per configuration (FLIP of a 1080p frame takes
/// seconds of one core, far more than a GPU's render).
fn compare(job: FrameToCompare) -> FrameCompared {
    let (width, height) = (job.viewing.width, job.viewing.height);
    let weights = Weighting::default();
    let compare_to = |reference: &[u8], rgba: &[u8]| {
        quality::measure(
            reference,
            rgba,
            width,
            height,
            job.viewing,
            job.gaze_px,
            &weights,
        )
    };
    let full_rgba = job.full.and_then(|i| job.frames[i].as_deref());
    let (reference, truth, full) = (&job.reference, job.truth, job.full);
    std::thread::scope(|scope| {
        let reference_truth = truth
            .filter(|_| job.frames.iter().any(Option::is_some))
            .map(|t| scope.spawn(move || compare_to(&t.rgba, reference)));
        let jobs: Vec<_> = job
            .frames
            .iter()
            .enumerate()
            .map(|(ci, rgba)| {
                let rgba = rgba.as_deref()?;
                Some(scope.spawn(move || {
                    Compared {
                        errors: compare_to(reference, rgba),
                        truth: truth.map(|t| compare_to(&t.rgba, rgba)),
                        // Every other configuration against `full`'s render of the same frame:
                        // what foveation, or a cheaper gather, costs apart from the shading
                        // model's own error.
                        vs_full: full_rgba
                            .filter(|_| Some(ci) != full)
                            .map(|f| compare_to(f, rgba)),
                    }
                }))
            })
            .collect();
        let compared = jobs.into_iter().map(|j| j.map(join)).collect();
        (reference_truth.map(join), compared)
    })
}

/// A comparison thread's result; its panic goes on as this thread's (as if run here).
fn join<T>(handle: std::thread::ScopedJoinHandle<'_, T>) -> T {
    handle
        .join()
        .unwrap_or_else(|panic| std::panic::resume_unwind(panic))
}

/// [`compare`], with the GPU kept busy meanwhile on a hardware adapter: left idle for the
/// seconds the comparisons take, a GPU drops its clocks and the next frames time slow (an H200
/// timed `full` at 1080p 18.6 ms this way, against 4 ms rendering steadily). The renders in
/// between are of `warm` and untimed. On a CPU adapter they would only take the comparisons'
/// cores.
fn compare_keeping_warm(
    renderer: &mut Renderer,
    warm: &FrameRequest,
    job: FrameToCompare,
) -> Result<FrameCompared, RenderError> {
    if renderer.is_software() {
        return Ok(compare(job));
    }
    std::thread::scope(|scope| {
        let comparing = scope.spawn(|| compare(job));
        while !comparing.is_finished() {
            renderer.render(warm)?;
        }
        Ok(join(comparing))
    })
}

fn gaze_at(start: [f32; 2], moving: bool, frame: u32) -> [f32; 2] {
    if !moving {
        return start;
    }
    // A slow pursuit around the start point: consecutive frames overlap, so history is reused.
    let a = frame as f32 * 0.15;
    [
        (start[0] + 0.15 * a.sin()).clamp(0.0, 1.0),
        (start[1] + 0.1 * (0.7 * a).cos() - 0.1).clamp(0.0, 1.0),
    ]
}

pub fn run(
    renderer: &mut Renderer,
    opts: &BenchOptions,
    stop: &AtomicBool,
    progress: Progress,
) -> Result<BenchReport, RenderError> {
    let started = Instant::now();
    let groups: Vec<(String, (u32, u32), [f32; 2])> = opts
        .scenes
        .iter()
        .flat_map(|s| {
            opts.sizes
                .iter()
                .flat_map(move |z| opts.gazes.iter().map(move |g| (s.clone(), *z, *g)))
        })
        .collect();
    let per_group = (opts.warmup + opts.frames) as usize * (opts.configs.len() + 1);
    let total = groups.len() * per_group;
    let mut done = 0usize;
    let mut records = Vec::new();
    let mut reference_truth = Vec::new();
    let mut interrupted = false;
    let reference = RenderSettings::of(Preset::Reference);
    for (gi, (scene, (w, h), gaze0)) in groups.iter().enumerate() {
        progress(done, total, &format!("radiosity of {scene}"));
        renderer.settle_radiosity(scene, RADIOSITY_WAIT, &|| stop.load(Ordering::Relaxed))?;
        let viewing = Viewing {
            width: *w,
            height: *h,
            width_cm: opts.display.width_cm,
            distance_cm: opts.display.distance_cm,
        };
        let mut samples: Vec<Samples> = opts.configs.iter().map(|_| Samples::default()).collect();
        let truth = opts
            .against
            .as_ref()
            .filter(|t| (t.width, t.height) == (*w, *h));
        let mut reference_vs_truth = Vec::new();
        let stream_base = 1_000 * (gi as u64 + 1);
        for f in 0..opts.warmup + opts.frames {
            let gaze = gaze_at(*gaze0, opts.moving, f);
            let measured = f >= opts.warmup;
            let request = |settings: &RenderSettings, stream: u64| {
                let mut r = FrameRequest::new(scene, *w, *h);
                r.gaze = gaze;
                r.settings = settings.clone();
                r.display = opts.display;
                r.pupil_mm = opts.pupil_mm;
                r.stream = stream;
                r
            };
            let reference_frame = renderer.render(&request(&reference, stream_base + 999))?;
            done += 1;
            let gaze_px = [
                f64::from(gaze[0]) * f64::from(*w),
                f64::from(gaze[1]) * f64::from(*h),
            ];
            // Each configuration's frame, to compare with `full`'s once all are rendered.
            let mut frames: Vec<Option<Vec<u8>>> = vec![None; opts.configs.len()];
            for (ci, config) in opts.configs.iter().enumerate() {
                if stop.load(Ordering::Relaxed) {
                    // Keep what this group measured so far (this frame's renders compared
                    // below); skip the rest.
                    interrupted = true;
                    break;
                }
                progress(done, total, &config.name);
                let frame = renderer.render(&request(&config.settings, stream_base + ci as u64))?;
                let t0 = Instant::now();
                let bytes = encode::encode(&frame.rgba, *w, *h, config.codec, config.quality)
                    .map_err(|e| RenderError::Readback(format!("encoding: {e}")))?;
                let encode_ms = t0.elapsed().as_secs_f64() * 1e3;
                done += 1;
                if !measured {
                    continue;
                }
                let s = &mut samples[ci];
                s.frame_ms.push(frame.render_ms);
                s.encode_ms.push(encode_ms);
                s.bytes.push(bytes.len() as f64);
                s.sampled.push(frame.sampled);
                for (k, v) in &frame.passes_ms {
                    s.passes.entry(k.clone()).or_default().push(*v);
                }
                frames[ci] = Some(frame.rgba);
            }
            let job = FrameToCompare {
                frames,
                reference: reference_frame.rgba,
                truth,
                full: opts.configs.iter().position(|c| c.name == "full"),
                viewing: &viewing,
                gaze_px,
            };
            let warm = request(&reference, stream_base + 999);
            let (reference_truth, compared) = compare_keeping_warm(renderer, &warm, job)?;
            reference_vs_truth.extend(reference_truth);
            for (s, c) in samples.iter_mut().zip(compared) {
                let Some(c) = c else { continue };
                s.errors.push(c.errors);
                s.truth.extend(c.truth);
                s.vs_full.extend(c.vs_full);
            }
            if interrupted {
                break;
            }
        }
        for (config, s) in opts.configs.iter().zip(samples) {
            if s.frame_ms.is_empty() {
                continue;
            }
            records.push(BenchRecord {
                config: config.name.clone(),
                scene: scene.clone(),
                width: *w,
                height: *h,
                gaze: *gaze0,
                moving_gaze: opts.moving,
                settings: config.settings.clone(),
                codec: config.codec,
                quality: config.quality,
                frames: s.frame_ms.len(),
                frame_ms: Spread::of(&s.frame_ms),
                passes_ms: s
                    .passes
                    .iter()
                    .map(|(k, v)| (k.clone(), Spread::of(v).median))
                    .collect(),
                encode_ms: Spread::of(&s.encode_ms),
                bytes: Spread::of(&s.bytes).median,
                sampled: Spread::of(&s.sampled).median,
                errors: median_errors(&s.errors),
                ground_truth: (!s.truth.is_empty()).then(|| median_errors(&s.truth)),
                speedup_vs_full: None,
                shade_speedup_vs_full: None,
                overhead_ms: 0.0,
                ideal_vs_full: None,
                bound_vs_full: None,
                vs_full: (!s.vs_full.is_empty()).then(|| median_errors(&s.vs_full)),
                pareto: false,
            });
        }
        if !reference_vs_truth.is_empty() {
            reference_truth.push(super::ReferenceTruth {
                scene: scene.clone(),
                width: *w,
                height: *h,
                gaze: *gaze0,
                errors: median_errors(&reference_vs_truth),
            });
        }
        if interrupted {
            break;
        }
    }
    let machine = Machine::describe(renderer);
    let mut report = BenchReport {
        machine,
        seconds: started.elapsed().as_secs_f64(),
        interrupted,
        warmup: opts.warmup,
        frames: opts.frames,
        display: opts.display,
        records,
        ground_truth: opts.against.as_ref().map(|t| t.path.display().to_string()),
        reference_truth,
    };
    report.finish();
    Ok(report)
}

fn median_errors(e: &[Errors]) -> Errors {
    let m = |f: fn(&Errors) -> f64| {
        let v: Vec<f64> = e.iter().map(|x| f(x).min(quality::PSNR_CAP_DB)).collect();
        Spread::of(&v).median
    };
    Errors {
        psnr: m(|e| e.psnr),
        ssim: m(|e| e.ssim),
        flip: m(|e| e.flip),
        psnr_pooled: m(|e| e.psnr_pooled),
        ssim_pooled: m(|e| e.ssim_pooled),
        flip_pooled: m(|e| e.flip_pooled),
        psnr_fovea: m(|e| e.psnr_fovea),
        ssim_fovea: m(|e| e.ssim_fovea),
        flip_fovea: m(|e| e.flip_fovea),
    }
}
