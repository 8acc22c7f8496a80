//! The web client, embedded at compile time so the binary serves it from any directory.

const FILES: &[(&str, &str, &[u8])] = &[
    (
        "/index.html",
        "text/html; charset=utf-8",
        include_bytes!("../../web/index.html"),
    ),
    (
        "/app.js",
        "text/javascript; charset=utf-8",
        include_bytes!("../../web/app.js"),
    ),
    (
        "/overlay.js",
        "text/javascript; charset=utf-8",
        include_bytes!("../../web/overlay.js"),
    ),
    (
        "/h264.js",
        "text/javascript; charset=utf-8",
        include_bytes!("../../web/h264.js"),
    ),
    (
        "/inset.js",
        "text/javascript; charset=utf-8",
        include_bytes!("../../web/inset.js"),
    ),
    (
        "/ui.js",
        "text/javascript; charset=utf-8",
        include_bytes!("../../web/ui.js"),
    ),
    (
        "/style.css",
        "text/css; charset=utf-8",
        include_bytes!("../../web/style.css"),
    ),
    (
        "/synthetic-eye.js",
        "text/javascript; charset=utf-8",
        include_bytes!("../../web/synthetic-eye.js"),
    ),
    (
        "/favicon.svg",
        "image/svg+xml",
        include_bytes!("../../web/favicon.svg"),
    ),
];

/// Content type and bytes for a request path; `/` is the page itself.
pub fn find(path: &str) -> Option<(&'static str, &'static [u8])> {
    let path = if path == "/" { "/index.html" } else { path };
    FILES
        .iter()
        .find(|(p, _, _)| *p == path)
        .map(|(_, mime, body)| (*mime, *body))
}

#[cfg(test)]
mod tests {
    #[test]
    fn root_serves_the_page_and_unknown_paths_do_not() {
        let (mime, body) = super::find("/").unwrap();
        assert!(mime.starts_with("text/html"));
        assert!(std::str::from_utf8(body).unwrap().contains("app.js"));
        assert!(super::find("/../Cargo.toml").is_none());
    }
}
