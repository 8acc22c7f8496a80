//! Who may open a session, read the metrics and drain the server. Checked before the WebSocket
//! upgrade, so a refused client costs one HTTP response and never a session slot:
//! - `/ws` wants the session token (`Authorization: Bearer …`, or `?token=…` where a browser
//!   cannot set headers) when one is set: 401 otherwise;
//! - a browser's `Origin` must be the page's own (its host equals the request's `Host`) or one
//!   named with `--allow-origin`: 403 otherwise (cross-site WebSocket hijacking: any page a
//!   viewer visits could otherwise open sessions on their server with their network position);
//! - `/metrics` wants the metrics token when one is set; `/admin/*` wants the admin token and is
//!   off without one.
//!
//! Tokens are compared in constant time and never logged (`Secret` prints as `<redacted>`).

use axum::http::{header, HeaderMap, StatusCode};

/// A token from a flag or the environment.
#[derive(Clone, PartialEq, Eq)]
pub struct Secret(String);

impl Secret {
    /// `None` for an empty string: `FOVEA_TOKEN=` does not mean "the empty token".
    pub fn new(value: impl Into<String>) -> Option<Secret> {
        let value = value.into();
        (!value.is_empty()).then_some(Secret(value))
    }

    /// Constant time in the contents (the length is not secret: tokens are generated).
    pub fn matches(&self, offered: &str) -> bool {
        constant_time_eq(self.0.as_bytes(), offered.as_bytes())
    }

    /// For clients that must send it.
    pub fn expose(&self) -> &str {
        &self.0
    }
}

impl std::fmt::Debug for Secret {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str("<redacted>")
    }
}

pub fn constant_time_eq(a: &[u8], b: &[u8]) -> bool {
    a.len() == b.len() && a.iter().zip(b).fold(0u8, |acc, (x, y)| acc | (x ^ y)) == 0
}

/// The server's access rules (see the module comment).
#[derive(Debug, Clone, Default)]
pub struct Access {
    pub token: Option<Secret>,
    pub metrics_token: Option<Secret>,
    pub admin_token: Option<Secret>,
    /// Origins (`scheme://host[:port]`) allowed besides the page's own.
    pub allow_origins: Vec<String>,
}

/// Why a request is refused, as its HTTP answer.
pub type Refusal = (StatusCode, &'static str);

impl Access {
    /// The check in front of `/ws`; `query_token` is the `token` query parameter, if any.
    pub fn admit_session(
        &self,
        headers: &HeaderMap,
        query_token: Option<&str>,
    ) -> Result<(), Refusal> {
        self.check_origin(headers)?;
        require(
            &self.token,
            offered(headers, query_token),
            "this server needs a token: Authorization: Bearer <token>, or ?token=<token>\n",
        )
    }

    pub fn admit_metrics(&self, headers: &HeaderMap) -> Result<(), Refusal> {
        require(
            &self.metrics_token,
            offered(headers, None),
            "metrics need the metrics token: Authorization: Bearer <token>\n",
        )
    }

    pub fn admit_admin(&self, headers: &HeaderMap) -> Result<(), Refusal> {
        if self.admin_token.is_none() {
            return Err((
                StatusCode::FORBIDDEN,
                "admin endpoints are off: start the server with --admin-token\n",
            ));
        }
        require(
            &self.admin_token,
            offered(headers, None),
            "admin endpoints need the admin token: Authorization: Bearer <token>\n",
        )
    }

    /// No `Origin`: not a browser (browsers always send one on a WebSocket handshake), and a
    /// non-browser client is held by the token instead. Otherwise the origin's host must be the
    /// `Host` the request came to (the page's own origin, also behind a proxy that keeps the
    /// Host header) or one of `allow_origins`.
    fn check_origin(&self, headers: &HeaderMap) -> Result<(), Refusal> {
        let Some(origin) = headers.get(header::ORIGIN) else {
            return Ok(());
        };
        let origin = origin.to_str().unwrap_or("").trim_end_matches('/');
        let host = headers
            .get(header::HOST)
            .and_then(|h| h.to_str().ok())
            .unwrap_or("");
        let own = ["http://", "https://"].iter().any(|scheme| {
            origin
                .strip_prefix(scheme)
                .is_some_and(|h| h.eq_ignore_ascii_case(host))
        });
        let listed = self
            .allow_origins
            .iter()
            .any(|o| o.trim_end_matches('/').eq_ignore_ascii_case(origin));
        if own || listed {
            Ok(())
        } else {
            Err((
                StatusCode::FORBIDDEN,
                "this page's origin may not open sessions here (the server allows its own page and --allow-origin)\n",
            ))
        }
    }
}

/// No secret set: open. Otherwise the offered token must match (401 with `why` if not).
fn require(
    secret: &Option<Secret>,
    offered: Option<&str>,
    why: &'static str,
) -> Result<(), Refusal> {
    match secret {
        None => Ok(()),
        Some(t) if offered.is_some_and(|o| t.matches(o)) => Ok(()),
        Some(_) => Err((StatusCode::UNAUTHORIZED, why)),
    }
}

/// The bearer token of `Authorization`, else the query's.
fn offered<'a>(headers: &'a HeaderMap, query_token: Option<&'a str>) -> Option<&'a str> {
    headers
        .get(header::AUTHORIZATION)
        .and_then(|v| v.to_str().ok())
        .and_then(|v| v.strip_prefix("Bearer "))
        .map(str::trim)
        .or(query_token)
}

#[cfg(test)]
mod tests {
    use super::*;
    use axum::http::HeaderValue;

    fn headers(pairs: &[(header::HeaderName, &str)]) -> HeaderMap {
        let mut h = HeaderMap::new();
        for (k, v) in pairs {
            h.insert(k.clone(), HeaderValue::from_str(v).unwrap());
        }
        h
    }

    #[test]
    fn origins_are_the_pages_own_or_listed() {
        let a = Access {
            allow_origins: vec!["https://lab.example".into()],
            ..Access::default()
        };
        let host = (header::HOST, "fovea.example:8080");
        let ok = |o: &str| {
            a.check_origin(&headers(&[host.clone(), (header::ORIGIN, o)]))
                .is_ok()
        };
        assert!(ok("http://fovea.example:8080"));
        assert!(ok("https://FOVEA.example:8080/"));
        assert!(ok("https://lab.example"));
        assert!(
            !ok("http://fovea.example:8081"),
            "another port is another origin"
        );
        assert!(!ok("http://evil.example"));
        assert!(!ok("null"), "sandboxed frames and files send null");
        assert!(!ok("http://fovea.example:8080.evil.example"));
        assert!(
            a.check_origin(&headers(&[host])).is_ok(),
            "no Origin: not a browser"
        );
    }

    #[test]
    fn tokens_come_from_the_header_or_the_query_and_must_match() {
        let a = Access {
            token: Secret::new("s3cret"),
            ..Access::default()
        };
        let bearer = |v: &str| headers(&[(header::AUTHORIZATION, v)]);
        assert!(a.admit_session(&bearer("Bearer s3cret"), None).is_ok());
        assert!(a.admit_session(&HeaderMap::new(), Some("s3cret")).is_ok());
        for wrong in ["Bearer s3cre", "Bearer s3cret2", "Basic s3cret", "s3cret"] {
            let e = a.admit_session(&bearer(wrong), None).unwrap_err();
            assert_eq!(e.0, StatusCode::UNAUTHORIZED, "{wrong}");
        }
        assert_eq!(
            a.admit_session(&HeaderMap::new(), None).unwrap_err().0,
            StatusCode::UNAUTHORIZED
        );
        assert_eq!(format!("{:?}", a.token), "Some(<redacted>)");
        assert!(Secret::new("").is_none());
    }

    #[test]
    fn admin_is_off_without_its_token_and_separate_from_the_session_token() {
        let mut a = Access {
            token: Secret::new("viewer"),
            ..Access::default()
        };
        let bearer = |v: &str| headers(&[(header::AUTHORIZATION, v)]);
        assert_eq!(
            a.admit_admin(&bearer("Bearer viewer")).unwrap_err().0,
            StatusCode::FORBIDDEN
        );
        a.admin_token = Secret::new("admin");
        assert_eq!(
            a.admit_admin(&bearer("Bearer viewer")).unwrap_err().0,
            StatusCode::UNAUTHORIZED
        );
        assert!(a.admit_admin(&bearer("Bearer admin")).is_ok());
        assert!(
            a.admit_metrics(&HeaderMap::new()).is_ok(),
            "metrics open without a metrics token"
        );
        a.metrics_token = Secret::new("prom");
        assert!(a.admit_metrics(&bearer("Bearer admin")).is_err());
        assert!(a.admit_metrics(&bearer("Bearer prom")).is_ok());
    }
}
