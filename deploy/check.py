#!/usr/bin/env python3
"""Checks deploy/: renders each kustomize overlay, validates every resource against the
Kubernetes schemas (kubernetes-validate, strict) and runs checkov on the rendered manifests and
the Dockerfile. Exits non-zero on any failure. scripts/check-deploy.sh runs it in the tools'
virtual environment; tests/deploy.rs runs that.

Rendering: where `kubectl` is installed its kustomize renders the overlays, and this file's own
small renderer (the subset our overlays use: resources, namespace, JSON 6902 patches by kind and
name) must give the same resources, so machines without kubectl check the same thing.
"""
import json
import os
import shutil
import subprocess
import sys
import tempfile
from pathlib import Path

import jsonpatch
import yaml

ROOT = Path(__file__).resolve().parent.parent
K8S = ROOT / "deploy" / "k8s"
OVERLAYS = ["cpu", "gpu"]
# Schemas of the oldest and newest Kubernetes we claim.
VERSIONS = ["1.30.0", "1.37.0"]
# Custom resources kubernetes-validate has no schema for: checked by checkov and by shape here.
CUSTOM = {
    ("gateway.networking.k8s.io/v1", "HTTPRoute"): ["spec.parentRefs", "spec.rules"],
    ("monitoring.coreos.com/v1", "ServiceMonitor"): ["spec.selector", "spec.endpoints"],
}


def render(folder: Path) -> list:
    """Our renderer for the kustomize subset deploy/k8s uses."""
    k = yaml.safe_load((folder / "kustomization.yaml").read_text())
    unknown = set(k) - {"apiVersion", "kind", "namespace", "resources", "patches"}
    if unknown:
        raise SystemExit(f"{folder}: kustomization fields this renderer does not know: {unknown}")
    docs = []
    for r in k.get("resources", []):
        path = folder / r
        if path.is_dir():
            docs += render(path)
        else:
            docs += [d for d in yaml.safe_load_all(path.read_text()) if d]
    for p in k.get("patches", []):
        target = p["target"]
        ops = yaml.safe_load(p["patch"])
        hits = [d for d in docs if d["kind"] == target["kind"] and d["metadata"]["name"] == target["name"]]
        if not hits:
            raise SystemExit(f"{folder}: a patch targets {target}, which no resource is")
        for d in hits:
            patched = jsonpatch.apply_patch(d, ops)
            d.clear()
            d.update(patched)
    if "namespace" in k:
        for d in docs:
            d["metadata"]["namespace"] = k["namespace"]
    return docs


def key(d):
    return (d["kind"], d["metadata"]["name"])


def kubectl_render(folder: Path):
    kubectl = shutil.which("kubectl")
    if not kubectl:
        return None
    out = subprocess.run([kubectl, "kustomize", str(folder)], check=True, capture_output=True, text=True)
    return [d for d in yaml.safe_load_all(out.stdout) if d]


def shape_ok(d, paths):
    for p in paths:
        v = d
        for part in p.split("."):
            v = v.get(part) if isinstance(v, dict) else None
        if not v:
            return f"{d['kind']}/{d['metadata']['name']}: {p} is missing or empty"
    return None


def main() -> int:
    failures = []
    rendered = {}
    for name in OVERLAYS:
        folder = K8S / "overlays" / name
        ours = render(folder)
        theirs = kubectl_render(folder)
        if theirs is not None:
            a = {key(d): d for d in ours}
            b = {key(d): d for d in theirs}
            if a != b:
                diff = [k for k in set(a) | set(b) if a.get(k) != b.get(k)]
                failures.append(f"{name}: kubectl kustomize and deploy/check.py disagree on {diff}")
            print(f"{name}: {len(ours)} resources; kubectl kustomize renders the same")
        else:
            print(f"{name}: {len(ours)} resources (no kubectl here: rendered by deploy/check.py only)")
        rendered[name] = ours

    with tempfile.TemporaryDirectory() as tmp:
        for name, docs in rendered.items():
            core = [d for d in docs if (d["apiVersion"], d["kind"]) not in CUSTOM]
            for d in docs:
                paths = CUSTOM.get((d["apiVersion"], d["kind"]))
                problem = paths and shape_ok(d, paths)
                if problem:
                    failures.append(f"{name}: {problem}")
            core_file = Path(tmp) / f"{name}-core.yaml"
            core_file.write_text(yaml.safe_dump_all(core))
            all_file = Path(tmp) / name / "all.yaml"
            all_file.parent.mkdir()
            all_file.write_text(yaml.safe_dump_all(docs))
            for v in VERSIONS:
                r = subprocess.run(
                    ["kubernetes-validate", "--strict", "--quiet", "-k", v, str(core_file)],
                    capture_output=True, text=True,
                )
                noise = (r.stdout + r.stderr).strip()
                if r.returncode != 0 or noise:
                    failures.append(f"{name}: kubernetes-validate {v}: {noise}")
                else:
                    print(f"{name}: {len(core)} core resources valid against Kubernetes {v} (strict)")
            failures += checkov(["-d", str(all_file.parent), "--framework", "kubernetes"], f"{name} manifests")
    failures += checkov(["-f", str(ROOT / "deploy/container/Dockerfile"), "--framework", "dockerfile"], "Dockerfile")
    for f in failures:
        print("FAIL", f)
    return 1 if failures else 0


def checkov(args, what):
    env = dict(os.environ, BC_SKIP_MAPPING="TRUE", CHECKOV_RUN_SCA_PACKAGE_SCAN_V2="false")
    r = subprocess.run(
        ["checkov", *args, "--skip-download", "--quiet", "--compact", "-o", "json"],
        capture_output=True, text=True, env=env,
    )
    try:
        report = json.loads(r.stdout)
    except json.JSONDecodeError:
        return [f"checkov on {what} gave no report: {r.stdout[-500:]} {r.stderr[-500:]}"]
    reports = report if isinstance(report, list) else [report]
    failed = [c for rep in reports for c in rep.get("results", {}).get("failed_checks", [])]
    summary = [rep.get("summary", {}) for rep in reports]
    passed = sum(s.get("passed", 0) for s in summary)
    skipped = sum(s.get("skipped", 0) for s in summary)
    print(f"checkov {what}: {passed} passed, {len(failed)} failed, {skipped} skipped")
    if passed == 0:
        return [f"checkov on {what} ran no check"]
    return [f"checkov {what}: {c['check_id']} {c['check_name']} ({c.get('resource')})" for c in failed]


if __name__ == "__main__":
    sys.exit(main())
