//! Foveation only where it wins. Foveating adds passes whose cost does not fall with the shaded
//! samples (the sampling map, compaction, reconstruction); on a scene whose shading is cheap, or
//! on an adapter where those passes weigh more than on ours, a foveated frame can cost as much
//! as the frame shaded whole, and then it only loses detail. The render thread asks the cost
//! model, which has seen frames of the scene rendered both ways on this adapter, and shades
//! such a frame whole instead, saying why in the frame it returns.
//!
//! Until the scene has been measured both ways, every `PROBE_EVERY`-th frame of a stream is
//! shaded whole to learn what that costs (the first such frame builds pipelines and is not
//! counted, so it takes two). While foveation loses, every `PROBE_EVERY`-th frame is foveated
//! again so the verdict can change back (the gaze moving onto cheap surfaces, say). While it
//! wins, nothing is probed: a whole frame in a foveated stream is a latency spike.

use std::collections::HashMap;

use super::cost::{CostModel, WORTH_SAVING};
use super::request::FrameRequest;

/// Frames of a stream between probes of the choice not taken.
pub const PROBE_EVERY: u64 = 64;

/// What foveating must save for a stream shading whole to foveate again: more than the 5% that
/// keeps it foveating, so estimates hovering at the threshold do not flip the periphery's look
/// every frame (they did at 160×120 on `gallery`, where the two cost within 10%).
pub const RESUME_SAVING: f64 = 0.15;

/// A stream's state: foveated frames asked for, whether the last verdict was that foveation
/// does not pay (logged when that changes, not per frame), and the frame of that change.
#[derive(Debug, Default)]
struct Stream {
    frames: u64,
    losing: bool,
    switched_at: Option<u64>,
}

/// Per stream, its [`Stream`] state.
#[derive(Debug, Default)]
pub struct FoveationPolicy {
    streams: HashMap<u64, Stream>,
}

impl FoveationPolicy {
    /// Turns foveation off in `req` where it does not pay (or to measure it); returns why, for
    /// the frame's header. Requests without foveation are left alone.
    pub fn apply(&mut self, cost: &CostModel, req: &mut FrameRequest) -> Option<String> {
        if !req.settings.foveation.enabled {
            return None;
        }
        let s = self.streams.entry(req.stream).or_default();
        s.frames += 1;
        let probe = s.frames.is_multiple_of(PROBE_EVERY);
        let verdict = cost.foveation_verdict(req);
        // A stream keeps a choice PROBE_EVERY frames before it may change it again: on a GPU
        // frames take a few ms and one frame's noise moves the estimates by more than
        // RESUME_SAVING (an H200 switched five times in 200 ms without this).
        let settled = s.switched_at.is_none_or(|at| s.frames - at >= PROBE_EVERY);
        if let Some(v) = verdict.filter(|_| settled) {
            let need = if s.losing {
                RESUME_SAVING
            } else {
                WORTH_SAVING
            };
            if v.saves(need) == s.losing {
                s.losing = !s.losing;
                s.switched_at = Some(s.frames);
                let (stream, scene) = (req.stream, &req.scene);
                let now = if s.losing {
                    "shading whole"
                } else {
                    "foveating"
                };
                tracing::info!(stream, scene, "{now}: {v}");
            }
        }
        let why = match verdict {
            None if probe => {
                "shaded whole once to measure what foveation saves on this scene".to_string()
            }
            None => return None,
            Some(_) if !s.losing || probe => return None,
            Some(v) => format!("shaded whole: foveation does not pay here ({v})"),
        };
        req.settings.foveation.enabled = false;
        Some(why)
    }

    /// Forgets a stream that has ended.
    pub fn forget(&mut self, stream: u64) {
        self.streams.remove(&stream);
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::settings::{Preset, RenderSettings};

    fn req(preset: Preset, stream: u64) -> FrameRequest {
        FrameRequest {
            settings: RenderSettings::of(preset),
            stream,
            ..FrameRequest::new("gallery", 640, 480)
        }
    }

    /// Which of frames 1..=n of a stream the policy shades whole.
    fn whole_frames(p: &mut FoveationPolicy, cost: &CostModel, stream: u64, n: u64) -> Vec<u64> {
        (1..=n)
            .filter(|_| {
                let mut r = req(Preset::Balanced, stream);
                let why = p.apply(cost, &mut r);
                assert_eq!(why.is_some(), !r.settings.foveation.enabled);
                why.is_some()
            })
            .collect()
    }

    #[test]
    fn unmeasured_scenes_are_probed_and_frames_shaded_whole_are_left_alone() {
        let cost = CostModel::default();
        let mut p = FoveationPolicy::default();
        let mut full = req(Preset::Full, 1);
        assert_eq!(p.apply(&cost, &mut full), None);
        assert_eq!(full.settings, RenderSettings::of(Preset::Full));
        let mut whole = Vec::new();
        for i in 1..=3 * PROBE_EVERY {
            let mut r = req(Preset::Balanced, 1);
            if let Some(why) = p.apply(&cost, &mut r) {
                assert!(why.contains("measure"), "{why}");
                assert!(!r.settings.foveation.enabled);
                whole.push(i);
            }
        }
        assert_eq!(whole, [PROBE_EVERY, 2 * PROBE_EVERY, 3 * PROBE_EVERY]);
        // A stream that ends and comes back starts counting again.
        p.forget(1);
        let mut r = req(Preset::Balanced, 1);
        assert_eq!(p.apply(&cost, &mut r), None);
    }

    #[test]
    fn foveation_that_pays_is_never_interrupted_and_one_that_does_not_is_rechecked() {
        let cost = CostModel::default();
        cost.record(&req(Preset::Balanced, 1), 50.0);
        cost.record(&req(Preset::Full, 1), 200.0);
        let mut p = FoveationPolicy::default();
        assert!(whole_frames(&mut p, &cost, 1, 2 * PROBE_EVERY).is_empty());

        let cheap = CostModel::default();
        cheap.record(&req(Preset::Balanced, 1), 60.0);
        cheap.record(&req(Preset::Full, 1), 40.0);
        let mut p = FoveationPolicy::default();
        let n = 2 * PROBE_EVERY;
        let whole = whole_frames(&mut p, &cheap, 2, n);
        // Every frame but the probes is shaded whole.
        let foveated: Vec<u64> = (1..=n).filter(|i| !whole.contains(i)).collect();
        assert_eq!(foveated, [PROBE_EVERY, 2 * PROBE_EVERY]);
        let mut r = req(Preset::Balanced, 3);
        let why = p.apply(&cheap, &mut r).unwrap();
        assert_eq!(
            why,
            "shaded whole: foveation does not pay here (foveated ~60 ms, shaded whole ~40 ms)"
        );
        // Each rendered frame teaches the model; once foveation wins again, it stays on.
        for _ in 0..40 {
            cheap.record(&req(Preset::Balanced, 2), 10.0);
        }
        assert!(whole_frames(&mut p, &cheap, 2, PROBE_EVERY).is_empty());
    }

    #[test]
    fn a_saving_between_the_two_thresholds_keeps_each_stream_as_it_was() {
        let cost = CostModel::default();
        let between = 1.0 - (WORTH_SAVING + RESUME_SAVING) / 2.0;
        cost.record(&req(Preset::Balanced, 1), 100.0 * between);
        cost.record(&req(Preset::Full, 1), 100.0);
        let mut p = FoveationPolicy::default();
        // A new stream foveates: the saving is over WORTH_SAVING.
        assert!(whole_frames(&mut p, &cost, 1, 10).is_empty());
        // A stream that went whole when foveation lost stays whole until it saves RESUME_SAVING.
        let dear = CostModel::default();
        dear.record(&req(Preset::Balanced, 1), 100.0);
        dear.record(&req(Preset::Full, 1), 100.0);
        assert_eq!(whole_frames(&mut p, &dear, 2, 3), [1, 2, 3]);
        assert_eq!(whole_frames(&mut p, &cost, 2, 10).len(), 10);
        let cheap = CostModel::default();
        cheap.record(&req(Preset::Balanced, 1), 100.0 * (0.99 - RESUME_SAVING));
        cheap.record(&req(Preset::Full, 1), 100.0);
        // Stream 2 switched at its frame 1 and is at frame 13: it foveates again from frame
        // 1 + PROBE_EVERY (this call's frame PROBE_EVERY - 12), the frame before being a probe.
        let expected: Vec<u64> = (1..=PROBE_EVERY - 14).collect();
        assert_eq!(whole_frames(&mut p, &cheap, 2, PROBE_EVERY), expected);
        assert!(whole_frames(&mut p, &cheap, 2, 10).is_empty());
    }

    #[test]
    fn estimates_that_flip_every_frame_switch_a_stream_at_most_once_per_probe_interval() {
        let (dear, cheap) = (CostModel::default(), CostModel::default());
        for (model, foveated) in [(&dear, 100.0), (&cheap, 50.0)] {
            model.record(&req(Preset::Balanced, 1), foveated);
            model.record(&req(Preset::Full, 1), 100.0);
        }
        let mut p = FoveationPolicy::default();
        let n = 4 * PROBE_EVERY;
        let whole: Vec<bool> = (0..n)
            .map(|i| {
                let mut r = req(Preset::Balanced, 1);
                p.apply(if i % 2 == 0 { &dear } else { &cheap }, &mut r)
                    .is_some()
            })
            .collect();
        let changes = whole.windows(2).filter(|w| w[0] != w[1]).count() as u64;
        // At most one switch and one probe (two changes) in each interval.
        assert!(
            changes <= 3 * n / PROBE_EVERY,
            "{changes} changes in {n} frames"
        );
        assert!(
            whole.iter().any(|w| *w),
            "the first verdict still applies at once"
        );
    }
}
