#!/usr/bin/env bash
# Fuzzes every parser that takes outside bytes (fuzz/targets.rs) with the stable-Rust mutation
# engine in fuzz/engine.rs: 10^6 inputs per target by default, from the committed corpus in
# fuzz/corpus/. Prints a table (inputs, time, slowest input, peak allocation, findings); each
# finding is saved under fuzz/findings/ and the script exits non-zero. CI runs 10^4 per target
# (tests/fuzz.rs).
#
#   scripts/fuzz.sh [EXECUTIONS] [TARGET…]
set -euo pipefail
cd "$(dirname "$0")/.."
executions=${1:-1000000}
shift || true
cargo run --release --quiet --example fuzz -- --executions "$executions" "$@"
