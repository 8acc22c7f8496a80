//! Gaze prediction and its evaluator: the truth is taken at exactly t + h, the baselines do
//! what they say, and the predictor is never worse than holding the last sample, per class,
//! on synthetic motion and on both shipped recordings (only one of which it was tuned on).

use fovea::gaze::classes::{self, Class, Motion};
use fovea::gaze::evaluate::{errors, truth_at, HorizonError};
use fovea::gaze::formats::{parse, ParseOptions};
use fovea::gaze::prediction::{quadratic_fit, Predictor, Tuning};
use fovea::gaze::{sendable, Sample, OFF_FRAME_MARGIN};
use fovea::viewing::{Display, Viewing};

fn at(t_ms: f64, x: f64, y: f64) -> Sample {
    Sample {
        t_ms,
        xy: Some([x, y]),
        pupil_mm: None,
    }
}

fn lost(t_ms: f64) -> Sample {
    Sample {
        t_ms,
        xy: None,
        pupil_mm: None,
    }
}

#[test]
fn the_truth_is_interpolated_at_exactly_t_plus_h_and_never_across_a_gap() {
    let samples = vec![
        at(0.0, 0.1, 0.5),
        at(2.0, 0.3, 0.5),
        lost(4.0),
        at(6.0, 0.9, 0.5),
    ];
    let pos: Vec<_> = samples.iter().map(sendable).collect();
    assert_eq!(
        truth_at(&samples, &pos, 2.0),
        Some([0.3, 0.5]),
        "on a sample"
    );
    let [x, _] = truth_at(&samples, &pos, 0.5).unwrap();
    assert!((x - 0.15).abs() < 1e-12, "a quarter of the way: {x}");
    assert_eq!(truth_at(&samples, &pos, 3.0), None, "next to track loss");
    assert_eq!(truth_at(&samples, &pos, 7.0), None, "never extrapolated");
    assert_eq!(truth_at(&samples, &pos, -1.0), None);
}

fn viewing(w: u32, h: u32) -> Viewing {
    Viewing::new(Display::default(), w, h)
}

fn row<'a>(rows: &'a [HorizonError], h: f64, class: &str) -> Option<&'a HorizonError> {
    rows.iter().find(|r| r.horizon_ms == h && r.class == class)
}

#[test]
fn constant_velocity_is_exact_on_constant_velocity_at_every_horizon() {
    // 500 Hz, 10°/s across the frame, a 60 ms track loss in the middle; horizons that do not
    // fall on sample times (7 ms) test the interpolation.
    let v = viewing(1920, 1080);
    let speed = 10.0 / v.field_of_view_deg()[0] / 1000.0; // frame widths per ms
    let samples: Vec<Sample> = (0..1500)
        .map(|i| {
            let t = f64::from(i) * 2.0;
            if (1000.0..1060.0).contains(&t) {
                lost(t)
            } else {
                at(t, 0.1 + speed * t, 0.5)
            }
        })
        .collect();
    let rows = errors(&samples, None, &v, &[7.0, 30.0], Tuning::default()).summary();
    for h in [7.0, 30.0] {
        for class in ["pursuit", "post_gap"] {
            let r = row(&rows, h, class).unwrap_or_else(|| panic!("{class} at {h}: {rows:?}"));
            assert!(r.samples > 10, "{r:?}");
            // (The first sample after the gap has no velocity yet: it holds.)
            assert!(r.methods[1].p95 < 1e-9, "constant velocity: {r:?}");
            // Hold is behind by v·h (10°/s in frame units; the angle seen from the eye is a
            // little more or less off-centre).
            let expected = 10.0 * h / 1000.0;
            assert!(
                (r.methods[0].median - expected).abs() < 0.1 * expected,
                "{r:?}"
            );
        }
    }
}

#[test]
fn labels_find_the_saccade_the_pursuit_and_the_gap() {
    let v = viewing(1920, 1080);
    let deg = v.field_of_view_deg()[0];
    // Still 100 ms, a 10° jump over 20 ms, still, then track loss, then 20°/s pursuit.
    let mut samples = Vec::new();
    for i in 0..400 {
        let t = f64::from(i);
        let x = match t {
            t if t < 100.0 => 0.3,
            t if t < 120.0 => 0.3 + 10.0 / deg * (t - 100.0) / 20.0,
            t if t < 200.0 => 0.3 + 10.0 / deg,
            t if t < 230.0 => f64::NAN,
            t => 0.3 + 20.0 / deg * (t - 230.0) / 1000.0,
        };
        samples.push(if x.is_nan() { lost(t) } else { at(t, x, 0.5) });
    }
    let pos: Vec<_> = samples.iter().map(sendable).collect();
    let motion = classes::label(&samples, &pos, &v, None);
    assert_eq!(motion[50], Motion::Still);
    assert_eq!(motion[110], Motion::Saccade);
    assert_eq!(motion[210], Motion::Gap);
    assert_eq!(motion[350], Motion::Pursuit);
    let since = classes::since_gap(&samples, &pos);
    let class = |i: usize, h: f64| classes::classify(&samples, &motion, &since, i, h);
    assert_eq!(class(240, 30.0), Class::PostGap);
    assert_eq!(class(350, 30.0), Class::Pursuit);
    assert_eq!(
        class(85, 30.0),
        Class::SaccadeOnset,
        "a saccade starts within h"
    );
    assert_eq!(class(60, 30.0), Class::Fixation);
    // The recording's own events replace the velocity labels.
    let events = [(50.0, 52.0)];
    let motion = classes::label(&samples, &pos, &v, Some(&events));
    assert_eq!(motion[51], Motion::Saccade);
    assert_ne!(
        motion[110],
        Motion::Saccade,
        "not a saccade by the recording's events"
    );
}

#[test]
fn the_predictor_is_finite_and_near_the_frame_whatever_it_is_fed() {
    // A deterministic stream of hostile input: jumps across the frame, off-frame samples,
    // NaN, repeated and backward times, long gaps.
    let mut p = Predictor::new([47.7, 29.8]);
    assert_eq!(p.predict(20.0), None);
    let mut seed = 0x9e37_79b9_u32;
    let mut next = || {
        seed ^= seed << 13;
        seed ^= seed >> 17;
        seed ^= seed << 5;
        f64::from(seed) / f64::from(u32::MAX)
    };
    let mut t = 0.0;
    for i in 0..20_000 {
        t += match i % 97 {
            0 => 500.0,
            1 => -3.0,
            2 => 0.0,
            _ => 1.0 + next(),
        };
        let xy = match i % 53 {
            0 => [f64::NAN, 0.5],
            1 => [1e300, -1e300],
            _ => [next() * 1.4 - 0.2, next() * 1.4 - 0.2],
        };
        p.push(t, xy);
        for h in [0.0, 10.0, 50.0, 1e9, f64::NAN, f64::INFINITY, -5.0] {
            if let Some([x, y]) = p.predict(h) {
                let m = OFF_FRAME_MARGIN;
                assert!(x.is_finite() && y.is_finite(), "sample {i}, h {h}");
                assert!((-m..=1.0 + m).contains(&x) && (-m..=1.0 + m).contains(&y));
            }
        }
    }
}

/// The predictor's median and p95 are at or below holding's in every class at `horizons`
/// (within 1% + 0.001°, the size of a rare false saccade in a fixation).
fn never_worse_than_holding(rows: &[HorizonError], horizons: &[f64], what: &str) {
    for r in rows.iter().filter(|r| horizons.contains(&r.horizon_ms)) {
        let [hold, _, predicted] = r.methods;
        for (p, h) in [(predicted.median, hold.median), (predicted.p95, hold.p95)] {
            assert!(p <= h * 1.01 + 1e-3, "{what}: worse than holding: {r:?}");
        }
    }
}

#[test]
fn on_synthetic_saccades_prediction_is_never_worse_than_holding() {
    let v = viewing(1920, 1080);
    let samples = fovea::gaze::synthetic::generate(9, &v, 1000.0, 30_000.0);
    let rows = errors(&samples, None, &v, &[10.0, 20.0, 30.0], Tuning::default()).summary();
    never_worse_than_holding(&rows, &[10.0, 20.0, 30.0], "synthetic eye");
    // The tuning, chosen on a real recording, is conservative: real saccades land short of
    // the synthetic eye's main sequence, so on its saccades the gain is small but real.
    let s = row(&rows, 20.0, "saccade").unwrap();
    assert!(
        s.samples > 100 && s.methods[2].median < s.methods[0].median,
        "{s:?}"
    );
}

fn shipped(file: &str, w: u32, h: u32) -> Vec<HorizonError> {
    let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("assets/gaze")
        .join(file);
    let text = std::fs::read_to_string(path).unwrap();
    let opts = ParseOptions {
        screen: Some((w, h)),
        ..Default::default()
    };
    let rec = parse(&text, &opts).unwrap();
    errors(
        &rec.samples,
        rec.saccades.as_deref(),
        &viewing(w, h),
        &[10.0, 20.0, 30.0],
        Tuning::default(),
    )
    .summary()
}

/// Both shipped recordings: the 500 Hz one the tuning was chosen on, and the 1000 Hz one it
/// never saw. The goals at 30 ms: fixation median ≤ 0.1°, never worse than holding in any
/// class, saccade p95 below both baselines.
#[test]
fn on_both_shipped_recordings_the_predictor_is_never_worse_than_holding() {
    for (file, w, h) in [
        ("eyelink_500hz_1920x1200.csv", 1920, 1200),
        ("eyelink_1000hz_1920x1080.csv", 1920, 1080),
    ] {
        let rows = shipped(file, w, h);
        never_worse_than_holding(&rows, &[10.0, 20.0, 30.0], file);
        let fixation = row(&rows, 30.0, "fixation").unwrap();
        assert!(fixation.methods[2].median <= 0.1, "{fixation:?}");
        let saccade = row(&rows, 30.0, "saccade").unwrap();
        let [hold, cv, predicted] = saccade.methods;
        assert!(
            predicted.p95 < hold.p95 && predicted.p95 < cv.p95 && predicted.median < cv.median,
            "{file}: {saccade:?}"
        );
        for class in ["fixation", "pursuit"] {
            let r = row(&rows, 30.0, class).unwrap();
            assert!(r.methods[2].p95 <= r.methods[1].p95, "{file}: {r:?}");
        }
        // After track loss the kinematic extrapolation beats holding in the tail and, by
        // far, constant velocity in the middle (its p95 on the 1000 Hz recording is not
        // beaten: docs/gaze/prediction.md).
        let post = row(&rows, 30.0, "post_gap").unwrap();
        let [hold, cv, predicted] = post.methods;
        assert!(
            predicted.p95 < 0.95 * hold.p95 && predicted.median < 0.6 * cv.median,
            "{file}: {post:?}"
        );
    }
}

#[test]
fn the_kinematic_fit_is_exact_on_a_parabola_and_refuses_too_few_samples() {
    use std::collections::VecDeque;
    // x(t) = 0.3 + 0.02 t − 0.001 t² (frame units, t in ms), y still; 1 frame unit = 40°.
    let x = |t: f64| 0.3 + 0.02 * t - 0.001 * t * t;
    let samples: VecDeque<(f64, [f64; 2])> = (0..6)
        .map(|i| (f64::from(i), [x(f64::from(i)), 0.5]))
        .collect();
    let (v, a) = quadratic_fit(&samples, [40.0, 30.0]).unwrap();
    // At t = 5: dx/dt = 0.02 − 0.002·5 = 0.01 → 0.4°/ms; d²x/dt² = −0.002 → −0.08°/ms².
    assert!((v[0] - 0.4).abs() < 1e-9 && v[1].abs() < 1e-9, "{v:?}");
    assert!((a[0] + 0.08).abs() < 1e-9 && a[1].abs() < 1e-9, "{a:?}");
    let two: VecDeque<_> = samples.iter().copied().take(2).collect();
    assert_eq!(quadratic_fit(&two, [40.0, 30.0]), None);
    // Three samples at one time: singular, refused.
    let same: VecDeque<_> = (0..3).map(|_| (1.0, [0.5, 0.5])).collect();
    assert_eq!(quadratic_fit(&same, [40.0, 30.0]), None);
}

/// A blink, then the eye found again already moving fast and slowing down: the predictor
/// moves on in that direction, never past where the fitted deceleration stops it.
#[test]
fn after_a_gap_a_fast_slowing_eye_is_followed_and_not_overshot() {
    let deg = [40.0, 30.0];
    let mut p = Predictor::new(deg);
    for t in 0..200 {
        p.push(f64::from(t), [0.3, 0.5]);
    }
    // Resumes 100 ms later at 0.35, moving right at 300°/s, decelerating at 10°/s per ms:
    // x(τ) = 0.35 + (0.3·τ − 0.005·τ²)/40 until it stops after 30 ms, 4.5° on.
    let x = |tau: f64| 0.35 + (0.3 * tau - 0.005 * tau * tau) / 40.0;
    for tau in 0..8 {
        p.push(300.0 + f64::from(tau), [x(f64::from(tau)), 0.5]);
        // Followed from its first velocity (the second sample): no sample spent confirming.
        assert_eq!(p.in_saccade(), tau >= 1, "after sample {tau}");
    }
    assert!(p.in_saccade());
    let last = x(7.0);
    let stop = x(30.0);
    let [px, py] = p.predict(30.0).unwrap();
    assert!(
        px > last + 0.005 && px <= stop + 1e-9,
        "{px} from {last}, stops at {stop}"
    );
    assert!((py - 0.5).abs() < 1e-9);
}
