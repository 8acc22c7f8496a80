//! Gaze prediction: where the eye will be when the frame is shown, from recent samples.
//!
//! Constant velocity with saccade detection: the velocity is the least-squares slope over the
//! last `WINDOW_MS` of samples. Below `SACCADE_DEG_S` the eye is fixating (its motion is drift
//! and tracker noise, which extrapolation only amplifies) and the last position is held; above
//! it the eye is in a saccade or pursuit and the motion is extrapolated over the horizon, at
//! most `MAX_LEAD_DEG` ahead (saccades stop; a line does not). Predictions are clamped to the
//! frame widened by `OFF_FRAME_MARGIN`, and are never NaN.

use std::collections::VecDeque;

use super::OFF_FRAME_MARGIN;

pub const WINDOW_MS: f64 = 8.0;
pub const SACCADE_DEG_S: f64 = 30.0;
pub const MAX_LEAD_DEG: f64 = 10.0;

#[derive(Debug, Clone)]
pub struct Predictor {
    /// Degrees of visual angle per frame width and height (small-angle scale of the display).
    deg_per_frame: [f64; 2],
    history: VecDeque<(f64, [f64; 2])>,
}

impl Predictor {
    /// `frame_deg`: the angle the frame subtends, horizontally and vertically.
    pub fn new(frame_deg: [f64; 2]) -> Predictor {
        Predictor { deg_per_frame: frame_deg, history: VecDeque::new() }
    }

    /// Adds a valid sample (normalised position, client time in ms). Non-finite samples and
    /// samples going back in time are ignored.
    pub fn push(&mut self, t_ms: f64, xy: [f64; 2]) {
        if !(t_ms.is_finite() && xy[0].is_finite() && xy[1].is_finite()) {
            return;
        }
        if self.history.back().is_some_and(|(t, _)| *t >= t_ms) {
            return;
        }
        self.history.push_back((t_ms, xy));
        while self.history.front().is_some_and(|(t, _)| t_ms - t > WINDOW_MS) && self.history.len() > 2 {
            self.history.pop_front();
        }
    }

    /// Velocity in frame units per ms over the window (None with fewer than two samples).
    pub fn velocity(&self) -> Option<[f64; 2]> {
        let n = self.history.len();
        if n < 2 {
            return None;
        }
        let mean_t = self.history.iter().map(|(t, _)| t).sum::<f64>() / n as f64;
        let mut v = [0.0; 2];
        for axis in 0..2 {
            let mean_p = self.history.iter().map(|(_, p)| p[axis]).sum::<f64>() / n as f64;
            let (num, den) = self.history.iter().fold((0.0, 0.0), |(a, b), (t, p)| (a + (t - mean_t) * (p[axis] - mean_p), b + (t - mean_t).powi(2)));
            v[axis] = if den > 0.0 { num / den } else { 0.0 };
        }
        Some(v)
    }

    /// Angular speed in degrees per second.
    pub fn speed_deg_s(&self) -> f64 {
        self.velocity().map(|v| (v[0] * self.deg_per_frame[0]).hypot(v[1] * self.deg_per_frame[1]) * 1000.0).unwrap_or(0.0)
    }

    /// The predicted gaze `horizon_ms` after the newest sample; None before any sample.
    pub fn predict(&self, horizon_ms: f64) -> Option<[f64; 2]> {
        let (_, last) = *self.history.back()?;
        let h = if horizon_ms.is_finite() { horizon_ms.clamp(0.0, 500.0) } else { 0.0 };
        let mut p = last;
        if self.speed_deg_s() >= SACCADE_DEG_S {
            if let Some(v) = self.velocity() {
                let mut d = [v[0] * h, v[1] * h];
                let lead_deg = (d[0] * self.deg_per_frame[0]).hypot(d[1] * self.deg_per_frame[1]);
                if lead_deg > MAX_LEAD_DEG {
                    let k = MAX_LEAD_DEG / lead_deg;
                    d = [d[0] * k, d[1] * k];
                }
                p = [last[0] + d[0], last[1] + d[1]];
            }
        }
        let m = OFF_FRAME_MARGIN;
        let clamp = |v: f64| if v.is_finite() { v.clamp(-m, 1.0 + m) } else { 0.5 };
        Some([clamp(p[0]), clamp(p[1])])
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn fixation_holds_and_a_saccade_is_extrapolated() {
        let mut p = Predictor::new([47.7, 29.8]);
        for i in 0..10 {
            p.push(f64::from(i), [0.5 + 1e-5 * f64::from(i % 2), 0.5]);
        }
        assert_eq!(p.predict(30.0), Some([0.5 + 1e-5, 0.5]), "fixation: hold the last sample");
        let mut s = Predictor::new([47.7, 29.8]);
        for i in 0..10 {
            s.push(f64::from(i), [0.3 + 0.002 * f64::from(i), 0.5]); // ~95°/s
        }
        let [x, _] = s.predict(10.0).unwrap();
        assert!((x - (0.318 + 0.02)).abs() < 1e-9, "{x}");
    }

    #[test]
    fn predictions_stay_finite_and_near_the_frame() {
        let mut p = Predictor::new([47.7, 29.8]);
        assert_eq!(p.predict(20.0), None);
        p.push(0.0, [0.99, 0.5]);
        p.push(1.0, [1.0, 0.5]);
        p.push(f64::NAN, [0.0, 0.0]);
        p.push(0.5, [0.0, 0.0]);
        for h in [0.0, 10.0, 50.0, 1e9, f64::NAN, f64::INFINITY, -5.0] {
            let [x, y] = p.predict(h).unwrap();
            assert!(x.is_finite() && y.is_finite());
            assert!((-OFF_FRAME_MARGIN..=1.0 + OFF_FRAME_MARGIN).contains(&x), "h {h}: x {x}");
        }
    }
}
