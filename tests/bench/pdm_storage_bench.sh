#!/usr/bin/env bash
# PDM storage on a big map (issue 22), printed, never asserted: a sparse SIDE x SIDE GeoTIFF (a few
# KB; default 7000, a 49 M-cell map of 1 m cells) is uploaded, a {"random": 3} PDM made on it, and
# for each binary given: the bytes the PDM takes in the data dir, the time to make it, to launch a
# team-search mission with it (the POST builds the PDM's mass to validate) and to render its PNG overview.
# Usage: tests/bench/pdm_storage_bench.sh path/to/roverplan [path/to/older/roverplan] (env: SIDE)
set -euo pipefail
SIDE=${SIDE:-7000}
TMP=$(mktemp -d)
PID=""
cleanup() { [ -n "$PID" ] && kill "$PID" 2>/dev/null; wait 2>/dev/null; rm -rf "$TMP"; }
trap cleanup EXIT
echo "load: $(uptime)"
gdal_create -q -of GTiff -outsize "$SIDE" "$SIDE" -bands 1 -ot Float32 -co SPARSE_OK=TRUE -co TILED=YES \
  -co COMPRESS=DEFLATE -a_srs "+proj=eqc +R=3396190 +units=m +no_defs" -a_ullr 0 "$SIDE" "$SIDE" 0 "$TMP/big.tif"
echo "map: $SIDE x $SIDE cells from a $(stat -c %s "$TMP/big.tif")-byte sparse GeoTIFF"
now() { date +%s.%N; }
since() { python3 -c "print(f'{$(now) - $1:.2f}')"; }
j() { python3 -c "import json,sys; d=json.load(sys.stdin); print($1)"; }

run() {
  local bin=$1 label=$2 d="$TMP/data-$2"
  "$bin" serve --data "$d" --port 0 --quiet > "$TMP/log" 2>&1 &
  PID=$!
  local port=""
  for _ in $(seq 1 600); do
    port=$(sed -n 's|.*http://127.0.0.1:\([0-9]*\)/.*|\1|p' "$TMP/log" | head -1)
    [ -n "$port" ] && break
    sleep 0.1
  done
  local api="http://127.0.0.1:$port"
  local t map pdm bytes make mission render id
  t=$(now)
  map=$(curl -sf "$api/api/maps?filename=big.tif&name=big" -H 'Content-Type: image/tiff' --data-binary @"$TMP/big.tif" | j 'd["id"]')
  echo "$label: map imported in $(since "$t") s"
  t=$(now)
  pdm=$(curl -sf "$api/api/maps/$map/pdms" -H 'Content-Type: application/json' -d '{"random":3,"seed":1}' | j 'd["id"]')
  make=$(since "$t")
  bytes=$(du -sb "$d/pdms/$pdm" | cut -f1)
  # The launch validates by building what the planner plans on (the map and the PDM's mass), so
  # its latency is what the PDM's storage costs a mission; the planning after it is the same for
  # both and is cancelled.
  t=$(now)
  id=$(curl -sf "$api/api/missions" -H 'Content-Type: application/json' -d "{\"map\":\"$map\",\"pdm\":\"$pdm\",\"planner\":\"team-search\",\"rovers\":[{\"x\":3500.5,\"y\":3500.5,\"heading\":0}],\"params\":{\"targets\":1,\"route\":\"lhc\"}}" | j 'd["id"]')
  mission=$(since "$t")
  curl -sf -o /dev/null -X DELETE "$api/api/missions/$id"
  t=$(now)
  curl -sf -o /dev/null "$api/api/maps/$map/layers/pdm.png?max=1024&pdm=$pdm"
  render=$(since "$t")
  echo "$label: PDM stored in $bytes bytes, made in $make s; a team-search mission on it launched (202) in $mission s; PNG overview: $render s"
  kill -9 "$PID"; wait "$PID" 2>/dev/null || true; PID=""
  rm -rf "$d"
}

[ -n "${2:-}" ] && run "$2" before
run "$1" after
echo "load: $(uptime)"
