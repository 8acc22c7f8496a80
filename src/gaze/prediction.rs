//! Gaze prediction: where the eye will be when the frame is shown, from recent samples.
//!
//! Scored on recordings (`evaluate`), three things decide the error: fixations and pursuit
//! move less over tens of milliseconds than tracker noise, so extrapolating them only adds
//! noise (the constant-velocity baseline loses to holding there on both shipped recordings);
//! a saccade cannot be seen before it starts; and once one is in flight its landing point is
//! predictable from its speed. So the predictor holds the last sample, except in a saccade it
//! has confirmed, which it moves on by a constant-deceleration model:
//!
//! * velocity is a least-squares slope over the last `Tuning::velocity_ms`, in degrees;
//! * a saccade starts when the speed reaches `onset_deg_s` on `confirm` samples in a row, its
//!   onset the oldest sample of the window that first crossed; it ends when the speed falls
//!   below `end_fraction` of its peak or under `onset_deg_s / 2`;
//! * its amplitude comes from the main sequence of the synthetic eye (V = 1.875·A/D,
//!   D = 2.2·A + 21 ms ⇒ A = 21·V/(1875 − 2.2·V)) applied to the peak speed once the eye is
//!   decelerating (speed below `past_peak` of the peak: the peak is known), and to the current
//!   speed times `rising_gain` before that (the peak is still to come); real eyes run slower
//!   than that model, so the amplitude is scaled by the median ratio of landed to
//!   main-sequence amplitude over the viewer's last `RATIOS_KEPT` saccades (`amplitude_gain`
//!   until three have landed): each viewer's own main sequence, learned as the session goes;
//! * the remaining distance R = A − travelled is covered at constant deceleration from the
//!   current speed v: in h ms the eye moves v·h − v²h²/(4R) until it stops at R (h ≥ 2R/v).
//!
//! History is dropped at a gap (samples more than `MAX_SAMPLE_GAP_MS` apart, or more than
//! four typical intervals): after track loss the eye is somewhere new. A saccade confirmed
//! within `POST_GAP_MS` of the gap whose speed reaches `post_gap_onset_deg_s` (on one sample,
//! not `confirm`) is a post-gap movement instead: after a blink the eye is often found already
//! moving, its onset unseen, and such movements run slower and longer than the main sequence
//! says (on the shipped recordings, 150–400°/s for 30–40 ms). It is extrapolated kinematically: a
//! position-velocity-acceleration fit over `post_gap_fit_ms`, moved on at the fitted
//! deceleration until it stops (never accelerated), by `post_gap_gain` of that travel (the
//! fit is noisy, and a shrunk guess loses less when the eye stops early). It is not learned
//! from, and it ends at the slow speed only. Predictions are
//! clamped to the frame widened by `OFF_FRAME_MARGIN` and are never NaN. The tuning was
//! chosen on the 500 Hz shipped recording (`examples/tune_prediction.rs`: the saccade knobs
//! on the saccade class, then the post-gap knobs on the post-gap class) and is reported on
//! the 1000 Hz one (`docs/gaze/prediction.md`).

use std::collections::VecDeque;

use super::{MAX_SAMPLE_GAP_MS, OFF_FRAME_MARGIN};
use crate::gaze::classes::POST_GAP_MS;

/// The knobs, chosen on one recording (see the module comment).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Tuning {
    pub velocity_ms: f64,
    pub onset_deg_s: f64,
    pub confirm: u32,
    pub end_fraction: f64,
    pub past_peak: f64,
    pub rising_gain: f64,
    /// Scales the main-sequence amplitude (real saccades run slower than the synthetic eye's).
    pub amplitude_gain: f64,
    /// The window (ms) of the position-velocity-acceleration fit that follows a movement
    /// found within `POST_GAP_MS` of a gap.
    pub post_gap_fit_ms: f64,
    /// The share of the kinematic travel predicted after a gap.
    pub post_gap_gain: f64,
    /// The peak speed (deg/s) that makes a movement near a gap a post-gap movement.
    pub post_gap_onset_deg_s: f64,
}

impl Default for Tuning {
    fn default() -> Self {
        Tuning {
            velocity_ms: 2.0,
            onset_deg_s: 45.0,
            confirm: 2,
            end_fraction: 0.5,
            past_peak: 0.95,
            rising_gain: 1.0,
            amplitude_gain: 0.6,
            post_gap_fit_ms: 6.0,
            post_gap_gain: 0.4,
            post_gap_onset_deg_s: 100.0,
        }
    }
}

/// The saccade in flight.
#[derive(Debug, Clone, Copy)]
struct Saccade {
    onset: [f64; 2],
    peak_deg_s: f64,
    /// Confirmed within `POST_GAP_MS` of a gap (its onset may have been missed).
    near_gap: bool,
}

impl Saccade {
    /// A fast movement right after a gap: its onset was not seen and it need not follow the
    /// main sequence (blink-associated movements run slower and longer than saccades), so it
    /// is extrapolated kinematically and not learned from.
    fn after_gap(&self, tuning: &Tuning) -> bool {
        self.near_gap && self.peak_deg_s >= tuning.post_gap_onset_deg_s
    }
}

#[derive(Debug, Clone)]
pub struct Predictor {
    tuning: Tuning,
    /// Degrees of visual angle per frame width and height (small-angle scale of the display).
    deg_per_frame: [f64; 2],
    history: VecDeque<(f64, [f64; 2])>,
    /// The last `Tuning::post_gap_fit_ms` of samples, for the kinematic fit after a gap.
    recent: VecDeque<(f64, [f64; 2])>,
    /// When the first sample after the last gap (or the first sample at all) arrived.
    resumed_ms: Option<f64>,
    /// Typical time between samples, ms (a running median's cheap cousin: a slow average).
    interval_ms: Option<f64>,
    /// Samples in a row at onset speed, before a saccade is confirmed.
    fast_run: u32,
    /// The oldest sample of the window that first crossed onset speed.
    candidate_onset: Option<[f64; 2]>,
    saccade: Option<Saccade>,
    /// A saccade no longer predicted whose landing is still to be measured.
    landing: Option<Saccade>,
    /// Landed amplitude ÷ main-sequence amplitude of recent saccades, newest last: the
    /// viewer's (and tracker's) own main sequence, learned as the session goes.
    ratios: VecDeque<f64>,
}

/// How many landed saccades the learned amplitude scale remembers.
const RATIOS_KEPT: usize = 15;
/// Speed under which a saccade has landed, deg/s.
const LANDED_DEG_S: f64 = 20.0;

/// The constant-velocity baseline's velocity: a least-squares slope over this many ms.
pub const CV_WINDOW_MS: f64 = 8.0;

/// Constant velocity, the baseline the predictor is scored against: the newest sample moved
/// on by the least-squares velocity of the last `CV_WINDOW_MS`; the newest sample itself with
/// fewer than two.
pub fn constant_velocity(history: &VecDeque<(f64, [f64; 2])>, h: f64) -> Option<[f64; 2]> {
    let &(t_last, last) = history.back()?;
    let window = history
        .iter()
        .filter(|(t, _)| t_last - t <= CV_WINDOW_MS + 1e-9);
    let v = slope(window).unwrap_or([0.0; 2]);
    Some([last[0] + v[0] * h, last[1] + v[1] * h])
}

/// The least-squares slope of position against time, per axis (units per ms); None with
/// fewer than two distinct times.
pub fn slope<'a>(samples: impl Iterator<Item = &'a (f64, [f64; 2])> + Clone) -> Option<[f64; 2]> {
    let n = samples.clone().count() as f64;
    if n < 2.0 {
        return None;
    }
    let mean_t = samples.clone().map(|(t, _)| t).sum::<f64>() / n;
    let den: f64 = samples.clone().map(|(t, _)| (t - mean_t).powi(2)).sum();
    if den <= 0.0 {
        return None;
    }
    Some(std::array::from_fn(|axis| {
        let mean_p = samples.clone().map(|(_, p)| p[axis]).sum::<f64>() / n;
        samples
            .clone()
            .map(|(t, p)| (t - mean_t) * (p[axis] - mean_p))
            .sum::<f64>()
            / den
    }))
}

/// Drops samples older than `window_ms` before `t_ms`, keeping at least two.
fn keep_last(samples: &mut VecDeque<(f64, [f64; 2])>, t_ms: f64, window_ms: f64) {
    while samples.len() > 2 && samples.front().is_some_and(|(t, _)| t_ms - t > window_ms) {
        samples.pop_front();
    }
}

/// Least-squares p(τ) = c + v·τ + a·τ²/2 per axis, τ in ms before the newest sample, in
/// degrees (`scale` per frame unit): the velocity (deg/ms) and acceleration (deg/ms²) at the
/// newest sample. None with fewer than three samples or a singular fit.
pub fn quadratic_fit(
    samples: &VecDeque<(f64, [f64; 2])>,
    scale: [f64; 2],
) -> Option<([f64; 2], [f64; 2])> {
    let &(t_last, _) = samples.back()?;
    if samples.len() < 3 {
        return None;
    }
    // Normal equations over the basis (1, τ, τ²/2).
    let mut m = [[0.0f64; 3]; 3];
    let mut r = [[0.0f64; 3]; 2];
    for &(t, p) in samples {
        let tau = t - t_last;
        let b = [1.0, tau, 0.5 * tau * tau];
        for i in 0..3 {
            for j in 0..3 {
                m[i][j] += b[i] * b[j];
            }
            for axis in 0..2 {
                r[axis][i] += b[i] * p[axis] * scale[axis];
            }
        }
    }
    let solve = |rhs: [f64; 3]| -> Option<[f64; 3]> {
        let det = det3(m);
        if det.abs() < 1e-12 {
            return None;
        }
        Some(std::array::from_fn(|k| {
            let mut mk = m;
            for (row, value) in mk.iter_mut().zip(rhs) {
                row[k] = value;
            }
            det3(mk) / det
        }))
    };
    let x = solve(r[0])?;
    let y = solve(r[1])?;
    let out = ([x[1], y[1]], [x[2], y[2]]);
    [out.0, out.1]
        .iter()
        .flatten()
        .all(|v| v.is_finite())
        .then_some(out)
}

fn det3(m: [[f64; 3]; 3]) -> f64 {
    m[0][0] * (m[1][1] * m[2][2] - m[1][2] * m[2][1])
        - m[0][1] * (m[1][0] * m[2][2] - m[1][2] * m[2][0])
        + m[0][2] * (m[1][0] * m[2][1] - m[1][1] * m[2][0])
}

/// Saccade amplitude (deg) whose main-sequence peak velocity is `v` (deg/s).
pub fn amplitude_from_peak_velocity(v: f64) -> f64 {
    let v = v.clamp(0.0, 800.0);
    21.0 * v / (1875.0 - 2.2 * v)
}

/// Distance (deg) covered in `h` ms from speed `v` (deg/ms) decelerating uniformly to a stop
/// after `remaining` deg.
pub fn decelerated_travel(v: f64, remaining: f64, h: f64) -> f64 {
    if remaining <= 0.0 || v <= 0.0 || h <= 0.0 {
        return 0.0;
    }
    let stop = 2.0 * remaining / v;
    if h >= stop {
        remaining
    } else {
        v * h - v * v * h * h / (4.0 * remaining)
    }
}

impl Predictor {
    /// `frame_deg`: the angle the frame subtends, horizontally and vertically.
    pub fn new(frame_deg: [f64; 2]) -> Predictor {
        Predictor::tuned(frame_deg, Tuning::default())
    }

    pub fn tuned(frame_deg: [f64; 2], tuning: Tuning) -> Predictor {
        Predictor {
            tuning,
            deg_per_frame: frame_deg,
            history: VecDeque::new(),
            recent: VecDeque::new(),
            resumed_ms: None,
            interval_ms: None,
            fast_run: 0,
            candidate_onset: None,
            saccade: None,
            landing: None,
            ratios: VecDeque::new(),
        }
    }

    /// The main-sequence scale to use: the median of the landed saccades' ratios once there
    /// are three, `Tuning::amplitude_gain` before.
    pub fn amplitude_scale(&self) -> f64 {
        if self.ratios.len() < 3 {
            return self.tuning.amplitude_gain;
        }
        let mut r: Vec<f64> = self.ratios.iter().copied().collect();
        r.sort_by(|a, b| a.total_cmp(b));
        r[r.len() / 2]
    }

    /// Adds a valid sample (normalised position, client time in ms). Non-finite samples and
    /// samples going back in time are ignored.
    pub fn push(&mut self, t_ms: f64, xy: [f64; 2]) {
        if !(t_ms.is_finite() && xy[0].is_finite() && xy[1].is_finite()) {
            return;
        }
        if let Some(&(t, _)) = self.history.back() {
            let dt = t_ms - t;
            if dt <= 0.0 {
                return;
            }
            let typical = self.interval_ms.unwrap_or(dt);
            if dt > MAX_SAMPLE_GAP_MS || dt > 4.0 * typical.max(1.0) {
                self.forget();
            } else {
                self.interval_ms = Some(0.95 * typical + 0.05 * dt);
            }
        }
        if self.history.is_empty() {
            self.resumed_ms = Some(t_ms);
        }
        self.history.push_back((t_ms, xy));
        self.recent.push_back((t_ms, xy));
        keep_last(&mut self.history, t_ms, self.tuning.velocity_ms);
        keep_last(&mut self.recent, t_ms, self.tuning.post_gap_fit_ms);
        self.follow_saccade();
    }

    /// Drops everything learned: after a gap the eye is somewhere new.
    fn forget(&mut self) {
        self.history.clear();
        self.recent.clear();
        self.fast_run = 0;
        self.candidate_onset = None;
        self.saccade = None;
        self.landing = None;
    }

    /// Learns the landed amplitude of the saccade last followed, once the eye is still.
    fn follow_landing(&mut self, speed: f64) {
        let (Some(s), Some(&(_, last))) = (self.landing, self.history.back()) else {
            return;
        };
        if speed >= LANDED_DEG_S {
            return;
        }
        self.landing = None;
        let d = self.deg_per_frame;
        let landed = ((last[0] - s.onset[0]) * d[0]).hypot((last[1] - s.onset[1]) * d[1]);
        let expected = amplitude_from_peak_velocity(s.peak_deg_s);
        if expected > 0.5 && landed.is_finite() {
            self.ratios.push_back((landed / expected).clamp(0.2, 2.0));
            if self.ratios.len() > RATIOS_KEPT {
                self.ratios.pop_front();
            }
        }
    }

    fn follow_saccade(&mut self) {
        let speed = self.speed_deg_s();
        let tuning = self.tuning;
        self.follow_landing(speed);
        if let Some(s) = &mut self.saccade {
            // A movement after a gap slows gradually (no main sequence): it ends at the
            // slow speed only.
            let slowed = !s.after_gap(&tuning) && speed < tuning.end_fraction * s.peak_deg_s;
            if slowed || speed < 0.5 * tuning.onset_deg_s {
                self.landing = self.saccade.take().filter(|s| !s.after_gap(&tuning));
                self.fast_run = 0;
                self.candidate_onset = None;
            } else {
                s.peak_deg_s = s.peak_deg_s.max(speed);
            }
            return;
        }
        if speed < tuning.onset_deg_s {
            self.fast_run = 0;
            self.candidate_onset = None;
            return;
        }
        if self.fast_run == 0 {
            self.candidate_onset = self.history.front().map(|(_, p)| *p);
        }
        self.fast_run += 1;
        let t_now = self.history.back().map_or(0.0, |(t, _)| *t);
        let after_gap = self.resumed_ms.is_some_and(|t0| t_now - t0 <= POST_GAP_MS);
        // Right after a gap a movement already at post-gap speed needs no second sample: its
        // onset went unseen and every sample spent confirming it is a sample held behind it.
        let fast_after_gap = after_gap && speed >= tuning.post_gap_onset_deg_s;
        if self.fast_run >= tuning.confirm || fast_after_gap {
            if let Some(onset) = self.candidate_onset {
                self.saccade = Some(Saccade {
                    onset,
                    peak_deg_s: speed,
                    near_gap: after_gap,
                });
            }
        }
    }

    /// Velocity in frame units per ms over the window (None with fewer than two samples).
    pub fn velocity(&self) -> Option<[f64; 2]> {
        slope(self.history.iter())
    }

    /// Angular speed in degrees per second.
    pub fn speed_deg_s(&self) -> f64 {
        self.velocity()
            .map(|v| (v[0] * self.deg_per_frame[0]).hypot(v[1] * self.deg_per_frame[1]) * 1000.0)
            .unwrap_or(0.0)
    }

    /// The newest sample moved on along the fitted velocity, slowing at the fitted
    /// deceleration until it stops; an accelerating fit is followed at constant velocity
    /// (acceleration is not extrapolated, so the guess never runs ahead of it).
    fn kinematic(&self, last: [f64; 2], h: f64) -> [f64; 2] {
        let d = self.deg_per_frame;
        let linear = || {
            let v = slope(self.recent.iter())?;
            Some(([v[0] * d[0], v[1] * d[1]], [0.0; 2]))
        };
        let Some((v, a)) = quadratic_fit(&self.recent, d).or_else(linear) else {
            return last;
        };
        let speed = v[0].hypot(v[1]);
        if speed <= 0.0 {
            return last;
        }
        let dir = [v[0] / speed, v[1] / speed];
        let decel = -(a[0] * dir[0] + a[1] * dir[1]);
        let ahead = self.tuning.post_gap_gain
            * if decel > 0.0 {
                decelerated_travel(speed, speed * speed / (2.0 * decel), h)
            } else {
                speed * h
            };
        [
            last[0] + dir[0] * ahead / d[0],
            last[1] + dir[1] * ahead / d[1],
        ]
    }

    /// Whether a saccade is in flight (confirmed).
    pub fn in_saccade(&self) -> bool {
        self.saccade.is_some()
    }

    /// The predicted gaze `horizon_ms` after the newest sample; None before any sample.
    pub fn predict(&self, horizon_ms: f64) -> Option<[f64; 2]> {
        let &(_, last) = self.history.back()?;
        let h = if horizon_ms.is_finite() {
            horizon_ms.clamp(0.0, 500.0)
        } else {
            0.0
        };
        let mut p = last;
        if self.saccade.is_some_and(|s| s.after_gap(&self.tuning)) {
            p = self.kinematic(last, h);
        } else if let Some(s) = self.saccade {
            let d = self.deg_per_frame;
            let moved = [(last[0] - s.onset[0]) * d[0], (last[1] - s.onset[1]) * d[1]];
            let travelled = moved[0].hypot(moved[1]);
            let speed = self.speed_deg_s();
            if travelled > 1e-6 && speed > 0.0 {
                let dir = [moved[0] / travelled, moved[1] / travelled];
                let amplitude = self.amplitude_scale()
                    * if speed < self.tuning.past_peak * s.peak_deg_s {
                        amplitude_from_peak_velocity(s.peak_deg_s)
                    } else {
                        amplitude_from_peak_velocity(speed * self.tuning.rising_gain)
                    };
                let ahead = decelerated_travel(speed / 1000.0, amplitude - travelled, h);
                p = [
                    last[0] + dir[0] * ahead / d[0],
                    last[1] + dir[1] * ahead / d[1],
                ];
            }
        }
        let m = OFF_FRAME_MARGIN;
        let clamp = |v: f64| {
            if v.is_finite() {
                v.clamp(-m, 1.0 + m)
            } else {
                0.5
            }
        };
        Some([clamp(p[0]), clamp(p[1])])
    }
}
