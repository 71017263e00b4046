#!/usr/bin/env bash
# Load benchmark (issue: server): wrk, 64 connections, on GET /api/maps/{id} of roverplan serve,
# and the same wrk run against nginx serving a static file of the same size; prints requests/s,
# p99 latency and the ratio (goal: roverplan >= 0.5 of nginx).
# With `tile` (issue 24: warm tiles), the target is a warm tile of the default map (an elevation
# tile at the native zoom, made once before the run: the layer cache's file) against nginx serving
# that same PNG.
#   tests/bench/http_vs_nginx.sh [SECONDS] [ROVERPLAN] [map|tile]
set -euo pipefail
secs=${1:-10}
root=$(cd "$(dirname "$0")/../.." && pwd)
roverplan=${2:-$root/build/bin/roverplan}
what=${3:-map}
bash "$root/docker/install-deps.sh" --bench
work=$(mktemp -d)
cleanup() {
  [ -n "${rp_pid:-}" ] && kill "$rp_pid" 2>/dev/null || true
  [ -n "${ng_pid:-}" ] && kill "$ng_pid" 2>/dev/null || true
  wait 2>/dev/null || true
  rm -rf "$work"
}
trap cleanup EXIT
port_rp=18181; port_ng=18182

"$roverplan" serve --port $port_rp --data "$work/data" --quiet > "$work/serve.log" 2>&1 &
rp_pid=$!
for _ in $(seq 1 100); do curl -fs "http://127.0.0.1:$port_rp/api/health" >/dev/null 2>&1 && break; sleep 0.2; done
id=$(curl -fs "http://127.0.0.1:$port_rp/api/maps" | python3 -c 'import json,sys; print(json.load(sys.stdin)[0]["id"])')
if [ "$what" = tile ]; then
  native=$(curl -fs "http://127.0.0.1:$port_rp/api/maps/$id" | python3 -c 'import json,sys; print(json.load(sys.stdin)["tiles"]["native_zoom"])')
  url_rp="http://127.0.0.1:$port_rp/api/maps/$id/tiles/elevation/$native/1/1.png"
  file=tile.png type=image/png label="roverplan warm tile"
else
  url_rp="http://127.0.0.1:$port_rp/api/maps/$id"
  file=map.json type=application/json label="roverplan GET /api/maps/ID"
fi
curl -fs "$url_rp" > "$work/body"  # a tile: rendered and cached now, so the run reads its file
size=$(stat -c %s "$work/body")

mkdir -p "$work/www" "$work/nginx/logs"
cp "$work/body" "$work/www/$file"
chmod -R a+rX "$work"  # nginx workers run as an unprivileged user
cat > "$work/nginx/nginx.conf" <<CONF
worker_processes 2;
pid $work/nginx/nginx.pid;
error_log $work/nginx/logs/error.log;
events { worker_connections 1024; }
http {
  access_log off;
  default_type $type;
  server { listen 127.0.0.1:$port_ng; root $work/www; }
}
CONF
nginx -c "$work/nginx/nginx.conf" -p "$work/nginx" -g 'daemon off;' &
ng_pid=$!
sleep 0.5
url_ng="http://127.0.0.1:$port_ng/$file"

bench() {  # prints "requests_per_s p99_ms"
  wrk -t2 -c64 -d"${secs}s" --latency "$1" > "$work/wrk.txt"
  python3 - "$work/wrk.txt" <<'PY'
import re, sys
t = open(sys.argv[1]).read()
rps = float(re.search(r"Requests/sec:\s+([\d.]+)", t).group(1))
m = re.search(r"99%\s+([\d.]+)(us|ms|s)", t)
p99 = float(m.group(1)) * {"us": 0.001, "ms": 1, "s": 1000}[m.group(2)]
errors = re.search(r"Non-2xx or 3xx responses: (\d+)", t)
print(rps, p99, errors.group(1) if errors else 0)
PY
}
read -r rp_rps rp_p99 rp_err < <(bench "$url_rp")
read -r ng_rps ng_p99 ng_err < <(bench "$url_ng")
awk -v a="$rp_rps" -v b="$ng_rps" -v pa="$rp_p99" -v pb="$ng_p99" -v s="$size" -v ea="$rp_err" -v eb="$ng_err" -v secs="$secs" -v label="$label" 'BEGIN {
  printf "wrk -t2 -c64 -d%ss, body %d bytes\n", secs, s
  printf "%-28s %12s %10s %8s\n", "target", "requests/s", "p99 ms", "non-2xx"
  printf "%-28s %12.0f %10.2f %8d\n", label, a, pa, ea
  printf "%-28s %12.0f %10.2f %8d\n", "nginx static file", b, pb, eb
  printf "ratio roverplan/nginx       x%.2f (goal >= 0.5)\n", a / b
}'
