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
//! four typical intervals): after track loss the eye is somewhere new. Predictions are
//! clamped to the frame widened by `OFF_FRAME_MARGIN` and are never NaN. The tuning was
//! chosen on the 500 Hz shipped recording and is reported on the 1000 Hz one
//! (`docs/gaze/prediction.md`).

use std::collections::VecDeque;

use super::{MAX_SAMPLE_GAP_MS, OFF_FRAME_MARGIN};

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
}

impl Default for Tuning {
    fn default() -> Self {
        Tuning {
            velocity_ms: 2.0,
            onset_deg_s: 45.0,
            confirm: 2,
            end_fraction: 0.5,
            past_peak: 0.4,
            rising_gain: 1.0,
            amplitude_gain: 0.7,
        }
    }
}

/// The saccade in flight.
#[derive(Debug, Clone, Copy)]
struct Saccade {
    onset: [f64; 2],
    peak_deg_s: f64,
}

#[derive(Debug, Clone)]
pub struct Predictor {
    tuning: Tuning,
    /// Degrees of visual angle per frame width and height (small-angle scale of the display).
    deg_per_frame: [f64; 2],
    history: VecDeque<(f64, [f64; 2])>,
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
        self.history.push_back((t_ms, xy));
        let window = self.tuning.velocity_ms;
        while self.history.len() > 2 && self.history.front().is_some_and(|(t, _)| t_ms - t > window)
        {
            self.history.pop_front();
        }
        self.follow_saccade();
    }

    /// Drops everything learned: after a gap the eye is somewhere new.
    fn forget(&mut self) {
        self.history.clear();
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
            if speed < tuning.end_fraction * s.peak_deg_s || speed < 0.5 * tuning.onset_deg_s {
                self.landing = self.saccade.take();
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
        if self.fast_run >= tuning.confirm {
            if let Some(onset) = self.candidate_onset {
                self.saccade = Some(Saccade {
                    onset,
                    peak_deg_s: speed,
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
        if let Some(s) = self.saccade {
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
