//! How well prediction hides latency on a recording: angular error between the gaze predicted
//! `h` ms ahead and the gaze actually recorded then, for no prediction (hold the last sample)
//! and for `Predictor`, split into fixation and saccade samples.

use super::prediction::Predictor;
use super::Sample;
use crate::viewing::Viewing;

#[derive(Debug, Clone, PartialEq, serde::Serialize)]
pub struct HorizonError {
    pub horizon_ms: f64,
    pub class: &'static str,
    pub samples: usize,
    pub hold_median_deg: f64,
    pub hold_p95_deg: f64,
    pub predicted_median_deg: f64,
    pub predicted_p95_deg: f64,
}

fn percentile(v: &mut [f64], q: f64) -> f64 {
    if v.is_empty() {
        return f64::NAN;
    }
    v.sort_by(|a, b| a.total_cmp(b));
    v[((q * (v.len() - 1) as f64).round() as usize).min(v.len() - 1)]
}

pub fn evaluate(samples: &[Sample], viewing: &Viewing, horizons: &[f64]) -> Vec<HorizonError> {
    let frame_deg = viewing.field_of_view_deg();
    let mut out = Vec::new();
    for &h in horizons {
        // (class, hold error, predicted error)
        let mut errors: Vec<(bool, f64, f64)> = Vec::new();
        let mut predictor = Predictor::new(frame_deg);
        let mut j = 0;
        for s in samples {
            let Some(xy) = s.xy else { continue };
            predictor.push(s.t_ms, xy);
            // The recorded gaze h ms later (nearest sample within 1 ms), if valid.
            while j < samples.len() && samples[j].t_ms < s.t_ms + h - 1.0 {
                j += 1;
            }
            let Some(future) = samples
                .get(j)
                .filter(|f| (f.t_ms - (s.t_ms + h)).abs() <= 1.0)
                .and_then(|f| f.xy)
            else {
                continue;
            };
            let Some(predicted) = predictor.predict(h) else {
                continue;
            };
            let saccade = predictor.in_saccade();
            errors.push((
                saccade,
                viewing.angle_deg(xy, future),
                viewing.angle_deg(predicted, future),
            ));
        }
        for (class, want) in [("fixation", false), ("saccade", true)] {
            let mut hold: Vec<f64> = errors.iter().filter(|e| e.0 == want).map(|e| e.1).collect();
            let mut pred: Vec<f64> = errors.iter().filter(|e| e.0 == want).map(|e| e.2).collect();
            out.push(HorizonError {
                horizon_ms: h,
                class,
                samples: hold.len(),
                hold_median_deg: percentile(&mut hold, 0.5),
                hold_p95_deg: percentile(&mut hold, 0.95),
                predicted_median_deg: percentile(&mut pred, 0.5),
                predicted_p95_deg: percentile(&mut pred, 0.95),
            });
        }
    }
    out
}

pub fn markdown(rows: &[HorizonError]) -> String {
    let mut s = String::from("| horizon | samples | class | hold median ° | hold p95 ° | predicted median ° | predicted p95 ° |\n|---:|---:|---|---:|---:|---:|---:|\n");
    for r in rows {
        s.push_str(&format!(
            "| {} ms | {} | {} | {:.3} | {:.3} | {:.3} | {:.3} |\n",
            r.horizon_ms,
            r.samples,
            r.class,
            r.hold_median_deg,
            r.hold_p95_deg,
            r.predicted_median_deg,
            r.predicted_p95_deg
        ));
    }
    s
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn prediction_beats_holding_during_smooth_motion_and_matches_it_at_rest() {
        let v = Viewing {
            width: 1920,
            height: 1080,
            width_cm: 53.0,
            distance_cm: 60.0,
        };
        // Synthetic-eye saccades: prediction must beat holding during them.
        let samples = crate::gaze::synthetic::generate(9, &v, 1000.0, 30_000.0);
        let rows = evaluate(&samples, &v, &[20.0]);
        let moving = rows.iter().find(|r| r.class == "saccade").unwrap();
        assert!(
            moving.samples > 200 && moving.predicted_median_deg < 0.5 * moving.hold_median_deg,
            "{moving:?}"
        );
        let still = rows.iter().find(|r| r.class == "fixation").unwrap();
        assert!(
            still.predicted_median_deg <= still.hold_median_deg + 1e-12,
            "{still:?}"
        );
    }
}
