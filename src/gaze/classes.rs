//! What the eye was doing at each sample, for scoring prediction per class of movement.
//!
//! Labels come from the recording's own saccade events where it has them (EyeLink ASC `ESACC`)
//! and otherwise from velocity (I-VT): the angular speed from a central difference over
//! ±`SACCADE_HALF_MS` is a saccade at `SACCADE_DEG_S` or more (EyeLink's own parser threshold);
//! smooth pursuit is a speed of `PURSUIT_DEG_S` or more over the wider ±`PURSUIT_HALF_MS`
//! (wide enough that tracker noise, ~0.01–0.03° per sample, stays near 1°/s) with no saccade
//! in that window. The labels look ahead and behind: they describe the recording, they are
//! never shown to a predictor.

use super::Sample;
use crate::viewing::Viewing;

pub const SACCADE_DEG_S: f64 = 30.0;
pub const SACCADE_HALF_MS: f64 = 4.0;
pub const PURSUIT_DEG_S: f64 = 5.0;
pub const PURSUIT_HALF_MS: f64 = 10.0;
/// A sample this soon after track loss or a blink ended is "post-gap", whatever it does.
pub const POST_GAP_MS: f64 = 50.0;

/// The motion at one sample.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Motion {
    /// No gaze that a client would send (track loss, blink, far off the frame).
    Gap,
    Still,
    Pursuit,
    Saccade,
}

/// The class a prediction from one sample is scored in.
#[derive(Debug, Clone, Copy, PartialEq, Eq, PartialOrd, Ord, Hash, serde::Serialize)]
#[serde(rename_all = "snake_case")]
pub enum Class {
    Fixation,
    Saccade,
    Pursuit,
    PostGap,
    SaccadeOnset,
}

impl Class {
    pub const ALL: [Class; 5] = [
        Class::Fixation,
        Class::Saccade,
        Class::Pursuit,
        Class::PostGap,
        Class::SaccadeOnset,
    ];
    pub fn name(self) -> &'static str {
        match self {
            Class::Fixation => "fixation",
            Class::Saccade => "saccade",
            Class::Pursuit => "pursuit",
            Class::PostGap => "post_gap",
            Class::SaccadeOnset => "saccade_onset",
        }
    }
}

/// The position at `i`, if it is a sample a client would send (already clamped to the frame).
pub type Positions = [Option<[f64; 2]>];

/// Central-difference speed (deg/s) at `i` over ±`half` ms, from the valid samples nearest
/// those times with no gap in between; None where the window reaches a gap or the ends.
fn speed(
    samples: &[Sample],
    pos: &Positions,
    viewing: &Viewing,
    i: usize,
    half: f64,
) -> Option<f64> {
    let t = samples[i].t_ms;
    let mut a = i;
    while a > 0 && samples[a].t_ms > t - half {
        a -= 1;
        pos[a]?;
    }
    let mut b = i;
    while b + 1 < samples.len() && samples[b].t_ms < t + half {
        b += 1;
        pos[b]?;
    }
    let dt = samples[b].t_ms - samples[a].t_ms;
    if dt <= 0.0 {
        return None;
    }
    Some(viewing.angle_deg(pos[a]?, pos[b]?) / dt * 1e3)
}

/// Labels every sample. `saccades`: the recording's own saccade intervals (ms), if it has them.
pub fn label(
    samples: &[Sample],
    pos: &Positions,
    viewing: &Viewing,
    saccades: Option<&[(f64, f64)]>,
) -> Vec<Motion> {
    let fast: Vec<bool> = (0..samples.len())
        .map(|i| match saccades {
            Some(events) => {
                let t = samples[i].t_ms;
                events.iter().any(|&(a, b)| a <= t && t <= b)
            }
            None => {
                speed(samples, pos, viewing, i, SACCADE_HALF_MS).is_some_and(|v| v >= SACCADE_DEG_S)
            }
        })
        .collect();
    (0..samples.len())
        .map(|i| {
            if pos[i].is_none() {
                return Motion::Gap;
            }
            if fast[i] {
                return Motion::Saccade;
            }
            let t = samples[i].t_ms;
            let near_saccade = (0..samples.len())
                .rev()
                .skip(samples.len() - i)
                .take_while(|&k| samples[k].t_ms >= t - PURSUIT_HALF_MS)
                .chain(
                    (i + 1..samples.len()).take_while(|&k| samples[k].t_ms <= t + PURSUIT_HALF_MS),
                )
                .any(|k| fast[k]);
            let slow_move = speed(samples, pos, viewing, i, PURSUIT_HALF_MS)
                .is_some_and(|v| v >= PURSUIT_DEG_S);
            if slow_move && !near_saccade {
                Motion::Pursuit
            } else {
                Motion::Still
            }
        })
        .collect()
}

/// The class of a prediction made at sample `i` for `h` ms later, from what the eye does at
/// t: post-gap within `POST_GAP_MS` of the last gap's end (or of the recording's start);
/// saccade when it is in one; pursuit when it pursues; otherwise fixation, or saccade onset
/// when a saccade starts in (t, t + h]: no method can see that one coming, so it is kept
/// apart rather than inflating the fixation figures or the saccade ones.
/// `since_gap`: ms since the last gap ended, at each sample.
pub fn classify(
    samples: &[Sample],
    motion: &[Motion],
    since_gap: &[f64],
    i: usize,
    h: f64,
) -> Class {
    if since_gap[i] <= POST_GAP_MS {
        return Class::PostGap;
    }
    match motion[i] {
        Motion::Saccade => return Class::Saccade,
        Motion::Pursuit => return Class::Pursuit,
        _ => {}
    }
    let t = samples[i].t_ms;
    let onset = (i + 1..samples.len())
        .take_while(|&k| samples[k].t_ms <= t + h + 1e-6)
        .any(|k| motion[k] == Motion::Saccade);
    if onset {
        Class::SaccadeOnset
    } else {
        Class::Fixation
    }
}

/// Milliseconds since the last gap ended (the recording's start counts as one), per sample.
pub fn since_gap(samples: &[Sample], pos: &Positions) -> Vec<f64> {
    let mut start = samples.first().map_or(0.0, |s| s.t_ms);
    let mut in_gap = true;
    let mut previous = f64::NEG_INFINITY;
    samples
        .iter()
        .zip(pos)
        .map(|(s, p)| {
            if p.is_none() {
                in_gap = true;
                return 0.0;
            }
            // Rows missing altogether are a gap too (a tracker that drops samples).
            if in_gap
                || s.t_ms - std::mem::replace(&mut previous, s.t_ms) > super::MAX_SAMPLE_GAP_MS
            {
                previous = s.t_ms;
                start = s.t_ms;
                in_gap = false;
            }
            s.t_ms - start
        })
        .collect()
}
