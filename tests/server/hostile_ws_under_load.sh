#!/usr/bin/env bash
# The WebSocket tests that once failed under load (issue 22 item 9: a close frame lost to a reset),
# RUNS times in a row (default 20) while `stress-ng --cpu 2` keeps both cores busy (two bounded
# busy loops when stress-ng is missing). Stops at the first failure and says which run.
#   tests/server/hostile_ws_under_load.sh [BUILD_DIR]    env: RUNS
set -euo pipefail
root=$(cd "$(dirname "$0")/../.." && pwd)
build=${1:-$root/build}
runs=${RUNS:-20}
tests='hostile: a WebSocket*,websocket:*,hostile missions: a subscriber that never reads*,mission stream:*'
limit=$((runs * 120))
if command -v stress-ng >/dev/null; then
  stress-ng --cpu 2 --timeout "${limit}s" --quiet &
  load="stress-ng --cpu 2"
else
  timeout "$limit" sh -c 'while :; do :; done' & timeout "$limit" sh -c 'while :; do :; done' &
  load="two busy loops"
fi
trap 'kill $(jobs -p) 2>/dev/null || true; wait 2>/dev/null || true' EXIT
echo "under $load: $(uptime | sed 's/.*load/load/')"
for i in $(seq 1 "$runs"); do
  if ! out=$(timeout 300 "$build/bin/test_server" -tc="$tests" 2>&1); then
    echo "run $i of $runs FAILED:"; echo "$out"; exit 1
  fi
  echo "run $i: $(echo "$out" | grep -E '^\[doctest\] (test cases|assertions)' | tr -s ' ' | paste -sd ' ')"
done
echo "all $runs runs passed under $load; $(uptime | sed 's/.*load/load/')"
