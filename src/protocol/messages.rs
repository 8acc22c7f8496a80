use serde::{Deserialize, Serialize};

use super::Limits;
pub use crate::viewing::Display;

pub const PROTOCOL_VERSION: u32 = 1;

/// Opens a session: what to render, how large, and how the client wants frames delivered.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Hello {
    #[serde(default = "default_version")]
    pub v: u32,
    #[serde(default = "default_scene")]
    pub scene: String,
    #[serde(default = "default_width")]
    pub width: u32,
    #[serde(default = "default_height")]
    pub height: u32,
    #[serde(default = "default_preset")]
    pub preset: String,
    #[serde(default)]
    pub display: Display,
    #[serde(default)]
    pub codec: Codec,
    /// JPEG quality 1–100; ignored for PNG and H.264.
    #[serde(default = "default_quality")]
    pub quality: u8,
    /// H.264 bitrate, kbit/s (default 4000); ignored by the other codecs.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub bitrate_kbps: Option<u32>,
    /// H.264: a keyframe at least every this many seconds (default 10, 0.1–60).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub keyframe_s: Option<f64>,
    /// Low-pass the periphery to what the eye resolves there before encoding (any codec).
    #[serde(default, skip_serializing_if = "std::ops::Not::not")]
    pub foveated_encoding: bool,
    /// Inset encoding (JPEG and PNG): each frame is a downscaled whole frame plus a
    /// full-resolution square this many degrees wide around the gaze (4–90), which the client
    /// composes (docs/protocol.md, "Inset frames").
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub inset_deg: Option<f64>,
    /// Frames the server may have sent that the client has not acknowledged yet.
    #[serde(default = "default_in_flight")]
    pub max_in_flight: u32,
}

impl Default for Hello {
    fn default() -> Self {
        Self {
            v: PROTOCOL_VERSION,
            scene: default_scene(),
            width: default_width(),
            height: default_height(),
            preset: default_preset(),
            display: Display::default(),
            codec: Codec::default(),
            quality: default_quality(),
            bitrate_kbps: None,
            keyframe_s: None,
            foveated_encoding: false,
            inset_deg: None,
            max_in_flight: default_in_flight(),
        }
    }
}

fn default_version() -> u32 {
    PROTOCOL_VERSION
}
fn default_scene() -> String {
    crate::scene::DEFAULT_SCENE.to_string()
}
fn default_width() -> u32 {
    640
}
fn default_height() -> u32 {
    480
}
fn default_preset() -> String {
    "balanced".to_string()
}
fn default_quality() -> u8 {
    85
}
fn default_in_flight() -> u32 {
    2
}

#[derive(Debug, Clone, Copy, Default, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum Codec {
    #[default]
    Jpeg,
    /// Lossless, so frames can be compared exactly.
    Png,
    /// H.264 Annex B, baseline profile, one stream per session (see docs/protocol.md).
    H264,
}

impl Codec {
    /// The codec's name on the wire (what `"codec"` carries).
    pub fn name(self) -> &'static str {
        match self {
            Codec::Jpeg => "jpeg",
            Codec::Png => "png",
            Codec::H264 => "h264",
        }
    }
}

/// One eye-tracker sample. `t_ms` is on the client's own clock; the server echoes it so the
/// Moves the session's camera (from the scene's own). Every field is optional; they apply in
/// the order `reset`, `pose`, `orbit_deg`, `pan`, `dolly`.
#[derive(Debug, Clone, Copy, PartialEq, Default, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct CameraMove {
    /// Back to the scene's camera.
    #[serde(default, skip_serializing_if = "std::ops::Not::not")]
    pub reset: bool,
    /// An absolute pose (field of view and clip planes stay the scene's).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub pose: Option<CameraPose>,
    /// Degrees to turn around the target: [yaw about up, pitch], each in [-360, 360].
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub orbit_deg: Option<[f64; 2]>,
    /// Slide across the view by [right, up] view heights, each in [-10, 10].
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub pan: Option<[f64; 2]>,
    /// Multiply the distance to the target, in [0.05, 20].
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub dolly: Option<f64>,
}

#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct CameraPose {
    pub eye: [f64; 3],
    pub target: [f64; 3],
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub up: Option<[f64; 3]>,
}

/// client can compute gaze-to-display latency without synchronised clocks.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Gaze {
    pub seq: u64,
    pub t_ms: f64,
    pub x: f64,
    pub y: f64,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub pupil_mm: Option<f64>,
    /// The time the tracker took the sample, ms on the recording's own clock, when that is
    /// not `t_ms` (a replay sends the recorded time, so a session recording keeps the
    /// original timing however the samples travelled).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub sample_t_ms: Option<f64>,
}

/// The client is done with a frame (shown, or dropped unseen): it returns one credit.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Ack {
    pub frame: u64,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub t_ms: Option<f64>,
    /// True when the client skipped the frame because a newer one was ready first.
    #[serde(default)]
    pub dropped: bool,
}

#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct SceneInfo {
    pub name: String,
    pub triangles: u32,
}

#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Welcome {
    pub v: u32,
    pub session: u64,
    pub scene: SceneInfo,
    pub scenes: Vec<String>,
    pub presets: Vec<String>,
    pub width: u32,
    pub height: u32,
    pub codec: Codec,
    pub max_in_flight: u32,
    pub limits: Limits,
    /// The GPU adapter frames come from, e.g. "llvmpipe (LLVM 15.0.6, 256 bits) (Vulkan)".
    pub adapter: String,
    /// The server's version (`fovea --version`), for the provenance of measurements.
    #[serde(default)]
    pub version: String,
    /// Where this session's own gaze recording can be downloaded (relative URL with its key),
    /// when the server records.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub recording: Option<String>,
}

#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct ErrorMessage {
    pub code: super::ErrorCode,
    pub message: String,
}

/// Text messages from server to client.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(tag = "type", rename_all = "snake_case")]
pub enum ServerMessage {
    Welcome(Welcome),
    Error(ErrorMessage),
    Goodbye(Goodbye),
}

/// The server is going away (a rolling update, a scale-down): the session keeps its frames
/// until the server closes it with 1001, and the client should open a new session to the same
/// URL after `retry_ms` (the balancer sends it to another instance).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Goodbye {
    /// Why: `draining` is the only reason so far.
    pub reason: String,
    /// When to reconnect, ms from now (spread per session so a fleet is not hit all at once).
    pub retry_ms: u64,
    /// When the server closes this session if the client has not left, ms from now.
    pub closes_in_ms: u64,
}

impl ServerMessage {
    pub fn to_json(&self) -> String {
        // Serialising these plain structs cannot fail: no maps with non-string keys, no NaN
        // (non-finite floats become null in serde_json).
        serde_json::to_string(self).unwrap_or_else(|e| {
            format!(r#"{{"type":"error","code":"render_failed","message":"serialise: {e}"}}"#)
        })
    }
}

impl From<super::ProtocolError> for ServerMessage {
    fn from(e: super::ProtocolError) -> Self {
        ServerMessage::Error(ErrorMessage {
            code: e.code,
            message: e.message,
        })
    }
}

#[cfg(test)]
mod tests {
    use super::Codec;

    #[test]
    fn a_codecs_name_is_its_wire_spelling() {
        for c in [Codec::Jpeg, Codec::Png, Codec::H264] {
            assert_eq!(serde_json::to_value(c).ok(), Some(c.name().into()));
        }
    }
}
