#!/usr/bin/env bash
# Soak: a server under steady load for a while, its resident memory sampled every few seconds,
# and the slope of a least-squares line through the samples after the first minute (warm-up:
# pipelines, caches, the allocator's pools). A server that frees what it uses has a slope near
# zero; one that leaks per frame climbs with the frame count.
#
#   scripts/soak.sh [OUT_DIR] [SECONDS] [SESSIONS]     (defaults: /tmp/fovea-soak 600 4)
#
# Writes OUT_DIR/rss.csv (t_s, rss_kb) and OUT_DIR/load/ (the load report); prints the slope.
# Not part of CI (ten minutes); run it after changes to sessions, the renderer or metrics.
set -euo pipefail
out=${1:-/tmp/fovea-soak}
seconds=${2:-600}
sessions=${3:-4}
every=5
here=$(cd "$(dirname "$0")/.." && pwd)
fovea="$here/target/release/fovea"
[ -x "$fovea" ] || cargo build --release --manifest-path "$here/Cargo.toml"
mkdir -p "$out"

"$fovea" serve --addr 127.0.0.1:0 >"$out/serve.out" 2>"$out/serve.log" &
server=$!
trap 'kill $server 2>/dev/null || true; wait 2>/dev/null || true' EXIT
for _ in $(seq 1 600); do
    grep -q "listening on" "$out/serve.out" 2>/dev/null && break
    sleep 0.1
done
url=$(sed -n 's#fovea listening on http://\(.*\)/#ws://\1/ws#p' "$out/serve.out")
[ -n "$url" ] || { echo "the server did not start; see $out/serve.log" >&2; exit 1; }
echo "soak: $sessions sessions for $seconds s against $url (server pid $server)"

"$fovea" load --url "$url" --sessions "$sessions" --duration "$seconds" --out "$out/load" \
    >"$out/load.out" 2>&1 &
load=$!
echo "t_s,rss_kb" >"$out/rss.csv"
start=$(date +%s)
while kill -0 "$load" 2>/dev/null; do
    rss=$(awk '/^VmRSS:/ {print $2}' "/proc/$server/status")
    echo "$(( $(date +%s) - start )),$rss" >>"$out/rss.csv"
    sleep "$every"
done
wait "$load" || { echo "load failed; see $out/load.out" >&2; exit 1; }

# Least-squares slope over the samples after the first minute, in KB/s and per frame.
frames=$(python3 -c "import json,sys; print(json.load(open(sys.argv[1]))['runs'][0]['frames'])" \
    "$out/load/load.json" 2>/dev/null || echo 0)
awk -F, -v frames="$frames" -v seconds="$seconds" 'NR > 1 && $1 >= 60 {
        n++; sx += $1; sy += $2; sxx += $1 * $1; sxy += $1 * $2
        if (n == 1) first = $2; last = $2
    }
    END {
        if (n < 3) { print "too few samples after the first minute"; exit 1 }
        slope = (n * sxy - sx * sy) / (n * sxx - sx * sx)
        printf "RSS after warm-up: %.1f MB → %.1f MB over %d samples; slope %.2f KB/s", first / 1024, last / 1024, n, slope
        if (frames > 0) printf " (%.1f bytes per frame over %d frames)", slope * 1024 * seconds / frames, frames
        printf "\n"
    }' "$out/rss.csv"
