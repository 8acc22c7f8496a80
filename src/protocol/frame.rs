use serde::{Deserialize, Serialize};

use super::Codec;

/// Where the marker was drawn and the frame was centred: the gaze actually used, normalised.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct GazeUsed {
    pub x: f64,
    pub y: f64,
}

/// What a frame answers.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Trigger {
    /// A gaze sample (`seq`, `t_ms`): the frames gaze-to-display latency is measured on.
    #[default]
    Gaze,
    /// A settings change, showing the last sample again.
    Settings,
    /// The session's first frame, before any sample.
    Start,
}

/// Milliseconds spent in each stage of one frame, measured on the server's monotonic clock.
#[derive(Debug, Clone, Copy, Default, PartialEq, Serialize, Deserialize)]
pub struct StageTimes {
    /// From the arrival of what the frame answers (sample, settings change or hello) to the
    /// render thread picking the frame up.
    pub queue: f64,
    /// Recording and executing the GPU passes (until the GPU reports them done).
    pub render: f64,
    /// Copying the image to host memory.
    pub readback: f64,
    /// JPEG/PNG encoding.
    pub encode: f64,
}

/// The JSON header in front of every frame's image bytes.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct FrameHeader {
    /// Frame number within the session, from 1.
    pub frame: u64,
    /// The gaze sample this frame answers; `None` for the first frame, drawn before any sample.
    pub seq: Option<u64>,
    /// That sample's own `t_ms` (client clock), echoed for gaze-to-display latency.
    pub t_ms: Option<f64>,
    /// What this frame answers; only `gaze` frames measure gaze-to-display latency.
    #[serde(default)]
    pub trigger: Trigger,
    pub gaze: GazeUsed,
    /// The sample's own position when prediction moved the gaze used.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub raw_gaze: Option<GazeUsed>,
    pub width: u32,
    pub height: u32,
    pub codec: Codec,
    /// H.264 only: whether this frame is a keyframe (IDR) a decoder can start from.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub keyframe: Option<bool>,
    /// The encoded image's size in bytes (what follows the header; for an inset frame both
    /// images together).
    #[serde(default)]
    pub bytes: usize,
    /// Inset frames only: the bytes are a downscaled whole frame, then the inset.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub inset: Option<InsetHeader>,
    /// Fraction of pixels shaded this frame (1.0 without foveation).
    pub sampled: f64,
    /// Set when the session asked for foveation but the server shaded this frame whole, with
    /// why: on this adapter a foveated frame of this scene costs no less than a whole one, or
    /// (now and then) to measure what foveation saves.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub unfoveated: Option<String>,
    /// Gaze samples the session had received when this frame was made (lost = sent − this).
    #[serde(default)]
    pub samples: u64,
    pub stages_ms: StageTimes,
    /// GPU milliseconds per render pass, where the adapter has timestamp queries.
    #[serde(default, skip_serializing_if = "std::collections::BTreeMap::is_empty")]
    pub passes_ms: std::collections::BTreeMap<String, f64>,
    /// In scenes with radiosity: the snapshot of the solve this frame was lit by. Until it
    /// converges the frame shows the preview (unshot energy spread as an ambient term).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub radiosity: Option<SolveProgress>,
}

/// How an inset frame's two images fit together: the first `bytes − inset_bytes` bytes are the
/// whole frame at `base_width`×`base_height`, to be scaled up to the frame's size; the rest is
/// the inset, `width`×`height` pixels at (`x`, `y`) of the frame, drawn over it with its
/// sides feathered over `feather` of its size (sides on the frame's edge are not feathered).
/// An H.264 inset frame is one picture holding both (`packed` says where; `inset_bytes` 0).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct InsetHeader {
    pub x: u32,
    pub y: u32,
    pub width: u32,
    pub height: u32,
    pub base_width: u32,
    pub base_height: u32,
    pub inset_bytes: usize,
    pub feather: f64,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub packed: Option<crate::encode::inset_packed::PackedLayout>,
}

/// Where a scene's radiosity solve stood when a frame used it (the wire's own type; the
/// server fills it from the solver's progress).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct SolveProgress {
    /// Shooting steps so far.
    pub shots: u32,
    /// Receiving elements after adaptive subdivision.
    pub elements: usize,
    /// Unshot power over emitted power (the ambient term previews it).
    pub unshot: f64,
    pub converged: bool,
}

/// Packs `[u32 LE header length][JSON header][image bytes]`.
pub fn encode_frame(header: &FrameHeader, image: &[u8]) -> Vec<u8> {
    let json = serde_json::to_vec(header).unwrap_or_default();
    let mut out = Vec::with_capacity(4 + json.len() + image.len());
    out.extend_from_slice(&(json.len() as u32).to_le_bytes());
    out.extend_from_slice(&json);
    out.extend_from_slice(image);
    out
}

#[derive(Debug, thiserror::Error)]
pub enum FrameDecodeError {
    #[error("frame message is {0} bytes, shorter than its 4-byte length prefix")]
    Short(usize),
    #[error("header length {len} runs past the end of a {total}-byte message")]
    HeaderPastEnd { len: usize, total: usize },
    #[error("frame header is not valid JSON: {0}")]
    Json(#[from] serde_json::Error),
}

/// Splits a binary frame message into its header and image bytes.
pub fn decode_frame(bytes: &[u8]) -> Result<(FrameHeader, &[u8]), FrameDecodeError> {
    let prefix: [u8; 4] = bytes
        .get(..4)
        .and_then(|b| b.try_into().ok())
        .ok_or(FrameDecodeError::Short(bytes.len()))?;
    let len = u32::from_le_bytes(prefix) as usize;
    let end = 4usize
        .checked_add(len)
        .filter(|&e| e <= bytes.len())
        .ok_or(FrameDecodeError::HeaderPastEnd {
            len,
            total: bytes.len(),
        })?;
    let header = serde_json::from_slice(&bytes[4..end])?;
    Ok((header, &bytes[end..]))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn frame_round_trips_header_and_image() {
        let header = FrameHeader {
            frame: 42,
            seq: Some(17),
            t_ms: Some(12399.1),
            trigger: super::Trigger::Gaze,
            gaze: GazeUsed { x: 0.25, y: 0.75 },
            raw_gaze: Some(GazeUsed { x: 0.2, y: 0.75 }),
            width: 64,
            height: 48,
            codec: Codec::Png,
            keyframe: None,
            bytes: 3,
            inset: Some(InsetHeader {
                x: 8,
                y: 6,
                width: 16,
                height: 12,
                base_width: 16,
                base_height: 12,
                inset_bytes: 1,
                feather: 0.125,
                packed: None,
            }),
            sampled: 1.0,
            unfoveated: Some("shaded whole: foveation does not pay here".into()),
            samples: 17,
            stages_ms: StageTimes {
                queue: 0.1,
                render: 2.0,
                readback: 0.5,
                encode: 1.25,
            },
            passes_ms: [("shade".to_string(), 0.75)].into_iter().collect(),
            radiosity: Some(SolveProgress {
                shots: 120,
                elements: 5000,
                unshot: 0.25,
                converged: false,
            }),
        };
        let image = [0xFFu8, 0xD8, 0x01, 0x02];
        let bytes = encode_frame(&header, &image);
        let (back, rest) = decode_frame(&bytes).unwrap();
        assert_eq!(back, header);
        assert_eq!(rest, image);
    }

    #[test]
    fn truncated_frames_are_errors_not_panics() {
        assert!(matches!(
            decode_frame(&[1, 0]),
            Err(FrameDecodeError::Short(2))
        ));
        assert!(matches!(
            decode_frame(&[200, 0, 0, 0, b'{']),
            Err(FrameDecodeError::HeaderPastEnd { len: 200, total: 5 })
        ));
        assert!(matches!(
            decode_frame(&[1, 0, 0, 0, b'x']),
            Err(FrameDecodeError::Json(_))
        ));
    }
}
