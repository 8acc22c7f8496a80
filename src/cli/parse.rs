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

/// Replay and load generate traffic: only loopback targets, or hosts named with --allow-host.
pub fn url_is_allowed(url: &str, allowed: &[String]) -> Result<String> {
    let rest = url
        .strip_prefix("ws://")
        .with_context(|| format!("{url:?}: expected ws://HOST:PORT/ws"))?;
    let host = if rest.starts_with('[') {
        rest.split(']')
            .next()
            .map(|h| format!("{h}]"))
            .unwrap_or_default()
    } else {
        rest.split(['/', ':']).next().unwrap_or("").to_string()
    };
    let loopback = host == "localhost"
        || host == "[::1]"
        || host
            .parse::<std::net::Ipv4Addr>()
            .is_ok_and(|ip| ip.is_loopback());
    if !loopback && !allowed.iter().any(|a| *a == host) {
        bail!("{url:?}: only loopback servers (127.0.0.0/8, localhost, [::1]) or hosts given with --allow-host may be targeted");
    }
    Ok(url.to_string())
}

/// The built-in scenes as clap's possible values, so `--help` lists them and a typo is refused
/// with the list.
pub fn scene_names() -> clap::builder::PossibleValuesParser {
    clap::builder::PossibleValuesParser::new(fovea::scene::builtin_names())
}

/// A duration in seconds from a flag: finite and within 0.1 s … 1 h.
pub fn parse_seconds(s: &str) -> Result<f64, String> {
    let v: f64 = s.trim().parse().map_err(|e| format!("{s:?}: {e}"))?;
    if !(0.1..=3600.0).contains(&v) {
        return Err(format!("{s:?}: seconds must lie in [0.1, 3600]"));
    }
    Ok(v)
}
