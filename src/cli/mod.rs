//! The subcommands beyond `serve` and `render`, one file each, with the value parsers they share.

pub mod access;
pub mod bench;
pub mod codecs;
pub mod gaze;
pub mod load;
pub mod parse;
pub mod progress;
pub mod radiosity;
pub mod scenes;
pub mod serve;
pub mod target;
