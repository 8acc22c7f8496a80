#!/usr/bin/env bash
# Runs every test: Rust unit, GPU, protocol, server and browser tests (the browser tests drive
# the system's Chromium over the DevTools protocol from Rust; no Node.js). The same command runs
# in CI (.ci/run). GPU tests use whatever Vulkan adapter there is (Mesa's software lavapipe on
# machines without a GPU) and fail if there is none; browser tests fail without a Chromium.
set -euo pipefail
cd "$(dirname "$0")/.."
scripts/setup.sh --test
# shellcheck disable=SC1091
[[ -f "$HOME/.cargo/env" ]] && . "$HOME/.cargo/env"
# Quiet Mesa's device-select layer on headless machines (see src/main.rs).
export NODEVICE_SELECT=1
# Where setup.sh fetched Playwright's Chromium (Ubuntu 24.04), when there is no system one.
if [[ -z "${CHROMIUM:-}" ]] && ! command -v chromium >/dev/null && ! command -v google-chrome >/dev/null; then
  shell=$(compgen -G "$HOME/.cache/ms-playwright/chromium_headless_shell-*/chrome-*/*headless*shell" | head -n1 || true)
  [[ -n "$shell" ]] && export CHROMIUM="$shell"
fi

# One profile (release) for the binary and the tests: the dependency tree is compiled once.
cargo build --release --locked
cargo test --release --locked
