//! Parsers for command-line values, and the traffic guard of the tools that generate load.

use anyhow::{bail, Context, Result};
use glam::Vec3;

pub fn parse_gaze(s: &str) -> Result<[f32; 2], String> {
    let v: Vec<f32> = s
        .split(',')
        .map(|p| p.trim().parse::<f32>())
        .collect::<Result<_, _>>()
        .map_err(|e| format!("{s:?}: {e}"))?;
    match v.as_slice() {
        [x, y] if (0.0..=1.0).contains(x) && (0.0..=1.0).contains(y) => Ok([*x, *y]),
        [_, _] => Err(format!("{s:?}: both coordinates must lie in [0, 1]")),
        _ => Err(format!("{s:?}: expected X,Y")),
    }
}

pub fn parse_vec3(s: &str) -> Result<Vec3, String> {
    let v: Vec<f32> = s
        .split(',')
        .map(|p| p.trim().parse::<f32>())
        .collect::<Result<_, _>>()
        .map_err(|e| format!("{s:?}: {e}"))?;
    match v.as_slice() {
        [x, y, z] if Vec3::new(*x, *y, *z).try_normalize().is_some() => Ok(Vec3::new(*x, *y, *z)),
        [_, _, _] => Err(format!("{s:?}: the direction must be finite and non-zero")),
        _ => Err(format!("{s:?}: expected X,Y,Z")),
    }
}

pub fn parse_size(s: &str) -> Result<(u32, u32)> {
    let (w, h) = s
        .trim()
        .split_once('x')
        .with_context(|| format!("{s:?}: expected WxH"))?;
    let (w, h): (u32, u32) = (
        w.parse().with_context(|| format!("{s:?}: width"))?,
        h.parse().with_context(|| format!("{s:?}: height"))?,
    );
    if w == 0 || h == 0 || w > 8192 || h > 8192 {
        bail!("{s:?}: sizes run from 1x1 to 8192x8192");
    }
    Ok((w, h))
}

/// The built-in scenes as clap's possible values, so `--help` lists them and a typo is refused
/// with the list.
pub fn scene_names() -> clap::builder::PossibleValuesParser {
    clap::builder::PossibleValuesParser::new(fovea::scene::builtin_names())
}

/// A duration in seconds from a flag: finite and within 0.1 s … 1 h.
pub fn parse_seconds(s: &str) -> Result<f64, String> {
    number_in(s, 0.1, 3600.0)
}

/// `--frame-budget-s`: down to a millisecond, since a GPU's frames take a few (an H200 renders
/// `gallery` at 1280×720 in ~2 ms), where the other durations' floor of 0.1 s would allow only
/// budgets no such server wants.
pub fn parse_frame_budget(s: &str) -> Result<f64, String> {
    number_in(s, 0.001, 3600.0)
}

/// `--display-width-cm`: the range a `hello` is held to.
pub fn display_width_cm(s: &str) -> Result<f64, String> {
    number_in(s, 1.0, 1000.0)
}

/// `--distance-cm`: the range a `hello` is held to.
pub fn distance_cm(s: &str) -> Result<f64, String> {
    number_in(s, 1.0, 10_000.0)
}

/// `--keyframe-s`: the range a `hello` is held to.
pub fn keyframe_s(s: &str) -> Result<f64, String> {
    let (lo, hi) = fovea::encode::h264::KEYFRAME_S_RANGE;
    number_in(s, lo, hi)
}

/// A finite number in [lo, hi] from a flag.
pub fn number_in(s: &str, lo: f64, hi: f64) -> Result<f64, String> {
    let v: f64 = s.trim().parse().map_err(|e| format!("{s:?}: {e}"))?;
    if !(lo..=hi).contains(&v) {
        return Err(format!("{s:?}: must lie in [{lo}, {hi}]"));
    }
    Ok(v)
}

/// How the sessions of `fovea replay` and `fovea load` ask for their frames to be encoded.
#[derive(clap::Args, Clone)]
pub struct EncodingArgs {
    /// Frame codec the sessions ask for: h264, jpeg or png. The default is what the page's
    /// `auto` picks wherever WebCodecs decodes H.264, so a run measures what viewers get.
    #[arg(long, value_parser = codec, default_value = "h264")]
    pub codec: fovea::protocol::Codec,
    /// H.264 bitrate, kbit/s (100 to 50000; default: the server's, 4000).
    #[arg(long)]
    pub bitrate_kbps: Option<u32>,
    /// H.264: a keyframe at least this often, seconds (0.1 to 60; default: the server's, 10).
    #[arg(long, value_parser = keyframe_s)]
    pub keyframe_s: Option<f64>,
    /// Low-pass the periphery to what the eye resolves before encoding (any codec).
    #[arg(long)]
    pub foveated_encoding: bool,
    /// Inset frames: a downscaled whole frame plus a full-resolution square this many degrees
    /// wide (4–90) around the gaze (with h264 both packed into one picture of the stream).
    #[arg(long)]
    pub inset_deg: Option<f64>,
}

impl EncodingArgs {
    /// A default hello carrying these choices.
    pub fn hello(&self) -> fovea::protocol::Hello {
        fovea::protocol::Hello {
            codec: self.codec,
            bitrate_kbps: self.bitrate_kbps,
            keyframe_s: self.keyframe_s,
            foveated_encoding: self.foveated_encoding,
            inset_deg: self.inset_deg,
            ..Default::default()
        }
    }
}

/// A frame codec by its protocol name.
pub fn codec(s: &str) -> Result<fovea::protocol::Codec, String> {
    serde_json::from_value(serde_json::Value::String(s.to_string()))
        .map_err(|_| format!("unknown codec {s:?} (jpeg, png, h264)"))
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A GPU server's budget (a 60 Hz frame) is accepted; nothing under a millisecond, not a
    /// number or past an hour is; the other durations keep their floor of 0.1 s.
    #[test]
    fn a_frame_budget_goes_down_to_a_millisecond() {
        for ok in ["0.001", "0.016", "10", "3600"] {
            assert!(parse_frame_budget(ok).is_ok(), "{ok}");
        }
        for bad in ["0", "0.0005", "-1", "nan", "inf", "3601", "", "ten"] {
            assert!(parse_frame_budget(bad).is_err(), "{bad}");
        }
        assert!(parse_seconds("0.016").is_err());
        assert!(parse_seconds("0.1").is_ok());
    }

    /// `--keyframe-s` refuses what the server's hello would, before connecting.
    #[test]
    fn a_keyframe_period_is_held_to_the_hellos_range() {
        for ok in ["0.1", "2", "10", "60"] {
            assert!(keyframe_s(ok).is_ok(), "{ok}");
        }
        for bad in ["0", "0.09", "60.5", "nan", "inf", "-2", ""] {
            assert!(keyframe_s(bad).is_err(), "{bad}");
        }
    }
}
