//! The module boundaries stay one-way: a `use crate::…` (or a `crate::…` path) across a
//! forbidden arrow fails here. The arrows and why: `docs/architecture.md`.

use std::path::{Path, PathBuf};

/// (module, modules it must not name). `settings`, `viewing` and `stats` are leaves: they name
/// nothing.
const FORBIDDEN: &[(&str, &[&str])] = &[
    ("render", &["protocol", "server", "client", "bench", "gaze"]),
    (
        "protocol",
        &[
            "foveation",
            "render",
            "radiosity",
            "server",
            "client",
            "bench",
            "gaze",
        ],
    ),
    ("settings", &["*"]),
    ("viewing", &["*"]),
    ("stats", &["*"]),
    ("foveation", &["protocol", "render", "server", "client"]),
    ("radiosity", &["protocol", "render", "server", "client"]),
    ("scene", &["protocol", "render", "server", "client"]),
    (
        "optics",
        &["protocol", "render", "server", "client", "foveation"],
    ),
];

fn rust_files(dir: &Path, out: &mut Vec<PathBuf>) {
    let Ok(entries) = std::fs::read_dir(dir) else {
        return;
    };
    for e in entries.flatten() {
        let p = e.path();
        if p.is_dir() {
            rust_files(&p, out);
        } else if p.extension().is_some_and(|x| x == "rs") {
            out.push(p);
        }
    }
}

/// The modules a source text names through `crate::`, outside comments.
fn named_modules(text: &str) -> Vec<String> {
    let mut out = Vec::new();
    for line in text.lines() {
        let code = line.split("//").next().unwrap_or("");
        let mut rest = code;
        while let Some(i) = rest.find("crate::") {
            let after = &rest[i + "crate::".len()..];
            let name: String = after
                .chars()
                .take_while(|c| c.is_ascii_alphanumeric() || *c == '_')
                .collect();
            if !name.is_empty() {
                out.push(name);
            }
            rest = after;
        }
        // `use crate::{a, b}` groups.
        if let Some(i) = code.find("crate::{") {
            let group = &code[i + "crate::{".len()..];
            for part in group.split([',', '}']) {
                let name: String = part
                    .trim()
                    .chars()
                    .take_while(|c| c.is_ascii_alphanumeric() || *c == '_')
                    .collect();
                if !name.is_empty() {
                    out.push(name);
                }
            }
        }
    }
    out
}

fn module_files(module: &str) -> Vec<PathBuf> {
    let src = Path::new(env!("CARGO_MANIFEST_DIR")).join("src");
    let mut files = Vec::new();
    rust_files(&src.join(module), &mut files);
    let single = src.join(format!("{module}.rs"));
    if single.exists() {
        files.push(single);
    }
    files
}

#[test]
fn no_module_names_one_it_must_not() {
    let mut violations = Vec::new();
    for (module, forbidden) in FORBIDDEN {
        let files = module_files(module);
        assert!(!files.is_empty(), "no sources for module {module}");
        for file in files {
            let text = std::fs::read_to_string(&file).unwrap();
            for named in named_modules(&text) {
                if named == *module {
                    continue;
                }
                if forbidden.contains(&"*") || forbidden.contains(&named.as_str()) {
                    violations.push(format!("{} names crate::{named}", file.display()));
                }
            }
        }
    }
    assert!(
        violations.is_empty(),
        "one-way boundaries crossed (see docs/architecture.md):\n{}",
        violations.join("\n")
    );
}

#[test]
fn the_scanner_sees_plain_and_grouped_paths_but_not_comments() {
    let text = "use crate::protocol::Hello;\nuse crate::{render, scene::Scene};\n// crate::server\nlet x = crate::gaze::f();";
    assert_eq!(named_modules(text), ["protocol", "render", "scene", "gaze"]);
}

#[test]
fn lib_module_map_lists_every_module() {
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    let lib = std::fs::read_to_string(root.join("src/lib.rs")).unwrap();
    for line in lib.lines().filter(|l| l.starts_with("pub mod ")) {
        let name = line.trim_start_matches("pub mod ").trim_end_matches(';');
        assert!(
            lib.contains(&format!("[`{name}`]")),
            "src/lib.rs's module map does not describe `{name}`"
        );
    }
}

/// Lines of each `fn` in `text` (from its signature to the closing brace at its indentation).
fn function_lengths(text: &str) -> Vec<(String, usize)> {
    let lines: Vec<&str> = text.lines().collect();
    let mut out = Vec::new();
    for (i, line) in lines.iter().enumerate() {
        let trimmed = line.trim_start();
        let indent = &line[..line.len() - trimmed.len()];
        let sig = [
            "fn ",
            "pub fn ",
            "pub(crate) fn ",
            "pub(super) fn ",
            "async fn ",
            "pub async fn ",
        ];
        let Some(rest) = sig.iter().find_map(|s| trimmed.strip_prefix(s)) else {
            continue;
        };
        let name: String = rest
            .chars()
            .take_while(|c| c.is_alphanumeric() || *c == '_')
            .collect();
        let close = format!("{indent}}}");
        if let Some(end) = lines[i + 1..].iter().position(|l| *l == close) {
            out.push((name, end + 2));
        }
    }
    out
}

#[test]
fn files_stay_under_500_lines_and_render_and_server_functions_under_100() {
    let src = Path::new(env!("CARGO_MANIFEST_DIR")).join("src");
    let mut files = Vec::new();
    rust_files(&src, &mut files);
    let mut too_long = Vec::new();
    for file in files {
        let text = std::fs::read_to_string(&file).unwrap();
        let lines = text.lines().count();
        if lines > 500 {
            too_long.push(format!("{}: {lines} lines", file.display()));
        }
        let rel = file
            .strip_prefix(&src)
            .unwrap()
            .to_string_lossy()
            .into_owned();
        if rel.starts_with("render") || rel.starts_with("server") {
            for (name, n) in function_lengths(&text) {
                if n > 100 {
                    too_long.push(format!("{}: fn {name} is {n} lines", file.display()));
                }
            }
        }
    }
    assert!(too_long.is_empty(), "split these:\n{}", too_long.join("\n"));
}

#[test]
fn function_lengths_are_measured_from_signature_to_closing_brace() {
    let text = "fn a() {\n    1;\n}\n\nimpl X {\n    pub fn b(&self) {\n        2;\n        3;\n    }\n}\n";
    assert_eq!(
        function_lengths(text),
        [("a".to_string(), 3), ("b".to_string(), 4)]
    );
}
