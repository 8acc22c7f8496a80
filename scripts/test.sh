#!/usr/bin/env bash
# Runs every test: Rust unit, GPU, protocol and server tests, then the browser test in headless
# Chromium. The same command runs in CI (.ci/run). GPU tests use whatever Vulkan adapter there
# is (Mesa's software lavapipe on machines without a GPU) and fail if there is none.
set -euo pipefail
cd "$(dirname "$0")/.."
scripts/setup.sh --test
[[ -f "$HOME/.cargo/env" ]] && source "$HOME/.cargo/env"

# One profile (release) for the binary and the tests: the dependency tree is compiled once.
cargo build --release --locked
cargo test --release --locked

(cd tests/browser && npm ci --no-audit --no-fund --loglevel=error)
FOVEA_BIN="$PWD/target/release/fovea" node --test tests/browser/
