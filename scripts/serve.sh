#!/usr/bin/env bash
# Quick start: set up what is missing, build, and serve the default scene on 127.0.0.1:8080.
# Extra arguments go to `fovea serve` (e.g. --addr 0.0.0.0:8080).
set -euo pipefail
cd "$(dirname "$0")/.."
scripts/setup.sh
[[ -f "$HOME/.cargo/env" ]] && source "$HOME/.cargo/env"
cargo build --release --locked
exec target/release/fovea serve "$@"
