#!/usr/bin/env bash
# Renders every built-in scene × preset at 160×120 into DIR (PNG, lossless), so a refactor can be
# checked for unchanged pixels:
#   scripts/compare_frames.sh render BEFORE_DIR      (on the old commit)
#   scripts/compare_frames.sh render AFTER_DIR       (on the new one)
#   scripts/compare_frames.sh diff BEFORE_DIR AFTER_DIR
# `diff` prints, per image, "identical" or the max and mean FLIP, and exits non-zero when any
# image differs by more than FLIP 0.001. Each frame is the 3rd of a stream, gaze off-centre, so
# reprojection and the foveation passes have history to work with.
set -euo pipefail
cd "$(dirname "$0")/.."
bin="${FOVEA_BIN:-target/release/fovea}"
scenes=(bunny-marble bunny-skin materials opaque bunny cornell)
presets=(reference full quality balanced fast)

case "${1:-}" in
  render)
    out="${2:?usage: compare_frames.sh render DIR}"
    mkdir -p "$out"
    # Binaries before the command-line cleanup took --width/--height instead of --size.
    size=(--size 160x120)
    "$bin" render --help | grep -q -- '--size' || size=(--width 160 --height 120)
    for s in "${scenes[@]}"; do
      for p in "${presets[@]}"; do
        "$bin" render --scene "$s" --preset "$p" "${size[@]}" --gaze 0.4,0.45 \
          --frames 3 --out "$out/$s-$p.png" 2>/dev/null
        echo "rendered $s $p"
      done
    done
    ;;
  diff)
    cargo run --release --locked --quiet --example frame_diff -- "${2:?before dir}" "${3:?after dir}"
    ;;
  *)
    echo "usage: compare_frames.sh render DIR | diff BEFORE_DIR AFTER_DIR" >&2
    exit 2
    ;;
esac
