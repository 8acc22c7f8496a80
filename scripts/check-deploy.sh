#!/usr/bin/env bash
# Validates deploy/: the kustomize overlays rendered and checked against the Kubernetes schemas
# (kubernetes-validate, strict, oldest and newest supported versions), checkov on the manifests
# and the Dockerfile. The tools live in a virtual environment that `scripts/setup.sh --test`
# makes (FOVEA_DEPLOY_TOOLS, default ~/.cache/fovea/deploy-tools); tests/deploy.rs runs this.
set -euo pipefail
cd "$(dirname "$0")/.."
tools=${FOVEA_DEPLOY_TOOLS:-$HOME/.cache/fovea/deploy-tools}
if [[ ! -x "$tools/bin/checkov" || ! -x "$tools/bin/kubernetes-validate" ]]; then
  echo "check-deploy: no validation tools in $tools; run scripts/setup.sh --test" >&2
  exit 2
fi
PATH="$tools/bin:$PATH" exec "$tools/bin/python" deploy/check.py
