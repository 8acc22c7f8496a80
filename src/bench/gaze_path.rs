//! The gaze path a codec sweep's frames follow: one or several stretches of a recording.

use super::codecs::{CodecBenchError, FPS};
use crate::gaze::formats::Recording;

/// `frames` gaze points one 1/60 s apart from `from_s` seconds into the recording: at each
/// time, the first sample at or after it that replay would send (so track loss holds the
/// next good sample, as the server would show). Past the recording's end the last good sample
/// holds.
pub fn gaze_path(
    rec: &Recording,
    from_s: f64,
    frames: usize,
) -> Result<Vec<[f64; 2]>, CodecBenchError> {
    let t0 = rec.samples.first().map(|s| s.t_ms).unwrap_or(0.0) + from_s * 1e3;
    let mut out = Vec::with_capacity(frames);
    let mut last = None;
    for k in 0..frames {
        let t = t0 + k as f64 * 1e3 / FPS;
        let i = rec.samples.partition_point(|s| s.t_ms < t);
        let g = rec.samples[i..]
            .iter()
            .find_map(crate::gaze::sendable)
            .or(last);
        let Some(g) = g else {
            return Err(CodecBenchError::NoGaze { from_s });
        };
        last = Some(g);
        out.push(g);
    }
    Ok(out)
}

/// `frames` gaze points from each of `froms` (seconds into the recording), laid end to end:
/// the stretches [`super::CodecOptions::stretch_frames`] pools.
pub fn gaze_stretches(
    rec: &Recording,
    froms: &[f64],
    frames: usize,
) -> Result<Vec<[f64; 2]>, CodecBenchError> {
    let mut out = Vec::with_capacity(froms.len() * frames);
    for &from_s in froms {
        out.extend(gaze_path(rec, from_s, frames)?);
    }
    Ok(out)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::gaze::formats::Format;
    use crate::gaze::Sample;

    fn recording(samples: &[(f64, Option<[f64; 2]>)]) -> Recording {
        Recording {
            format: Format::Generic,
            samples: samples
                .iter()
                .map(|&(t_ms, xy)| Sample {
                    t_ms,
                    xy,
                    pupil_mm: None,
                })
                .collect(),
            pupil_rule: None,
            eye: None,
            screen: None,
            saccades: None,
        }
    }

    #[test]
    fn the_path_takes_the_next_sendable_sample_and_holds_the_last_past_the_end() {
        // Samples at 1000, 1010, 1020 and 1040 ms; the second is lost, the third far off the
        // frame (replay sends neither).
        let rec = recording(&[
            (1000.0, Some([0.1, 0.1])),
            (1010.0, None),
            (1020.0, Some([5.0, 5.0])),
            (1040.0, Some([0.6, 0.4])),
        ]);
        let path = gaze_path(&rec, 0.0, 4).unwrap();
        // Frames at 0, 16.7, 33.3 and 50 ms after the first sample.
        assert_eq!(path, vec![[0.1, 0.1], [0.6, 0.4], [0.6, 0.4], [0.6, 0.4]]);
        assert!(matches!(
            gaze_path(&rec, 1.0, 2),
            Err(CodecBenchError::NoGaze { .. })
        ));
        assert!(gaze_path(&recording(&[]), 0.0, 1).is_err());
    }

    #[test]
    fn stretches_lie_end_to_end_each_from_its_own_start() {
        let rec = recording(&[
            (0.0, Some([0.1, 0.1])),
            (20.0, Some([0.2, 0.2])),
            (1000.0, Some([0.7, 0.7])),
            (1020.0, Some([0.8, 0.8])),
        ]);
        let path = gaze_stretches(&rec, &[0.0, 1.0], 2).unwrap();
        assert_eq!(path, vec![[0.1, 0.1], [0.2, 0.2], [0.7, 0.7], [0.8, 0.8]]);
        assert!(gaze_stretches(&rec, &[0.0, 5.0], 2).is_err());
    }
}
