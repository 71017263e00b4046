#!/usr/bin/env bash
# Fan-out benchmark (issue: server): 50 WebSocket clients on one coverage mission (600×600 cells,
# paced so it lasts a few seconds); frames per second delivered and server memory.
#   tests/bench/ws_fanout.sh [CLIENTS] [PACE]
set -euo pipefail
clients=${1:-50}; pace=${2:-4000}
root=$(cd "$(dirname "$0")/../.." && pwd)
ninja -C "$root/build" roverplan bench_ws_fanout >/dev/null
work=$(mktemp -d)
"$root/build/bin/roverplan" serve --port 0 --data "$work/data" --quiet > "$work/log" 2>&1 &
pid=$!
trap 'kill $pid 2>/dev/null; wait 2>/dev/null; rm -rf "$work"' EXIT
for _ in $(seq 1 150); do
  port=$(sed -n 's|.*http://127.0.0.1:\([0-9]*\)/.*|\1|p' "$work/log" | head -1)
  [ -n "$port" ] && curl -fs "http://127.0.0.1:$port/api/health" >/dev/null 2>&1 && break
  sleep 0.1
done
map=$(curl -fs "http://127.0.0.1:$port/api/maps" | python3 -c 'import json,sys; print(json.load(sys.stdin)[0]["id"])')
echo "server idle RSS: $(awk '/VmRSS/ {print $2/1024 " MiB"}' /proc/$pid/status)"
mission=$(curl -fs "http://127.0.0.1:$port/api/missions" -H 'Content-Type: application/json' -d "{\"map\":\"$map\",\"planner\":\"coverage\",\"pace\":$pace,\"rovers\":[{\"x\":20,\"y\":20,\"heading\":0},{\"x\":120,\"y\":120,\"heading\":180}],\"params\":{\"coverage_cell\":0.25,\"coverage\":0.3}}" | python3 -c 'import json,sys; print(json.load(sys.stdin)["id"])')
echo "mission $mission: 600x600 coverage cells, 2 rovers, pace $pace steps/s, $clients clients"
"$root/build/bin/bench_ws_fanout" "$port" "$mission" "$clients" "$pid"
