//! Gaze: samples, recording formats, the synthetic eye, and prediction. No GPU, no sockets.
//!
//! Samples are normalised to the frame (x, y in [0, 1], top-left origin) with time in
//! milliseconds from the start of the recording. Track loss is `None` for x/y; a blink or a
//! missing pupil is `None` for the pupil.

pub mod classes;
pub mod evaluate;
pub mod formats;
pub mod prediction;
pub mod synthetic;

/// One eye-tracker sample, normalised.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Sample {
    pub t_ms: f64,
    /// Gaze position; `None` during track loss.
    pub xy: Option<[f64; 2]>,
    /// Pupil diameter in mm; `None` during blinks or when the format has none.
    pub pupil_mm: Option<f64>,
}

/// How a client treats samples a real tracker produces that the protocol cannot carry:
/// a sample off the frame is clamped onto it when within `OFF_FRAME_MARGIN` (trackers
/// overshoot the screen edge) and dropped beyond; track loss and blinks send nothing, so the
/// server keeps rendering for the last valid gaze (which is what the eye last fixated).
pub const OFF_FRAME_MARGIN: f64 = 0.1;

/// Samples further apart than this are separated by a gap (track loss the file does not mark,
/// or a client that stopped sending): prediction starts afresh after one. Slow trackers (30 Hz
/// webcams, 33 ms) stay under it.
pub const MAX_SAMPLE_GAP_MS: f64 = 50.0;

/// The gaze to send for a sample, if any (see `OFF_FRAME_MARGIN`).
pub fn sendable(sample: &Sample) -> Option<[f64; 2]> {
    let [x, y] = sample.xy?;
    if !(x.is_finite() && y.is_finite()) {
        return None;
    }
    let m = OFF_FRAME_MARGIN;
    if x < -m || y < -m || x > 1.0 + m || y > 1.0 + m {
        return None;
    }
    Some([x.clamp(0.0, 1.0), y.clamp(0.0, 1.0)])
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn slightly_off_frame_samples_are_clamped_and_far_ones_dropped() {
        let s = |x, y| Sample {
            t_ms: 0.0,
            xy: Some([x, y]),
            pupil_mm: None,
        };
        assert_eq!(sendable(&s(1.05, -0.02)), Some([1.0, 0.0]));
        assert_eq!(sendable(&s(1.5, 0.5)), None);
        assert_eq!(sendable(&s(f64::NAN, 0.5)), None);
        assert_eq!(
            sendable(&Sample {
                t_ms: 0.0,
                xy: None,
                pupil_mm: Some(4.0)
            }),
            None
        );
    }
}
