//! How well prediction hides latency on a recording: the angular error between the gaze
//! predicted `h` ms ahead and the gaze actually recorded at exactly t + h, per class of eye
//! movement (see `classes`), for two baselines and the predictor.
//!
//! Only what a replay would send is scored, and both sides are treated alike: a sample is
//! used if `sendable` (on the frame, or within the margin and clamped onto it); the truth at
//! t + h is interpolated between the two sendable samples around it (never extrapolated, and
//! never across a gap); every prediction is clamped to the frame, as the renderer clamps it.

use std::collections::{BTreeMap, VecDeque};

use super::classes::{self, Class};
use super::prediction::{constant_velocity, Predictor, Tuning, CV_WINDOW_MS};
use super::{sendable, Sample, MAX_SAMPLE_GAP_MS};
use crate::viewing::Viewing;

/// The ways of guessing the gaze h ms ahead that are scored side by side.
pub const METHODS: [&str; 3] = ["hold", "constant_velocity", "predictor"];

#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize)]
pub struct Stat {
    pub median: f64,
    pub p95: f64,
    pub p99: f64,
}

/// One row of the table: a horizon, a class and each method's error in degrees.
#[derive(Debug, Clone, PartialEq, serde::Serialize)]
pub struct HorizonError {
    pub horizon_ms: f64,
    pub class: &'static str,
    pub samples: usize,
    /// In the order of `METHODS`.
    pub methods: [Stat; 3],
}

/// Raw errors (degrees) per horizon and class, per method: pooled across recordings by
/// concatenation, summarised once.
#[derive(Debug, Clone, Default)]
pub struct Errors {
    by: BTreeMap<(u64, Class), [Vec<f64>; 3]>,
}

fn percentile(sorted: &[f64], q: f64) -> f64 {
    if sorted.is_empty() {
        return f64::NAN;
    }
    sorted[((q * (sorted.len() - 1) as f64).round() as usize).min(sorted.len() - 1)]
}

impl Errors {
    pub fn pool(&mut self, other: &Errors) {
        for (k, v) in &other.by {
            let mine = self.by.entry(*k).or_default();
            for (m, o) in mine.iter_mut().zip(v) {
                m.extend_from_slice(o);
            }
        }
    }

    pub fn summary(&self) -> Vec<HorizonError> {
        self.by
            .iter()
            .map(|(&(h, class), v)| {
                let methods = std::array::from_fn(|m| {
                    let mut e = v[m].clone();
                    e.sort_by(|a, b| a.total_cmp(b));
                    Stat {
                        median: percentile(&e, 0.5),
                        p95: percentile(&e, 0.95),
                        p99: percentile(&e, 0.99),
                    }
                });
                HorizonError {
                    horizon_ms: f64::from_bits(h),
                    class: class.name(),
                    samples: v[0].len(),
                    methods,
                }
            })
            .collect()
    }
}

/// The gaze at exactly `t`: a sample at t, or the line between the two samples around it
/// when both are sendable and not a gap apart.
pub fn truth_at(samples: &[Sample], pos: &[Option<[f64; 2]>], t: f64) -> Option<[f64; 2]> {
    const EPS: f64 = 1e-6;
    let j = samples.partition_point(|s| s.t_ms < t - EPS);
    let b = samples.get(j)?;
    if (b.t_ms - t).abs() <= EPS {
        return pos[j];
    }
    let a = samples.get(j.checked_sub(1)?)?;
    if b.t_ms - a.t_ms > MAX_SAMPLE_GAP_MS {
        return None;
    }
    let (pa, pb) = (pos[j - 1]?, pos[j]?);
    let f = (t - a.t_ms) / (b.t_ms - a.t_ms);
    Some([pa[0] + f * (pb[0] - pa[0]), pa[1] + f * (pb[1] - pa[1])])
}

fn on_frame(p: [f64; 2]) -> [f64; 2] {
    [p[0].clamp(0.0, 1.0), p[1].clamp(0.0, 1.0)]
}

/// Scores hold, constant velocity and the predictor on one recording. `saccades`: the
/// recording's own saccade events (ms), used for the labels when present.
pub fn errors(
    samples: &[Sample],
    saccades: Option<&[(f64, f64)]>,
    viewing: &Viewing,
    horizons: &[f64],
    tuning: Tuning,
) -> Errors {
    let pos: Vec<Option<[f64; 2]>> = samples.iter().map(sendable).collect();
    let motion = classes::label(samples, &pos, viewing, saccades);
    let since_gap = classes::since_gap(samples, &pos);
    let mut out = Errors::default();
    let mut predictor = Predictor::tuned(viewing.field_of_view_deg(), tuning);
    let mut history: VecDeque<(f64, [f64; 2])> = VecDeque::new();
    for (i, s) in samples.iter().enumerate() {
        // Only what replay sends reaches a predictor; the baseline forgets across gaps.
        let Some(xy) = pos[i] else { continue };
        if since_gap[i] == 0.0 {
            history.clear();
        }
        history.push_back((s.t_ms, xy));
        while history
            .front()
            .is_some_and(|(t, _)| s.t_ms - t > 4.0 * CV_WINDOW_MS)
        {
            history.pop_front();
        }
        predictor.push(s.t_ms, xy);
        for &h in horizons {
            let Some(truth) = truth_at(samples, &pos, s.t_ms + h) else {
                continue;
            };
            let guesses = [
                Some(xy),
                constant_velocity(&history, h),
                predictor.predict(h),
            ];
            let class = classes::classify(samples, &motion, &since_gap, i, h);
            let slot = out.by.entry((h.to_bits(), class)).or_default();
            for (m, g) in guesses.into_iter().enumerate() {
                // Every method guesses whenever one sample has been sent.
                let g = on_frame(g.unwrap_or(xy));
                slot[m].push(viewing.angle_deg(g, truth));
            }
        }
    }
    out
}

pub fn markdown(rows: &[HorizonError]) -> String {
    let mut s = String::from(
        "| horizon | class | samples | hold median / p95 / p99 ° | constant velocity ° | predictor ° |\n|---:|---|---:|---:|---:|---:|\n",
    );
    let f = |m: &Stat| format!("{:.3} / {:.3} / {:.3}", m.median, m.p95, m.p99);
    for r in rows {
        s.push_str(&format!(
            "| {} ms | {} | {} | {} | {} | {} |\n",
            r.horizon_ms,
            r.class,
            r.samples,
            f(&r.methods[0]),
            f(&r.methods[1]),
            f(&r.methods[2])
        ));
    }
    s
}
