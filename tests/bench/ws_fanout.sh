#!/usr/bin/env bash
# Fan-out benchmark (issue 14, issue 22 item 2), figures printed, never asserted:
#   1. /api/health latency (p50/p99/max) on a running mission with IDLE never-reading sockets and
#      READERS reading subscribers on its stream (default 5000 and 1000), and with 1000/2000 readers;
#   2. a running study's runs/s with 0 vs STUDY_READERS (200) readers of its stream;
#   3. (FRAMES=1) frames/s delivered to 50 clients reading a mission to its end, server memory.
#   tests/bench/ws_fanout.sh [ROVERPLAN]   env: IDLE READERS SECONDS_EACH STUDY_READERS FRAMES EXTRA BENCH
# ROVERPLAN defaults to build/bin/roverplan; give another version's binary to measure it (this
# tree's bench binary drives it). EXTRA: more `serve` flags (e.g. "--max-stream-subscribers 2000 --max-subscribers 8000").
set -euo pipefail
root=$(cd "$(dirname "$0")/../.." && pwd)
bin=${1:-$root/build/bin/roverplan}
idle=${IDLE:-5000}; readers=${READERS:-1000}; seconds=${SECONDS_EACH:-10}; study_readers=${STUDY_READERS:-200}
bench=${BENCH:-$root/build/bin/bench_ws_fanout}  # BENCH: a bench binary built elsewhere
[ -n "${BENCH:-}" ] || ninja -C "$root/build" bench_ws_fanout $([ -z "${1:-}" ] && echo roverplan) >/dev/null
# Every socket is a descriptor on both ends: raise the soft limit to the hard one.
ulimit -n "$(ulimit -Hn)" || true
echo "descriptors: $(ulimit -n); load: $(uptime | sed 's/.*load/load/')"
work=$(mktemp -d)
pid=
start_server() {
  # shellcheck disable=SC2086
  "$bin" serve --port 0 --data "$work/data" --quiet ${EXTRA:-} > "$work/log" 2>&1 &
  pid=$!
  for _ in $(seq 1 300); do
    port=$(sed -n 's|.*http://127.0.0.1:\([0-9]*\)/.*|\1|p' "$work/log" | head -1)
    [ -n "$port" ] && curl -fs "http://127.0.0.1:$port/api/health" >/dev/null 2>&1 && return 0
    sleep 0.1
  done
  echo "the server did not start:"; cat "$work/log"; exit 1
}
stop_server() { kill "$pid" 2>/dev/null || true; wait "$pid" 2>/dev/null || true; rm -rf "$work/data"; }
trap 'stop_server; rm -rf "$work"' EXIT
json() { python3 -c "import json,sys; print(json.load(sys.stdin)$1)"; }
mission() {  # a coverage mission on the default map, 600x600 cells, paced to last ~a minute
  local map
  map=$(curl -fs "http://127.0.0.1:$port/api/maps" | json '[0]["id"]')
  curl -fs "http://127.0.0.1:$port/api/missions" -H 'Content-Type: application/json' -d "{\"map\":\"$map\",\"planner\":\"coverage\",\"pace\":${1},\"rovers\":[{\"x\":20,\"y\":20,\"heading\":0},{\"x\":120,\"y\":120,\"heading\":180}],\"params\":{\"coverage_cell\":0.25,\"coverage\":0.9}}" | json '["id"]'
}

for load in "0 1000" "0 2000" "$idle $readers"; do
  set -- $load
  start_server
  m=$(mission 400)
  sleep 1
  echo "== mission $m (600x600 cells, 2 rovers, pace 400 steps/s): $1 never-reading sockets + $2 readers, ${seconds} s"
  "$bench" health "$port" "$m" "$1" "$2" "$seconds" "$pid"
  stop_server
done

start_server
s=$(curl -fs "http://127.0.0.1:$port/api/studies" -H 'Content-Type: application/json' -d '{"preset":"laine-fig6","runs":50000}' | json '["id"]')
for _ in $(seq 1 100); do
  [ "$(curl -fs "http://127.0.0.1:$port/api/studies" | json '[0]["runs_done"]')" -gt 0 ] && break
  sleep 0.2
done
echo "== study $s (laine-fig6, 200000 runs, in the server): ${seconds} s per phase"
"$bench" study "$port" "$s" "$study_readers" "$seconds"
stop_server

if [ -n "${FRAMES:-}" ]; then
  start_server
  m=$(mission 4000)
  echo "== mission $m: 50 clients read it to its end"
  "$bench" frames "$port" "$m" 50 "$pid"
  stop_server
fi
echo "load: $(uptime | sed 's/.*load/load/')"
