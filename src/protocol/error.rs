use serde::{Deserialize, Serialize};

/// Machine-readable reason sent in an `error` message. The session survives every one of these
/// except where the server says otherwise (it closes only on transport-level failures).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum ErrorCode {
    /// The text was not JSON.
    BadJson,
    /// JSON has no `NaN`/`Infinity`; a client that emits them (Python's default) gets told so.
    NotFinite,
    /// No `type` field, or it is not a string.
    MissingType,
    /// `type` names no message this server knows.
    UnknownType,
    /// A field is missing, unknown, or of the wrong JSON type.
    BadField,
    /// A number is outside its stated range (see `welcome.limits`).
    OutOfRange,
    /// The message is longer than `limits.max_message_bytes`.
    TooLarge,
    /// A message that needs a session (`gaze`, `ack`) came before `hello`.
    NoHello,
    /// A second `hello` on a session that already started.
    AlreadyStarted,
    /// `hello.v` is not a version this server speaks.
    UnsupportedVersion,
    /// `hello.scene` names no scene this server has.
    UnknownScene,
    /// `hello.preset` names no preset this server has.
    UnknownPreset,
    /// Clients send text only.
    UnexpectedBinary,
    /// An `ack` for a frame that was never sent.
    BadAck,
    /// The server failed to render or encode a frame; the session goes on.
    RenderFailed,
    /// The session's recording reached its size limit and stopped; the session goes on.
    RecordingStopped,
    /// The frame asked for (`hello`, or a `settings` change) would take longer than
    /// `limits.frame_budget_ms` at the current load; the message says the largest size that fits.
    OverBudget,
}

/// A rejected client message: the code for programs, the sentence for people.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[error("{code:?}: {message}")]
pub struct ProtocolError {
    pub code: ErrorCode,
    pub message: String,
}

impl ProtocolError {
    pub fn new(code: ErrorCode, message: impl Into<String>) -> Self {
        Self {
            code,
            message: message.into(),
        }
    }
}
