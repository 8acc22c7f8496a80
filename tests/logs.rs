//! Logs for machines and for people: `--log-format json` writes one JSON object per line, and
//! text logs carry no colour codes when stderr is not a terminal (here it is a pipe).

fn render(args: &[&str]) -> String {
    let out = std::env::temp_dir().join(format!("fovea-logs-{}.png", std::process::id()));
    let o = std::process::Command::new(env!("CARGO_BIN_EXE_fovea"))
        .args(args)
        .args(["render", "--size", "16x12", "--out"])
        .arg(&out)
        .output()
        .expect("fovea runs");
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    String::from_utf8_lossy(&o.stderr).into_owned()
}

#[test]
fn json_logs_parse_one_object_per_line() {
    let stderr = render(&["--log-format", "json"]);
    let logs: Vec<serde_json::Value> = stderr
        .lines()
        .filter(|l| l.starts_with('{'))
        .map(|l| serde_json::from_str(l).unwrap_or_else(|e| panic!("{e}: {l}")))
        .collect();
    assert!(!logs.is_empty(), "no JSON log lines in:\n{stderr}");
    for l in &logs {
        assert!(
            l["level"].is_string() && l["fields"]["message"].is_string(),
            "{l}"
        );
    }
    assert!(logs
        .iter()
        .any(|l| l["fields"]["message"] == "GPU adapter chosen"));
}

#[test]
fn text_logs_to_a_pipe_have_no_colour_codes() {
    let stderr = render(&[]);
    assert!(stderr.contains("GPU adapter chosen"), "{stderr}");
    assert!(!stderr.contains('\u{1b}'), "ANSI codes in:\n{stderr}");
}
