#!/usr/bin/env bash
# A fleet on one machine: three `fovea serve` on loopback ports behind nginx (WebSocket upgrade,
# least_conn, a 503 from a draining instance retried on the next), `fovea load` through nginx,
# and SIGTERM to one instance in the middle of the run. tests/fleet.rs runs it and checks what
# it leaves in OUT; run by hand it prints the figures.
#
#   scripts/fleet.sh OUT [SECONDS]      (default 16 s of load with the drain, after 6 s without)
#
# Environment: FOVEA (the binary, default target/release/fovea), NGINX (default: nginx on PATH
# or /usr/sbin/nginx), SESSIONS (6), SIZE (96x64), SCENE (opaque), DRAIN_S (4).
# OUT holds: baseline/load.json, drain/load.json, serve-N.log (JSON logs), rec-N/ (each
# instance's recordings), nginx.conf and its logs, and fleet.env (the figures, KEY=VALUE).
set -euo pipefail
cd "$(dirname "$0")/.."

out=${1:?usage: scripts/fleet.sh OUT [SECONDS]}
seconds=${2:-16}
fovea=${FOVEA:-target/release/fovea}
nginx=${NGINX:-$(command -v nginx || echo /usr/sbin/nginx)}
sessions=${SESSIONS:-6}
size=${SIZE:-96x64}
scene=${SCENE:-opaque}
drain_s=${DRAIN_S:-4}

[[ -x "$fovea" ]] || { echo "fleet: no fovea binary at $fovea (cargo build --release)" >&2; exit 2; }
[[ -x "$nginx" ]] || { echo "fleet: no nginx (apt-get install nginx, or scripts/setup.sh --test)" >&2; exit 2; }
rm -rf "$out" && mkdir -p "$out"
out=$(cd "$out" && pwd)
chmod 755 "$out"

pids=()
cleanup() {
  for p in "${pids[@]}"; do kill "$p" 2>/dev/null || true; done
  [[ -f "$out/nginx.pid" ]] && kill "$(cat "$out/nginx.pid")" 2>/dev/null || true
}
trap cleanup EXIT

# Status code of GET path on 127.0.0.1:port, with bash's own TCP (no curl needed).
status() {
  local port=$1 path=$2 line
  exec 3<>"/dev/tcp/127.0.0.1/$port" || return 1
  printf 'GET %s HTTP/1.1\r\nHost: 127.0.0.1:%s\r\nConnection: close\r\n\r\n' "$path" "$port" >&3
  read -r line <&3 || true
  exec 3<&- 3>&-
  echo "$line" | cut -d' ' -f2
}

# Three instances on ports the kernel picks; each prints "fovea listening on http://ADDR/".
ports=()
for i in 1 2 3; do
  mkdir -p "$out/rec-$i"
  "$fovea" --log-format json serve --addr 127.0.0.1:0 --record-dir "$out/rec-$i" \
    --drain-s "$drain_s" >"$out/serve-$i.out" 2>"$out/serve-$i.log" &
  pids+=($!)
done
for i in 1 2 3; do
  for _ in $(seq 1 600); do
    grep -q "listening on" "$out/serve-$i.out" 2>/dev/null && break
    sleep 0.1
  done
  port=$(sed -n 's|.*listening on http://127.0.0.1:\([0-9]*\)/.*|\1|p' "$out/serve-$i.out")
  [[ -n "$port" ]] || { echo "fleet: instance $i did not start:" >&2; cat "$out/serve-$i.log" >&2; exit 1; }
  ports+=("$port")
  [[ "$(status "$port" /readyz)" == 200 ]] || { echo "fleet: instance $i not ready" >&2; exit 1; }
done

# nginx in the foreground of its own prefix: no root paths, no system service.
write_conf() {
  cat >"$out/nginx.conf" <<EOF
daemon on;
worker_processes 1;
pid $out/nginx.pid;
error_log $out/nginx-error.log info;
events { worker_connections 512; }
http {
  access_log $out/nginx-access.log;
  client_body_temp_path $out/tmp/body;
  proxy_temp_path $out/tmp/proxy;
  fastcgi_temp_path $out/tmp/fastcgi;
  uwsgi_temp_path $out/tmp/uwsgi;
  scgi_temp_path $out/tmp/scgi;
  map \$http_upgrade \$connection_upgrade { default upgrade; '' close; }
  upstream fovea {
    least_conn;
    server 127.0.0.1:${ports[0]};
    server 127.0.0.1:${ports[1]};
    server 127.0.0.1:${ports[2]};
  }
  server {
    listen 127.0.0.1:$1;
    location / {
      proxy_pass http://fovea;
      proxy_http_version 1.1;
      proxy_set_header Upgrade \$http_upgrade;
      proxy_set_header Connection \$connection_upgrade;
      proxy_set_header Host \$http_host;
      proxy_read_timeout 1h;
      proxy_connect_timeout 1s;
      # A draining instance answers /ws with 503, an exited one refuses the connection:
      # either way the handshake goes to the next instance.
      proxy_next_upstream error timeout http_503;
      proxy_next_upstream_tries 3;
    }
  }
}
EOF
}
mkdir -p "$out/tmp"
nport=""
for _ in $(seq 1 20); do
  try=$((20000 + RANDOM % 20000))
  write_conf "$try"
  if "$nginx" -e "$out/nginx-error.log" -p "$out" -c "$out/nginx.conf" 2>>"$out/nginx-start.log"; then
    nport=$try
    break
  fi
done
[[ -n "$nport" ]] || { echo "fleet: nginx did not start:" >&2; cat "$out/nginx-start.log" >&2; exit 1; }
for _ in $(seq 1 50); do [[ "$(status "$nport" /readyz)" == 200 ]] && break; sleep 0.1; done
url="ws://127.0.0.1:$nport/ws"
echo "fleet: instances on ${ports[*]}, nginx on $nport"

load() {
  "$fovea" load --url "$url" --sessions "$sessions" --duration "$1" --size "$size" \
    --scene "$scene" --rate-hz 60 --out "$out/$2" >"$out/$2.out" 2>&1
}

# Baseline: the whole fleet, no drain.
load 6 baseline

# The drain run: SIGTERM to the instance with the most sessions a third of the way in.
load "$seconds" drain &
loader=$!
sleep "$(awk "BEGIN{print $seconds / 3}")"
victim=0 most=-1
for i in 0 1 2; do
  n=$(grep -c '"session opened"' "$out/serve-$((i + 1)).log" || true)
  n=$((n - $(grep -c '"session closed"' "$out/serve-$((i + 1)).log" || true)))
  if (( n > most )); then most=$n victim=$i; fi
done
vpid=${pids[$victim]}
echo "fleet: SIGTERM to instance $((victim + 1)) (port ${ports[$victim]}, $most sessions)"
t0=$(date +%s.%N)
kill -TERM "$vpid"
wait "$vpid" && vrc=0 || vrc=$?
t1=$(date +%s.%N)
wait "$loader" && lrc=0 || lrc=$?

exit_s=$(awk "BEGIN{print $t1 - $t0}")
partial=$(find "$out/rec-$((victim + 1))" -name '*.partial' | wc -l)
{
  echo "VICTIM=$((victim + 1))"
  echo "VICTIM_SESSIONS=$most"
  echo "VICTIM_EXIT_CODE=$vrc"
  echo "VICTIM_EXIT_S=$exit_s"
  echo "DRAIN_S=$drain_s"
  echo "LOAD_EXIT_CODE=$lrc"
  echo "PARTIAL_RECORDINGS=$partial"
} >"$out/fleet.env"
cat "$out/fleet.env"
echo "fleet: baseline $(grep -h 'p95' "$out/baseline.out" | head -1)"
echo "fleet: drain    $(grep -h 'p95' "$out/drain.out" | head -1)"
