//! deploy/ is checked like code: the Kubernetes overlays render (the same with kubectl's
//! kustomize where it is installed), every core resource validates strictly against the
//! Kubernetes schemas, and checkov passes on the manifests and the Dockerfile
//! (scripts/check-deploy.sh; its tools come from `scripts/setup.sh --test`). Fails without them.

#[test]
fn manifests_and_dockerfile_validate() {
    let run = std::process::Command::new("bash")
        .arg(concat!(
            env!("CARGO_MANIFEST_DIR"),
            "/scripts/check-deploy.sh"
        ))
        .output()
        .expect("bash runs");
    let stdout = String::from_utf8_lossy(&run.stdout);
    let stderr = String::from_utf8_lossy(&run.stderr);
    assert!(run.status.success(), "{stdout}\n{stderr}");
    for overlay in ["cpu", "gpu"] {
        for version in ["1.30.0", "1.37.0"] {
            let line =
                format!("{overlay}: 6 core resources valid against Kubernetes {version} (strict)");
            assert!(stdout.contains(&line), "missing {line:?} in\n{stdout}");
        }
        assert!(
            stdout.contains(&format!("checkov {overlay} manifests: ")),
            "{stdout}"
        );
    }
    assert!(stdout.contains("checkov Dockerfile: "), "{stdout}");
    assert!(!stdout.contains("FAIL"), "{stdout}");
}

/// The pod's termination grace covers the preStop hook, the drain and the close wait, so
/// Kubernetes never kills a pod that is still handing its sessions over.
#[test]
fn the_grace_period_covers_the_drain() {
    let text = std::fs::read_to_string(concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/deploy/k8s/base/deployment.yaml"
    ))
    .unwrap();
    let number_after = |key: &str| -> f64 {
        let at = text
            .find(key)
            .unwrap_or_else(|| panic!("{key} not in deployment.yaml"));
        text[at + key.len()..]
            .trim_start_matches([' ', ':', '=', '"', '[', '\''])
            .split(|c: char| !c.is_ascii_digit() && c != '.')
            .next()
            .and_then(|n| n.parse().ok())
            .unwrap_or_else(|| panic!("no number after {key}"))
    };
    let grace = number_after("terminationGracePeriodSeconds");
    let drain = number_after("- --drain-s");
    let pre_stop = number_after("command: [\"sleep\", \"");
    let close_wait = 2.0; // server::drain::CLOSE_WAIT
    assert!(
        grace >= pre_stop + drain + close_wait + 2.0,
        "grace {grace} s < preStop {pre_stop} + drain {drain} + close {close_wait} + 2"
    );
}
