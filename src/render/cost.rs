//! What a frame costs the render thread, learnt from the frames it renders: a fixed part and
//! milliseconds per megapixel for each kind of frame (scene, foveated or not, translucency
//! rung). The fixed part matters: a foveated frame's passes cost about the same at 320×240 as
//! at 640×480, so a per-pixel figure from small frames alone would call 4K frames many times
//! dearer than they are. The server
//! admits a session only if its frames fit the per-frame budget, and the render thread splits
//! frames expected to be long into slices. Estimates start from a calibration at start-up
//! ([`calibrate`]) and follow the frames actually rendered.

use crate::stats::median;
use std::collections::HashMap;
use std::sync::{Arc, Mutex};

use super::request::FrameRequest;
use super::{RenderError, Renderer};
use crate::settings::{Preset, RenderSettings};

/// Weight of the newest frame in the running estimate: a few frames to follow a change, not
/// thrown by one slow frame.
const NEWEST: f64 = 0.2;

/// The kinds of frame whose cost per pixel differs by more than noise.
#[derive(Debug, Clone, PartialEq, Eq, Hash)]
struct CostClass {
    scene: String,
    foveated: bool,
    /// A foveated frame's sampling and reconstruction knobs (empty when not foveated): presets
    /// sharing a rung shade from 2% to 20% of the pixels and reconstruct differently.
    sampling: String,
    rung: u32,
}

impl CostClass {
    fn of(req: &FrameRequest) -> CostClass {
        let f = &req.settings.foveation;
        CostClass {
            scene: req.scene.clone(),
            foveated: f.enabled,
            // Every knob, so two settings that differ in any are never averaged together.
            sampling: if f.enabled {
                format!("{f:?}")
            } else {
                String::new()
            },
            rung: req.settings.translucency.rung.id(),
        }
    }
}

/// A kind of frame's cost: `fixed_ms + per_mp × megapixels`.
#[derive(Debug, Clone, Copy, PartialEq)]
struct Fit {
    fixed_ms: f64,
    per_mp: f64,
}

impl Fit {
    fn at(&self, mp: f64) -> f64 {
        self.fixed_ms + self.per_mp * mp
    }

    /// The line through two measured frames; the per-pixel part never negative.
    fn through((mp0, ms0): (f64, f64), (mp1, ms1): (f64, f64)) -> Option<Fit> {
        let ok = |x: f64| x.is_finite() && x >= 0.0;
        if !(ok(mp0) && ok(ms0) && ok(mp1) && ok(ms1)) || mp1 <= mp0 {
            return None;
        }
        let per_mp = ((ms1 - ms0) / (mp1 - mp0)).max(0.0);
        Some(Fit {
            fixed_ms: (ms0 - per_mp * mp0).max(0.0),
            per_mp,
        })
    }
}

/// Running estimates, shared between the render thread (which learns) and sessions (which ask).
#[derive(Debug, Clone, Default)]
pub struct CostModel(Arc<Mutex<HashMap<CostClass, Fit>>>);

fn megapixels(req: &FrameRequest) -> f64 {
    f64::from(req.width) * f64::from(req.height) / 1e6
}

impl CostModel {
    /// Expected render milliseconds of `req`, if a frame of its kind has been seen (of its
    /// scene, else of any scene: the same rung costs alike per pixel across our scenes).
    pub fn estimate_ms(&self, req: &FrameRequest) -> Option<f64> {
        let map = self.0.lock().ok()?;
        let class = CostClass::of(req);
        let mp = megapixels(req);
        map.get(&class).map(|f| f.at(mp)).or_else(|| {
            map.iter()
                .filter(|(c, _)| c.foveated == class.foveated && c.rung == class.rung)
                .map(|(_, f)| f.at(mp))
                .reduce(f64::max)
        })
    }

    /// Learns from a frame that took `ms` of render-thread time in all: the per-pixel part
    /// follows it, the fixed part stays what calibration found.
    pub fn record(&self, req: &FrameRequest, ms: f64) {
        let mp = megapixels(req);
        if !(ms.is_finite() && ms >= 0.0 && mp > 0.0) {
            return;
        }
        if let Ok(mut map) = self.0.lock() {
            let fit = map.entry(CostClass::of(req)).or_insert(Fit {
                fixed_ms: 0.0,
                per_mp: ms / mp,
            });
            let per_mp = (ms - fit.fixed_ms).max(0.0) / mp;
            fit.per_mp += NEWEST * (per_mp - fit.per_mp);
        }
    }

    /// What foveating `req` is expected to save, from frames of its own scene and rung rendered
    /// both ways on this adapter; `None` until both kinds have been measured (another scene's
    /// figures do not decide this: how much a scene's shading weighs against the fixed passes
    /// is the very thing that differs).
    pub fn foveation_verdict(&self, req: &FrameRequest) -> Option<Verdict> {
        if !req.settings.foveation.enabled {
            return None;
        }
        let map = self.0.lock().ok()?;
        let mp = megapixels(req);
        let mut whole = req.clone();
        whole.settings.foveation.enabled = false;
        Some(Verdict {
            foveated_ms: map.get(&CostClass::of(req))?.at(mp),
            whole_ms: map.get(&CostClass::of(&whole))?.at(mp),
        })
    }

    /// Sets a kind of frame's cost from two frames of different sizes.
    fn calibrated(&self, small: (&FrameRequest, f64), large: (&FrameRequest, f64)) {
        let point = |(r, ms): (&FrameRequest, f64)| (megapixels(r), ms);
        if let (Some(fit), Ok(mut map)) = (Fit::through(point(small), point(large)), self.0.lock())
        {
            map.insert(CostClass::of(small.0), fit);
        }
    }
}

/// A foveated frame's expected cost against the same frame shaded whole.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Verdict {
    pub foveated_ms: f64,
    pub whole_ms: f64,
}

/// Foveation must save at least this share of the whole frame to be worth what it costs in
/// the periphery: within 5% the two are within this machine's frame-to-frame noise.
pub const WORTH_SAVING: f64 = 0.05;

impl Verdict {
    /// Whether foveating saves enough to be worth it.
    pub fn pays(&self) -> bool {
        self.saves(WORTH_SAVING)
    }

    /// Whether foveating saves more than `share` of the whole frame's cost.
    pub fn saves(&self, share: f64) -> bool {
        self.foveated_ms < self.whole_ms * (1.0 - share)
    }
}

impl std::fmt::Display for Verdict {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(
            f,
            "foveated ~{:.0} ms, shaded whole ~{:.0} ms",
            self.foveated_ms, self.whole_ms
        )
    }
}

/// Renders `req` foveated and shaded whole, `frames` times each (interleaved, so a machine
/// slowing down weighs on both alike) after one each that builds pipelines, and compares the
/// median render times as the render thread compares its estimates.
pub fn measure_foveation(
    renderer: &mut Renderer,
    req: &FrameRequest,
    frames: u32,
) -> Result<Verdict, RenderError> {
    let mut whole = req.clone();
    whole.settings.foveation.enabled = false;
    let mut foveated = req.clone();
    foveated.settings.foveation.enabled = true;
    for r in [&foveated, &whole] {
        renderer.render(r)?;
    }
    let (mut f, mut w) = (Vec::new(), Vec::new());
    for _ in 0..frames.max(1) {
        f.push(renderer.render(&foveated)?.render_ms);
        w.push(renderer.render(&whole)?.render_ms);
    }
    renderer.release_stream(req.stream);
    Ok(Verdict {
        foveated_ms: median(f),
        whole_ms: median(w),
    })
}

/// Frames timed per preset and size at start-up (after one that is not), where foveation's
/// verdict compares them; the reference, which only sizes admission and costs four times
/// `full`, is timed once (its two more frames were a fifth of a lavapipe start-up).
const CALIBRATION_FRAMES: usize = 3;

fn calibration_frames(preset: Preset) -> usize {
    if preset == Preset::Reference {
        1
    } else {
        CALIBRATION_FRAMES
    }
}

/// Renders frames of `scene` for each preset at two sizes so the first sessions' estimates come
/// from this adapter (a first frame at each size builds pipelines and is not counted). Returns
/// each preset's estimate for a 1920×1080 frame, for the log.
pub fn calibrate(renderer: &mut Renderer, model: &CostModel, scene: &str) -> Vec<(Preset, f64)> {
    let mut estimates = Vec::new();
    for (i, preset) in Preset::ALL.into_iter().enumerate() {
        let stream = u64::MAX - i as u64;
        let at = |w, h| FrameRequest {
            settings: RenderSettings::of(preset),
            stream,
            ..FrameRequest::new(scene, w, h)
        };
        // Four times the pixels apart: enough to split the fixed from the per-pixel part. The
        // larger is the page's default size, so the first sessions' foveation verdict there is
        // measured, not extrapolated: from 160×120 and 320×240 (where a larger share of the
        // pixels is shaded) it said foveating `gallery` at 640×480 costs ~182 ms against ~157
        // whole, and the page's frames were shaded whole, where the bench measures 141 against
        // 171. Start-up here: ~2.4 s → ~6.7 s (a slower host once took 38 s for 480×360;
        // three instances must start within fleet.sh's minute).
        let (small, large) = (at(320, 240), at(640, 480));
        // After a frame that builds pipelines and history, the median of a few: one frame of
        // a noisy machine decided whether a preset's foveation pays.
        let mut time = |req: &FrameRequest| -> Result<f64, RenderError> {
            renderer.render(req)?;
            let timed: Result<Vec<f64>, RenderError> = (0..calibration_frames(preset))
                .map(|_| renderer.render(req).map(|f| f.render_ms))
                .collect();
            Ok(median(timed?))
        };
        match (time(&small), time(&large)) {
            (Ok(a), Ok(b)) => {
                model.calibrated((&small, a), (&large, b));
                if let Some(ms) = model.estimate_ms(&at(1920, 1080)) {
                    estimates.push((preset, ms));
                }
            }
            (Err(e), _) | (_, Err(e)) => tracing::warn!("calibrating {preset} frames: {e}"),
        }
        renderer.release_stream(stream);
    }
    estimates
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::settings::Rung;

    fn req(w: u32, h: u32, preset: Preset) -> FrameRequest {
        FrameRequest {
            settings: RenderSettings::of(preset),
            ..FrameRequest::new("gallery", w, h)
        }
    }

    #[test]
    fn estimates_scale_with_pixels_and_follow_new_frames() {
        let m = CostModel::default();
        assert_eq!(m.estimate_ms(&req(640, 480, Preset::Reference)), None);
        m.record(&req(640, 480, Preset::Reference), 300.0);
        let e = m.estimate_ms(&req(1280, 960, Preset::Reference)).unwrap();
        assert!((e - 1200.0).abs() < 1e-6, "{e}");
        // Another kind of frame is not estimated from this one.
        assert_eq!(m.estimate_ms(&req(640, 480, Preset::Balanced)), None);
        // Another scene's frame of the same kind is.
        let mut other = req(640, 480, Preset::Reference);
        other.scene = "cornell".into();
        assert!(m.estimate_ms(&other).is_some());
        for _ in 0..40 {
            m.record(&req(640, 480, Preset::Reference), 150.0);
        }
        let e = m.estimate_ms(&req(640, 480, Preset::Reference)).unwrap();
        assert!((e - 150.0).abs() < 1.0, "{e}");
    }

    #[test]
    fn a_fixed_part_keeps_large_frames_from_looking_dear() {
        let m = CostModel::default();
        let (small, large) = (req(160, 120, Preset::Fast), req(480, 360, Preset::Fast));
        // 40 ms whatever the size, plus 100 ms per megapixel.
        let ms = |r: &FrameRequest| 40.0 + 100.0 * megapixels(r);
        m.calibrated((&small, ms(&small)), (&large, ms(&large)));
        let big = req(3840, 2160, Preset::Fast);
        let e = m.estimate_ms(&big).unwrap();
        assert!((e - ms(&big)).abs() < 1e-6, "{e}");
        // Frames rendered later move the per-pixel part only.
        for _ in 0..60 {
            m.record(&big, 40.0 + 50.0 * megapixels(&big));
        }
        let e = m.estimate_ms(&small).unwrap();
        assert!((e - (40.0 + 50.0 * megapixels(&small))).abs() < 0.1, "{e}");
        // Calibration that makes no sense is ignored.
        assert_eq!(Fit::through((0.1, 5.0), (0.1, 9.0)), None);
        assert_eq!(Fit::through((0.1, f64::NAN), (0.2, 9.0)), None);
        // A larger frame measured faster gives no negative per-pixel cost.
        let f = Fit::through((0.1, 50.0), (0.2, 40.0)).unwrap();
        assert!(f.per_mp == 0.0 && f.fixed_ms == 50.0);
    }

    #[test]
    fn foveation_is_judged_on_its_own_scene_and_rung_measured_both_ways() {
        let m = CostModel::default();
        let fov = req(640, 480, Preset::Balanced);
        assert_eq!(m.foveation_verdict(&fov), None);
        m.record(&fov, 80.0);
        // Half the evidence is no verdict.
        assert_eq!(m.foveation_verdict(&fov), None);
        // Another scene shaded whole says nothing about this one.
        let mut elsewhere = req(640, 480, Preset::Full);
        elsewhere.scene = "opaque".into();
        m.record(&elsewhere, 10.0);
        assert_eq!(m.foveation_verdict(&fov), None);
        m.record(&req(640, 480, Preset::Full), 200.0);
        let v = m.foveation_verdict(&fov).unwrap();
        assert_eq!((v.foveated_ms, v.whole_ms), (80.0, 200.0));
        assert!(v.pays());
        // Saving less than WORTH_SAVING is not worth it; costing more certainly is not.
        let close = Verdict {
            foveated_ms: 196.0,
            whole_ms: 200.0,
        };
        assert!(!close.pays());
        let dearer = Verdict {
            foveated_ms: 30.0,
            whole_ms: 25.0,
        };
        assert!(!dearer.pays());
        assert_eq!(dearer.to_string(), "foveated ~30 ms, shaded whole ~25 ms");
        // A frame that is not foveated has no verdict; other sampling knobs are another kind.
        assert_eq!(m.foveation_verdict(&req(640, 480, Preset::Full)), None);
        assert_eq!(m.foveation_verdict(&req(640, 480, Preset::Fast)), None);
        // A different rung is a different verdict.
        let mut other = fov.clone();
        other.settings.translucency.rung = Rung::Opaque;
        assert_eq!(m.foveation_verdict(&other), None);
    }

    #[test]
    fn nonsense_times_and_empty_frames_teach_nothing() {
        let m = CostModel::default();
        let r = req(64, 64, Preset::Full);
        for ms in [f64::NAN, f64::INFINITY, -1.0] {
            m.record(&r, ms);
        }
        m.record(&req(0, 64, Preset::Full), 10.0);
        assert_eq!(m.estimate_ms(&r), None);
        m.record(&r, 0.0);
        assert_eq!(m.estimate_ms(&r), Some(0.0));
        let mut s = r.clone();
        s.settings.translucency.rung = Rung::Opaque;
        assert_eq!(m.estimate_ms(&s), None);
    }
}
