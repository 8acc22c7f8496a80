//! Wire protocol v1: JSON text messages both ways, frames as binary messages
//! `[u32 LE header length][JSON header][image bytes]`.
//!
//! Everything here is plain data and validation so it can be tested without a socket or a GPU.

mod error;
mod frame;
mod limits;
mod messages;
mod parse;

/// The `settings` message is the knob list of [`crate::settings::knobs`].
pub use crate::settings::SettingsPatch;
pub use error::{ErrorCode, ProtocolError};
pub use frame::{
    decode_frame, encode_frame, FrameHeader, GazeUsed, InsetHeader, SolveProgress, StageTimes,
    Trigger,
};
pub use limits::{Limits, SceneFileLimits};
pub use messages::{
    Ack, CameraMove, CameraPose, Codec, Display, ErrorMessage, Gaze, Goodbye, Hello, SceneInfo,
    ServerMessage, Welcome, PROTOCOL_VERSION,
};
pub use parse::{parse_client_message, ClientMessage};
