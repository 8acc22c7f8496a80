//! Clients of the protocol: a plain connection (tests, tools); `link`, a session that moves to
//! another instance when its server drains; `replay`, which streams a gaze recording to a
//! server at its recorded timing; and `load`, concurrent synthetic sessions.

mod connection;
pub mod link;
pub mod load;
pub mod replay;
pub mod saved_frames;

pub use connection::{Client, ClientError, Event};
