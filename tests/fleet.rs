//! The fleet on loopback (scripts/fleet.sh): three instances behind nginx, `fovea load` through
//! it, one instance sent SIGTERM mid-run. Needs nginx (scripts/setup.sh --test installs it)
//! and fails without it.

mod common;

use std::collections::BTreeMap;
use std::path::Path;

fn env_file(path: &Path) -> BTreeMap<String, String> {
    std::fs::read_to_string(path)
        .unwrap_or_else(|e| panic!("{}: {e}", path.display()))
        .lines()
        .filter_map(|l| l.split_once('='))
        .map(|(k, v)| (k.to_string(), v.to_string()))
        .collect()
}

#[test]
fn a_drained_instance_hands_its_sessions_to_the_fleet_and_loses_nothing() {
    let out = Path::new(env!("CARGO_TARGET_TMPDIR")).join("fleet");
    let run = std::process::Command::new("bash")
        .arg(Path::new(env!("CARGO_MANIFEST_DIR")).join("scripts/fleet.sh"))
        .arg(&out)
        .arg("12")
        .env("FOVEA", env!("CARGO_BIN_EXE_fovea"))
        .output()
        .expect("bash runs");
    let stdout = String::from_utf8_lossy(&run.stdout);
    let stderr = String::from_utf8_lossy(&run.stderr);
    assert!(run.status.success(), "fleet.sh failed:\n{stdout}\n{stderr}");
    println!("{stdout}");
    let figures = env_file(&out.join("fleet.env"));
    let num = |k: &str| -> f64 { figures[k].parse().unwrap_or(f64::NAN) };
    assert_eq!(figures["LOAD_EXIT_CODE"], "0", "{stdout}");
    assert_eq!(
        figures["VICTIM_EXIT_CODE"], "0",
        "the drained instance exits cleanly"
    );
    assert!(
        num("VICTIM_SESSIONS") >= 1.0,
        "the victim had sessions: {figures:?}"
    );
    // Bounded by the grace period plus the close wait (2 s) and process teardown.
    assert!(
        num("VICTIM_EXIT_S") <= num("DRAIN_S") + 3.0,
        "the drained instance exits within its grace period: {figures:?}"
    );
    assert_eq!(figures["PARTIAL_RECORDINGS"], "0");

    let load: serde_json::Value = serde_json::from_str(
        &std::fs::read_to_string(out.join("drain/load.json")).expect("drain/load.json"),
    )
    .unwrap();
    // The file says how the frames were asked for (fleet.sh: the default, what the page asks for).
    assert_eq!(load["encoding"]["codec"], "h264", "{load}");
    assert_eq!(
        load["encoding"]["inset_deg"],
        serde_json::Value::Null,
        "{load}"
    );
    let run = &load["runs"][0];
    for zero in [
        "connection_failures",
        "refused",
        "errors",
        "sessions_ended_early",
    ] {
        assert_eq!(run[zero], 0, "{zero}: {run}");
    }
    let reconnects = run["reconnects"].as_f64().unwrap_or(0.0);
    assert!(
        reconnects >= num("VICTIM_SESSIONS"),
        "every session of the drained instance moved: {reconnects} reconnects, {figures:?}"
    );
    let gap = run["reconnect_gap_ms"]["max"].as_f64().unwrap_or(f64::NAN);
    assert!(
        gap <= 2000.0,
        "a moved session's frames resumed within 2 s: {gap} ms"
    );
    // Frames flowed in every whole second of the run, the drain's included.
    let timeline: Vec<u64> = run["fps_timeline"]
        .as_array()
        .unwrap()
        .iter()
        .filter_map(|v| v.as_u64())
        .collect();
    let whole = run["seconds"].as_f64().unwrap_or(0.0).floor() as usize;
    assert!(
        timeline[..whole.min(timeline.len())].iter().all(|&n| n > 0),
        "{timeline:?}"
    );

    // Every session of the drained instance left a whole recording of what it received.
    let victim = &figures["VICTIM"];
    let log = std::fs::read_to_string(out.join(format!("serve-{victim}.log"))).unwrap();
    let mut checked = 0;
    for line in log.lines() {
        let Ok(v) = serde_json::from_str::<serde_json::Value>(line) else {
            panic!("a log line that is not JSON: {line}");
        };
        let f = &v["fields"];
        if f["message"] != "session closed" {
            continue;
        }
        let (id, samples) = (
            f["session"].as_u64().unwrap(),
            f["samples"].as_u64().unwrap(),
        );
        let path = common::run_folder(&out.join(format!("rec-{victim}")))
            .join(format!("session-{id}.csv"));
        let text = std::fs::read_to_string(&path).unwrap_or_else(|e| panic!("{path:?}: {e}"));
        let rows: Vec<&str> = text.lines().skip(1).collect();
        assert_eq!(rows.len() as u64, samples, "{path:?}");
        let whole = |r: &&str| {
            let cells: Vec<&str> = r.split(',').collect();
            cells.len() == 4 && cells[..3].iter().all(|c| c.parse::<f64>().is_ok())
        };
        assert!(rows.iter().all(whole), "{path:?}: a cut row");
        checked += 1;
    }
    assert!(
        checked as f64 >= num("VICTIM_SESSIONS"),
        "{checked} recordings checked"
    );
}
