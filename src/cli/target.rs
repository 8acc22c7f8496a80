//! Where `fovea replay` and `fovea load` may send traffic: loopback servers, or hosts named
//! with `--allow-host`. The URL is parsed as a URI (not split by hand), so userinfo, IPv6
//! literals and the short and numeric IPv4 forms the resolver accepts (`127.1`, `2130706433`,
//! `0x7f.1`) cannot make a remote host look local or a local one look remote.

use anyhow::{bail, Context, Result};
use std::net::{Ipv4Addr, Ipv6Addr};

pub fn url_is_allowed(url: &str, allowed: &[String]) -> Result<String> {
    let uri: axum::http::Uri = url
        .parse()
        .with_context(|| format!("{url:?}: expected ws://HOST:PORT/ws"))?;
    if uri.scheme_str() != Some("ws") {
        bail!("{url:?}: expected ws://HOST:PORT/ws (plain WebSocket; TLS ends at your proxy)");
    }
    let authority = uri
        .authority()
        .with_context(|| format!("{url:?}: no host"))?;
    if authority.as_str().contains('@') {
        bail!("{url:?}: credentials in the URL are not supported; use --token");
    }
    let host = authority.host();
    if !is_loopback(host) && !allowed.iter().any(|a| a.eq_ignore_ascii_case(host)) {
        bail!("{url:?}: only loopback servers (127.0.0.0/8, localhost, [::1]) or hosts given with --allow-host may be targeted");
    }
    Ok(url.to_string())
}

fn is_loopback(host: &str) -> bool {
    let name = host.trim_end_matches('.').to_ascii_lowercase();
    if name == "localhost" || name.ends_with(".localhost") {
        return true;
    }
    if let Some(v6) = host.strip_prefix('[').and_then(|h| h.strip_suffix(']')) {
        return v6.parse::<Ipv6Addr>().is_ok_and(|ip| {
            ip.is_loopback() || ip.to_ipv4_mapped().is_some_and(|v4| v4.is_loopback())
        });
    }
    inet_aton(host).is_some_and(|ip| ip.is_loopback())
}

/// IPv4 as the C resolver reads it: one to four parts, each decimal, octal (leading 0) or hex
/// (0x), the last part filling the bytes that remain (`127.1` is 127.0.0.1).
fn inet_aton(host: &str) -> Option<Ipv4Addr> {
    let parts: Vec<u32> = host.split('.').map(part).collect::<Option<_>>()?;
    let (last, head) = parts.split_last()?;
    if head.len() > 3 || head.iter().any(|&p| p > 255) {
        return None;
    }
    let room = 8 * (4 - head.len() as u32);
    if room < 32 && *last >= 1 << room {
        return None;
    }
    let mut value = *last;
    for (i, &p) in head.iter().enumerate() {
        value |= p << (24 - 8 * i as u32);
    }
    Some(Ipv4Addr::from(value))
}

fn part(s: &str) -> Option<u32> {
    if let Some(hex) = s.strip_prefix("0x").or_else(|| s.strip_prefix("0X")) {
        u32::from_str_radix(hex, 16).ok()
    } else if s.len() > 1 && s.starts_with('0') {
        u32::from_str_radix(&s[1..], 8).ok()
    } else if !s.is_empty() && s.bytes().all(|b| b.is_ascii_digit()) {
        s.parse().ok()
    } else {
        None
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn loopback_in_every_spelling_and_nothing_else() {
        let ok = |u: &str| url_is_allowed(u, &[]).is_ok();
        for local in [
            "ws://127.0.0.1:8080/ws",
            "ws://localhost:8080/ws",
            "ws://LOCALHOST.:8080/ws",
            "ws://[::1]:8080/ws",
            "ws://[::ffff:127.0.0.1]:8080/ws",
            "ws://127.1:8080/ws",
            "ws://2130706433:8080/ws",
            "ws://0x7f.1:8080/ws",
            "ws://0177.0.0.1:8080/ws",
            "ws://127.255.255.254/ws",
        ] {
            assert!(ok(local), "{local}");
        }
        for remote in [
            "ws://localhost:1@127.1:8080/ws",
            "ws://127.0.0.1@evil.example/ws",
            "ws://example.org/ws",
            "ws://128.0.0.1/ws",
            "ws://[::2]/ws",
            "ws://127.0.0.1.evil.example/ws",
            "ws://localhost.evil.example/ws",
            "ws://4294967296/ws",
            "ws://127.256.0.1/ws",
            "http://127.0.0.1/ws",
            "127.0.0.1:8080",
            "ws://",
        ] {
            assert!(!ok(remote), "{remote}");
        }
        let lab = ["render-1.lab".to_string()];
        assert!(url_is_allowed("ws://render-1.lab:8080/ws", &lab).is_ok());
        assert!(url_is_allowed("ws://render-2.lab:8080/ws", &lab).is_err());
    }

    #[test]
    fn the_resolvers_ipv4_forms() {
        assert_eq!(inet_aton("127.1"), Some(Ipv4Addr::new(127, 0, 0, 1)));
        assert_eq!(inet_aton("10.1.2"), Some(Ipv4Addr::new(10, 1, 0, 2)));
        assert_eq!(inet_aton("0"), Some(Ipv4Addr::new(0, 0, 0, 0)));
        assert_eq!(inet_aton("1.2.3.4.5"), None);
        assert_eq!(inet_aton("1.2.65536"), None);
        assert_eq!(inet_aton("08"), None, "8 is not an octal digit");
        assert_eq!(inet_aton(""), None);
    }
}
