#!/usr/bin/env bash
# Exports a GIS user can use (issue 13): a finished coverage and a team mission on the default map;
# each export is fetched over HTTP and opened with GDAL's own tools — result.geojson and result.csv
# with ogrinfo, map.png and map.tif with gdalinfo — and checked against result.json: features per
# "layer" kind, CSV rows per sample, the map CRS present, the picture's size. Usage:
# exports_test.sh path/to/roverplan
set -u
BIN=$1
TMP=$(mktemp -d "${TMPDIR:-/tmp}/roverplan_exports_test.XXXXXX")
PID=""
cleanup() { [ -n "$PID" ] && kill -9 "$PID" 2>/dev/null; rm -rf "$TMP"; }
trap cleanup EXIT
# KEEP=1: leave the downloads in $TMP to look at (the server is still stopped).
[ -n "${KEEP:-}" ] && trap '[ -n "$PID" ] && kill -9 "$PID"' EXIT
passed=0
fail() { echo "FAIL: $*" >&2; echo "--- server log:" >&2; tail -20 "$TMP/log" >&2; echo "$passed passed, 1 failed"; exit 1; }
pass() { passed=$((passed + 1)); echo "ok: $*"; }
json() { python3 -c "import json,sys; d=json.load(sys.stdin); print($1)"; }
command -v ogrinfo >/dev/null && command -v gdalinfo >/dev/null || { echo "skipped: no ogrinfo/gdalinfo"; exit 77; }

"$BIN" serve --port 0 --data "$TMP/data" --quiet > "$TMP/log" 2>&1 &
PID=$!
for _ in $(seq 1 150); do
  PORT=$(sed -n 's|.*http://127.0.0.1:\([0-9]*\)/.*|\1|p' "$TMP/log" | head -1)
  [ -n "$PORT" ] && curl -fs "http://127.0.0.1:$PORT/api/health" >/dev/null 2>&1 && break
  sleep 0.1
done
[ -n "$PORT" ] || fail "server did not start"
api() { curl -s "http://127.0.0.1:$PORT$1" "${@:2}"; }
MAP=$(api /api/maps | json 'd[0]["id"]')
PDM=$(api "/api/maps/$MAP/pdms" -H 'Content-Type: application/json' -d '{"random":3,"seed":2}' | json 'd["id"]')

launch() {
  api /api/missions -H 'Content-Type: application/json' -d "$1" | json 'd["id"]'
}
wait_ended() {
  for _ in $(seq 1 1200); do
    case "$(api "/api/missions/$1" | json 'd["status"]')" in
      succeeded|completed_with_warnings) return 0 ;;
      failed|cancelled|interrupted) fail "mission $1 ended $(api "/api/missions/$1")" ;;
    esac
    sleep 0.1
  done
  fail "mission $1 did not finish"
}
# A keep-out zone, where the server takes the request field keep_out (a FeatureCollection in the
# local frame); a server without it refuses the field and the coverage mission runs without.
ZONE='"keep_out":{"type":"FeatureCollection","features":[{"type":"Feature","properties":{"name":"rim"},"geometry":{"type":"Polygon","coordinates":[[[130,10],[140,10],[140,20],[130,20],[130,10]]]}}]}'
ZONES=1
code=$(api /api/missions -o /dev/null -w '%{http_code}' -H 'Content-Type: application/json' \
  -d "{\"map\":\"$MAP\",\"planner\":\"coverage\",\"rovers\":[{\"x\":20,\"y\":20,\"heading\":0}],\"params\":{\"coverage\":0.01},$ZONE}")
[ "$code" = 202 ] || { ZONES=0; ZONE='"pace":0'; echo "note: this server does not take keep_out (HTTP $code): no zone exported"; }
COV=$(launch "{\"map\":\"$MAP\",\"planner\":\"coverage\",$ZONE,\"rovers\":[{\"x\":20,\"y\":20,\"heading\":0},{\"x\":120,\"y\":100,\"heading\":180}],\"params\":{\"coverage\":0.3}}")
TEAM=$(launch "{\"map\":\"$MAP\",\"pdm\":\"$PDM\",\"planner\":\"team-search\",\"rovers\":[{\"x\":70,\"y\":70,\"heading\":0},{\"x\":73,\"y\":70,\"heading\":90}],\"params\":{\"targets\":3}}")
wait_ended "$COV"
wait_ended "$TEAM"
pass "a coverage and a team mission finished"

# The map's CRS as gdalinfo names it: every export must carry the same one.
api "/api/maps/$MAP/layers/elevation.tif" -o "$TMP/dem.tif"
CRS_NAME=$(gdalinfo "$TMP/dem.tif" | sed -n 's/^\(PROJCRS\|GEOGCRS\)\["\([^"]*\)".*/\2/p' | head -1)
[ -n "$CRS_NAME" ] || fail "the default map has no CRS name"

for ID in "$COV" "$TEAM"; do
  D="$TMP/$ID"
  mkdir -p "$D"
  for f in result.json result.geojson result.csv map.png map.tif; do
    code=$(api "/api/missions/$ID/$f" -o "$D/$f" -w '%{http_code}')
    [ "$code" = 200 ] || fail "$ID/$f: HTTP $code"
  done
  PLANNER=$(json 'd["planner"]' < "$D/result.json")

  # GeoJSON: one layer "mission"; features per kind as result.json counts them; the map's CRS.
  INFO=$(ogrinfo -ro -al -so "$D/result.geojson" 2>&1) || fail "$ID: ogrinfo cannot read result.geojson: $INFO"
  grep -q '^Layer name: mission' <<<"$INFO" || fail "$ID: GeoJSON layer name: $INFO"
  grep -q "\"$CRS_NAME\"" <<<"$INFO" || fail "$ID: GeoJSON CRS is not the map's ($CRS_NAME): $INFO"
  for kind in track route target incident zone; do
    want=$(python3 -c "
import json; r = json.load(open('$D/result.json'))
n = {'zone': $ZONES if r['planner'] == 'coverage' else 0,
     'track': len(r['rovers']) + sum(1 for x in r['rovers'] if 'believed_path' in x),
     'route': sum(1 for o in r.get('overlays', []) if o['key'] == 'route'),
     'target': len(r.get('targets', [])), 'incident': len(r['incidents'])}
print(n['$kind'])")
    got=$(ogrinfo -ro -al -q -where "layer='$kind'" "$D/result.geojson" | grep -c '^OGRFeature')
    [ "$got" = "$want" ] || fail "$ID ($PLANNER): $got '$kind' features, result.json has $want"
  done
  total=$(sed -n 's/^Feature Count: //p' <<<"$INFO")
  [ "$total" -ge 2 ] || fail "$ID: only $total features"
  if [ "$PLANNER" = team-search ]; then
    ogrinfo -ro -al -q -where "layer='target'" "$D/result.geojson" | grep -Eq 'status \(String\) = (reached|short|skipped|unreachable)' \
      || fail "$ID: targets carry no status"
    ogrinfo -ro -al -q -where "layer='track'" "$D/result.geojson" | grep -q 'duration_s (Real) = ' || fail "$ID: tracks carry no duration"
  fi

  # CSV: ogrinfo reads it; one row per sample (team: every 10 Hz sample; coverage: every point).
  head -1 "$D/result.csv" > "$D/header"
  if [ "$PLANNER" = team-search ]; then
    grep -qx 'rover,time_s,x_m,y_m,easting_m,northing_m,heading_deg,roll_deg,pitch_deg,speed_m_s,elevation_m' "$D/header" \
      || fail "$ID: CSV header $(cat "$D/header")"
    want=$(json 'sum(int(x["metrics"]["samples"]) for x in d["rovers"])' < "$D/result.json")
  else
    grep -qx 'rover,move,x_m,y_m,easting_m,northing_m,heading_deg,roll_deg,pitch_deg,elevation_m' "$D/header" \
      || fail "$ID: CSV header $(cat "$D/header")"
    want=$(json 'sum(len(x["path"]) for x in d["rovers"])' < "$D/result.json")
  fi
  got=$(ogrinfo -ro -al -so "$D/result.csv" | sed -n 's/^Feature Count: //p')
  [ "$got" = "$want" ] || fail "$ID: CSV has $got rows, result.json $want samples"
  # Both frames agree: easting − x_m and northing − y_m are the same offset on every row.
  python3 - "$D/result.csv" <<'PY' || fail "$ID: CSV frames disagree"
import csv, sys
rows = list(csv.DictReader(open(sys.argv[1])))
dx = {round(float(r['easting_m']) - float(r['x_m']), 2) for r in rows}
dy = {round(float(r['northing_m']) - float(r['y_m']), 2) for r in rows}
assert len(dx) == 1 and len(dy) == 1, (dx, dy)
assert all(r['elevation_m'] != '' and r['heading_deg'] != '' for r in rows)
PY

  # map.tif: the mission's values as Float32 bands of the map's extent in its CRS (issue 27:
  # elevation, traversability class, visits; a PDM when the mission had one), each with its
  # description and the nodata value; map.png: the picture with legends below.
  GI=$(gdalinfo "$D/map.tif" 2>&1) || fail "$ID: gdalinfo cannot read map.tif"
  grep -q "\"$CRS_NAME\"" <<<"$GI" || fail "$ID: map.tif CRS is not the map's: $GI"
  grep -q '^Size is 600, 600' <<<"$GI" || fail "$ID: map.tif size: $(grep '^Size' <<<"$GI")"
  grep -q 'Band 1 .*Type=Float32' <<<"$GI" || fail "$ID: map.tif band 1 is not Float32: $GI"
  grep -q 'Description = elevation (m)' <<<"$GI" || fail "$ID: map.tif has no elevation band"
  grep -q 'Description = traversability class' <<<"$GI" || fail "$ID: map.tif has no traversability band"
  grep -q 'Description = visits' <<<"$GI" || fail "$ID: map.tif has no visits band"
  grep -q 'NoData Value=-9999' <<<"$GI" || fail "$ID: map.tif has no nodata value"
  grep -q '^Origin = (' <<<"$GI" || fail "$ID: map.tif has no origin"
  PI=$(gdalinfo "$D/map.png" 2>&1) || fail "$ID: gdalinfo cannot read map.png"
  size=$(sed -n 's/^Size is \([0-9]*\), \([0-9]*\)/\1 \2/p' <<<"$PI")
  set -- $size
  [ "$1" = 600 ] && [ "$2" -gt 640 ] || fail "$ID: map.png is $size (want 600 wide, legends below the 600 rows)"
  pass "$PLANNER $ID: GeoJSON, CSV, map.png and map.tif open in ogrinfo/gdalinfo and match result.json"
done

# An unknown file is a 404.
code=$(api "/api/missions/$COV/map.jpg" -o /dev/null -w '%{http_code}')
[ "$code" = 404 ] || fail "map.jpg: HTTP $code"
pass "unknown export: 404"
echo "$passed passed"
