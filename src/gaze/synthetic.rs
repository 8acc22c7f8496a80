//! The synthetic eye: fixations with drift and microsaccades, saccades on the main sequence,
//! smooth pursuit, blinks, and a smoothly varying pupil. Deterministic for a seed. The web page's
//! "auto gaze" (`web/synthetic-eye.js`) runs the same model with the same generator.
//!
//! Positions are degrees of visual angle from the screen centre (x right, y down) and are
//! mapped to the frame through the viewing geometry.

use super::Sample;
use crate::viewing::Viewing;

/// Saccade duration from amplitude (Carpenter 1988): D = 2.2·A + 21 ms.
pub fn saccade_duration_ms(amplitude_deg: f64) -> f64 {
    2.2 * amplitude_deg + 21.0
}

/// Peak velocity of the minimum-jerk profile this model moves saccades along: 1.875·A/D. With
/// D from `saccade_duration_ms` it rises with amplitude and saturates: the main sequence.
pub fn saccade_peak_velocity(amplitude_deg: f64) -> f64 {
    1.875 * amplitude_deg / (saccade_duration_ms(amplitude_deg) / 1000.0)
}

/// Minimum-jerk position profile: 0 → 1 over τ ∈ [0, 1].
fn min_jerk(t: f64) -> f64 {
    let t = t.clamp(0.0, 1.0);
    t * t * t * (10.0 - 15.0 * t + 6.0 * t * t)
}

/// mulberry32: tiny, deterministic, and identical in the page's JavaScript.
#[derive(Debug, Clone)]
pub struct Rng(u32);

impl Rng {
    pub fn new(seed: u32) -> Rng {
        Rng(seed)
    }

    pub fn next_f64(&mut self) -> f64 {
        self.0 = self.0.wrapping_add(0x6D2B_79F5);
        let mut t = self.0;
        t = (t ^ (t >> 15)).wrapping_mul(t | 1);
        t ^= t.wrapping_add((t ^ (t >> 7)).wrapping_mul(t | 61));
        f64::from(t ^ (t >> 14)) / 4_294_967_296.0
    }

    fn range(&mut self, lo: f64, hi: f64) -> f64 {
        lo + (hi - lo) * self.next_f64()
    }

    /// Approximately standard normal (sum of uniforms).
    fn normal(&mut self) -> f64 {
        (0..4).map(|_| self.next_f64()).sum::<f64>() * 3f64.sqrt() - 2.0 * 3f64.sqrt()
    }
}

#[derive(Debug, Clone, Copy, PartialEq)]
enum Phase {
    Fixation {
        until_ms: f64,
        next_micro_ms: f64,
    },
    Saccade {
        from: [f64; 2],
        to: [f64; 2],
        start_ms: f64,
        duration_ms: f64,
    },
    Pursuit {
        velocity: [f64; 2],
        until_ms: f64,
    },
    Blink {
        until_ms: f64,
        resume: [f64; 2],
    },
}

/// The eye's state; `sample_at` advances it.
#[derive(Debug, Clone)]
pub struct SyntheticEye {
    rng: Rng,
    /// Half the field the gaze roams, degrees (the screen's half-width and half-height).
    half_field: [f64; 2],
    pos: [f64; 2],
    phase: Phase,
    pupil: f64,
    next_blink_ms: f64,
    last_ms: f64,
}

impl SyntheticEye {
    pub fn new(seed: u32, viewing: &Viewing) -> SyntheticEye {
        let [fov_w, fov_h] = viewing.field_of_view_deg();
        let (half_w, half_h) = (0.5 * fov_w, 0.5 * fov_h);
        let mut rng = Rng::new(seed);
        let next_blink_ms = rng.range(2000.0, 6000.0);
        SyntheticEye {
            rng,
            half_field: [half_w * 0.9, half_h * 0.9],
            pos: [0.0, 0.0],
            phase: Phase::Fixation {
                until_ms: 300.0,
                next_micro_ms: 400.0,
            },
            pupil: 4.0,
            next_blink_ms,
            last_ms: 0.0,
        }
    }

    /// Gaze position in degrees (None during blinks) and pupil at `t_ms` (must not go back).
    pub fn step(&mut self, t_ms: f64) -> (Option<[f64; 2]>, Option<f64>) {
        let dt = (t_ms - self.last_ms).max(0.0);
        self.last_ms = t_ms;
        // Pupil: Ornstein–Uhlenbeck around 4 mm (time constant 2 s, stationary σ 0.8 mm).
        let theta = dt / 2000.0;
        self.pupil += theta * (4.0 - self.pupil) + 0.8 * (2.0 * theta).sqrt() * self.rng.normal();
        self.pupil = self.pupil.clamp(2.0, 8.0);
        loop {
            match self.phase {
                Phase::Blink { until_ms, resume } => {
                    if t_ms < until_ms {
                        return (None, None);
                    }
                    self.pos = resume;
                    self.next_blink_ms = t_ms + self.rng.range(2000.0, 6000.0);
                    self.phase = Phase::Fixation {
                        until_ms: t_ms + self.rng.range(150.0, 450.0),
                        next_micro_ms: t_ms + 400.0,
                    };
                }
                Phase::Saccade {
                    from,
                    to,
                    start_ms,
                    duration_ms,
                } => {
                    let s = min_jerk((t_ms - start_ms) / duration_ms);
                    self.pos = [
                        from[0] + (to[0] - from[0]) * s,
                        from[1] + (to[1] - from[1]) * s,
                    ];
                    if t_ms >= start_ms + duration_ms {
                        self.pos = to;
                        self.phase = Phase::Fixation {
                            until_ms: t_ms + self.rng.range(150.0, 450.0),
                            next_micro_ms: t_ms + self.rng.range(300.0, 900.0),
                        };
                        continue;
                    }
                    return (Some(self.pos), Some(self.pupil));
                }
                Phase::Pursuit { velocity, until_ms } => {
                    self.pos = self.clamp([
                        self.pos[0] + velocity[0] * dt / 1000.0,
                        self.pos[1] + velocity[1] * dt / 1000.0,
                    ]);
                    if t_ms >= until_ms {
                        self.phase = Phase::Fixation {
                            until_ms: t_ms + self.rng.range(150.0, 450.0),
                            next_micro_ms: t_ms + 400.0,
                        };
                    }
                    return (Some(self.pos), Some(self.pupil));
                }
                Phase::Fixation {
                    until_ms,
                    next_micro_ms,
                } => {
                    if t_ms >= self.next_blink_ms {
                        self.phase = Phase::Blink {
                            until_ms: t_ms + self.rng.range(100.0, 300.0),
                            resume: self.pos,
                        };
                        continue;
                    }
                    if t_ms >= until_ms {
                        self.start_next(t_ms);
                        continue;
                    }
                    // Drift: a slow random walk (~0.1°/√s).
                    let k = 0.1 * (dt / 1000.0).sqrt();
                    let (dx, dy) = (k * self.rng.normal(), k * self.rng.normal());
                    self.pos = self.clamp([self.pos[0] + dx, self.pos[1] + dy]);
                    if t_ms >= next_micro_ms {
                        let a = self.rng.range(0.1, 0.5);
                        let angle = self.rng.range(0.0, std::f64::consts::TAU);
                        let to = self
                            .clamp([self.pos[0] + a * angle.cos(), self.pos[1] + a * angle.sin()]);
                        self.phase = Phase::Saccade {
                            from: self.pos,
                            to,
                            start_ms: t_ms,
                            duration_ms: saccade_duration_ms(a),
                        };
                        continue;
                    }
                    return (Some(self.pos), Some(self.pupil));
                }
            }
        }
    }

    fn clamp(&self, p: [f64; 2]) -> [f64; 2] {
        [
            p[0].clamp(-self.half_field[0], self.half_field[0]),
            p[1].clamp(-self.half_field[1], self.half_field[1]),
        ]
    }

    fn start_next(&mut self, t_ms: f64) {
        if self.rng.next_f64() < 0.15 {
            let speed = self.rng.range(5.0, 20.0);
            let angle = self.rng.range(0.0, std::f64::consts::TAU);
            self.phase = Phase::Pursuit {
                velocity: [speed * angle.cos(), speed * angle.sin()],
                until_ms: t_ms + self.rng.range(500.0, 1500.0),
            };
        } else {
            let to = [
                self.rng.range(-1.0, 1.0) * self.half_field[0],
                self.rng.range(-1.0, 1.0) * self.half_field[1],
            ];
            let amplitude = ((to[0] - self.pos[0]).powi(2) + (to[1] - self.pos[1]).powi(2)).sqrt();
            self.phase = Phase::Saccade {
                from: self.pos,
                to,
                start_ms: t_ms,
                duration_ms: saccade_duration_ms(amplitude),
            };
        }
    }
}

/// Degrees from the screen centre → normalised frame coordinates.
pub fn degrees_to_frame(viewing: &Viewing, deg: [f64; 2]) -> [f64; 2] {
    let cm_per_unit_x = viewing.width_cm;
    let height_cm = viewing.width_cm * f64::from(viewing.height) / f64::from(viewing.width.max(1));
    let x_cm = viewing.distance_cm * deg[0].to_radians().tan();
    let y_cm = viewing.distance_cm * deg[1].to_radians().tan();
    [0.5 + x_cm / cm_per_unit_x, 0.5 + y_cm / height_cm]
}

/// `duration_ms` of samples at `rate_hz` from the synthetic eye.
pub fn generate(seed: u32, viewing: &Viewing, rate_hz: f64, duration_ms: f64) -> Vec<Sample> {
    let mut eye = SyntheticEye::new(seed, viewing);
    let step = 1000.0 / rate_hz.max(1.0);
    let n = (duration_ms / step).floor() as usize;
    (0..n)
        .map(|i| {
            let t = i as f64 * step;
            let (deg, pupil) = eye.step(t);
            Sample {
                t_ms: t,
                xy: deg.map(|d| degrees_to_frame(viewing, d)),
                pupil_mm: pupil,
            }
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    fn view() -> Viewing {
        Viewing {
            width: 1280,
            height: 720,
            width_cm: 53.0,
            distance_cm: 60.0,
        }
    }

    #[test]
    fn the_same_seed_gives_the_same_eye() {
        assert_eq!(
            generate(7, &view(), 500.0, 3000.0),
            generate(7, &view(), 500.0, 3000.0)
        );
        assert_ne!(
            generate(7, &view(), 500.0, 3000.0),
            generate(8, &view(), 500.0, 3000.0)
        );
    }

    #[test]
    fn saccades_follow_the_main_sequence() {
        // Measured on generated saccades: peak velocity matches 1.875·A/D within 3%.
        let mut eye = SyntheticEye::new(3, &view());
        for a in [2.0, 5.0, 10.0, 20.0] {
            eye.pos = [0.0, 0.0];
            eye.phase = Phase::Saccade {
                from: [0.0, 0.0],
                to: [a, 0.0],
                start_ms: 0.0,
                duration_ms: saccade_duration_ms(a),
            };
            eye.last_ms = 0.0;
            eye.next_blink_ms = 1e9;
            let mut prev = 0.0;
            let mut peak: f64 = 0.0;
            for i in 1..=200 {
                let t = f64::from(i) * 0.25;
                let (p, _) = eye.step(t);
                let x = p.unwrap()[0];
                peak = peak.max((x - prev) / 0.25e-3);
                prev = x;
                if t > saccade_duration_ms(a) {
                    break;
                }
            }
            let expected = saccade_peak_velocity(a);
            assert!(
                (peak - expected).abs() < 0.03 * expected,
                "A = {a}°: peak {peak:.0}°/s, main sequence {expected:.0}°/s"
            );
        }
        assert!(
            saccade_peak_velocity(10.0) > 1.8 * saccade_peak_velocity(2.0),
            "rises with amplitude"
        );
        assert!(
            saccade_peak_velocity(20.0) < 1.5 * saccade_peak_velocity(10.0),
            "and saturates"
        );
    }

    #[test]
    fn a_minute_of_eye_has_every_behaviour_and_stays_physiological() {
        let v = view();
        let samples = generate(11, &v, 250.0, 60_000.0);
        let blinks = samples
            .windows(2)
            .filter(|w| w[0].xy.is_some() && w[1].xy.is_none())
            .count();
        assert!((8..=30).contains(&blinks), "{blinks} blinks in a minute");
        for s in &samples {
            if let Some(p) = s.pupil_mm {
                assert!((2.0..=8.0).contains(&p), "pupil {p}");
            }
            if let Some([x, y]) = s.xy {
                assert!(
                    (0.0..=1.0).contains(&x) && (0.0..=1.0).contains(&y),
                    "gaze ({x}, {y}) left the frame"
                );
            }
        }
        // Saccades: some sample-to-sample jumps over 100°/s; fixations: most under 30°/s.
        let deg_per_frame = v.field_of_view_deg()[0];
        let speeds: Vec<f64> = samples
            .windows(2)
            .filter_map(|w| {
                Some(
                    ((w[1].xy?[0] - w[0].xy?[0]).hypot(w[1].xy?[1] - w[0].xy?[1])) * deg_per_frame
                        / 0.004,
                )
            })
            .collect();
        assert!(speeds.iter().filter(|s| **s > 100.0).count() > 50);
        assert!(speeds.iter().filter(|s| **s < 30.0).count() > speeds.len() * 3 / 4);
        let max_step = samples
            .windows(2)
            .filter_map(|w| Some((w[1].pupil_mm? - w[0].pupil_mm?).abs()))
            .fold(0.0, f64::max);
        assert!(
            max_step < 0.3,
            "the pupil changes smoothly: largest 4 ms step {max_step} mm"
        );
    }
}
