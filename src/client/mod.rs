//! Clients of the protocol: a plain connection (tests, tools), and `replay`, which streams a
//! gaze recording to a server at its recorded timing and records every frame that comes back.

mod connection;
pub mod load;
pub mod replay;

pub use connection::{Client, ClientError, Event};
