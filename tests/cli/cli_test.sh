#!/usr/bin/env bash
# roverplan as a user runs it: exit statuses, one-line errors on stderr, the --json shape, and the
# files a sweep writes. Usage: cli_test.sh path/to/roverplan
set -u

if [ $# -ne 1 ] || [ ! -x "$1" ]; then
  echo "usage: $0 path/to/roverplan (got '${1:-}')" >&2
  exit 1
fi
BIN=$1
TMP=$(mktemp -d "${TMPDIR:-/tmp}/roverplan_cli_test.XXXXXX") || { echo "FAIL: mktemp" >&2; exit 1; }
trap 'rm -rf "$TMP"' EXIT

passed=0
OUT=$TMP/stdout
ERR=$TMP/stderr
STATUS=0

fail() {
  echo "FAIL: $*" >&2
  echo "--- stdout (first 20 lines):" >&2
  head -n 20 "$OUT" >&2 2>/dev/null
  echo "--- stderr (first 20 lines):" >&2
  head -n 20 "$ERR" >&2 2>/dev/null
  echo "$passed passed, 1 failed"
  exit 1
}
pass() {
  passed=$((passed + 1))
  echo "ok: $*"
}
# run ARGS...: runs roverplan, capturing stdout, stderr and the exit status.
run() {
  "$BIN" "$@" >"$OUT" 2>"$ERR"
  STATUS=$?
}
expect_status() {  # expect_status N DESCRIPTION
  [ "$STATUS" -eq "$1" ] || fail "$2: expected exit status $1, got $STATUS"
}
lines() { wc -l <"$1" | tr -d ' '; }

# --- usage errors -------------------------------------------------------------------------------
run
expect_status 2 "roverplan with no arguments"
grep -q "usage: roverplan" "$OUT" || fail "roverplan with no arguments: no usage text"
pass "no arguments exits 2 with the usage"

run nope
expect_status 2 "roverplan nope"
[ "$(lines "$ERR")" -eq 1 ] || fail "roverplan nope: expected one stderr line, got $(lines "$ERR")"
grep -q "nope" "$ERR" || fail "roverplan nope: stderr does not name the command"
pass "unknown command exits 2 with one stderr line"

run coverage --rows abc
expect_status 2 "roverplan coverage --rows abc"
[ "$(lines "$ERR")" -eq 1 ] || fail "coverage --rows abc: expected one stderr line, got $(lines "$ERR")"
grep -q -- "--rows" "$ERR" || fail "coverage --rows abc: stderr does not name --rows"
[ -s "$OUT" ] && fail "coverage --rows abc: unexpected stdout"
pass "bad --rows exits 2 with one stderr line naming --rows"

run coverage --frobnicate
expect_status 2 "roverplan coverage --frobnicate"
[ "$(lines "$ERR")" -eq 1 ] || fail "coverage --frobnicate: expected one stderr line"
grep -q -- "--frobnicate" "$ERR" || fail "coverage --frobnicate: stderr does not name --frobnicate"
pass "unknown option exits 2 naming it"

run coverage --sense 3
expect_status 2 "roverplan coverage --sense 3"
[ "$(lines "$ERR")" -eq 1 ] || fail "coverage --sense 3: expected one stderr line"
grep -q -- "--sense" "$ERR" || fail "coverage --sense 3: stderr does not name --sense"
pass "out-of-range planner parameter exits 2 naming the option"

# --- help ---------------------------------------------------------------------------------------
run coverage --help
expect_status 0 "roverplan coverage --help"
for opt in --rows --cols --cell --obstacles --seed --rovers --mode --pattern --circumnavigate \
           --frontier --sense --coverage --alpha --beta --max-steps --json; do
  grep -q -- "$opt" "$OUT" || fail "coverage --help does not list $opt"
done
pass "coverage --help exits 0 and lists every option"

# --- coverage -----------------------------------------------------------------------------------
run coverage --json --seed 5 --rovers 2
expect_status 0 "roverplan coverage --json --seed 5 --rovers 2"
[ "$(lines "$OUT")" -eq 1 ] || fail "coverage --json: expected one stdout line, got $(lines "$OUT")"
[ -s "$ERR" ] && fail "coverage --json: unexpected stderr"
python3 -c '
import json, sys
d = json.load(sys.stdin)
m = d["metrics"]
for k in ("coverage", "moves", "makespan", "path_length_ratio", "distance_m", "energy_j",
          "max_pitch_deg", "revisits", "unreachable_cells"):
    assert k in m, "metrics has no " + k
    assert isinstance(m[k], (int, float)), k + " is not a number"
assert 0 < m["coverage"] <= 1, "coverage out of range"
assert len(d["rovers"]) == 2, "expected 2 rovers, got %d" % len(d["rovers"])
for r in d["rovers"]:
    assert len(r["path"]) > 0, "empty path"
    assert all(len(p) == 2 for p in r["path"]), "path point is not [x, y]"
assert "coverage_vs_moves" in d["series"], "no coverage_vs_moves series"
assert d["world"]["seed"] == 5, "seed not echoed"
' <"$OUT" 2>>"$ERR" || fail "coverage --json: JSON check failed"
pass "coverage --json prints one JSON line with metrics, 2 rovers and the curve"

cp "$OUT" "$TMP/first.json"
run coverage --json --seed 5 --rovers 2
expect_status 0 "second roverplan coverage --json --seed 5 --rovers 2"
cmp -s "$OUT" "$TMP/first.json" || fail "coverage --json: same seed gave different output"
pass "coverage --json is deterministic for a seed"

run coverage
expect_status 0 "roverplan coverage"
grep -q "path length ratio" "$OUT" || fail "coverage summary does not mention 'path length ratio'"
pass "coverage prints a readable summary"

# --- sweep --------------------------------------------------------------------------------------
run sweep --preset frontier --runs 4 --out "$TMP/sweep"
expect_status 0 "roverplan sweep --preset frontier --runs 4"
[ -s "$TMP/sweep/summary.json" ] || fail "sweep did not write summary.json"
[ -s "$TMP/sweep/summary.csv" ] || fail "sweep did not write summary.csv"
python3 -c '
import json, sys
d = json.load(open(sys.argv[1]))
assert d["preset"] == "frontier"
assert len(d["rows"]) > 0, "no rows"
assert {r["config"] for r in d["rows"]} == {"spiral", "spiral+frontier"}, "unexpected configs"
' "$TMP/sweep/summary.json" 2>>"$ERR" || fail "sweep: summary.json check failed"
head -n 1 "$TMP/sweep/summary.csv" | grep -q "^config,metric" || fail "sweep: bad summary.csv header"
pass "sweep writes summary.json and summary.csv"

run sweep --preset nope --runs 1
expect_status 2 "roverplan sweep --preset nope"
[ "$(lines "$ERR")" -eq 1 ] || fail "sweep --preset nope: expected one stderr line"
grep -q "nope" "$ERR" || fail "sweep --preset nope: stderr does not name the preset"
pass "unknown sweep preset exits 2"

# --- bench --------------------------------------------------------------------------------------
run bench coverage --runs 4
expect_status 0 "roverplan bench coverage --runs 4"
grep -q "runs/s" "$OUT" || fail "bench coverage: no runs/s column"
[ "$(grep -c "^spiral" "$OUT")" -eq 4 ] || fail "bench coverage: expected 4 measurement lines"
pass "bench coverage prints its figures"

# --- terrain commands ---------------------------------------------------------------------------
run terrain --preset mars --size 64 --cell 0.5 --seed 3 --out "$TMP/t.tif"
expect_status 0 "terrain --preset mars"
[ -s "$TMP/t.tif" ] || fail "terrain: no GeoTIFF written"
pass "terrain writes a GeoTIFF"

run traversability "$TMP/t.tif" --out "$TMP/classes.tif" --json
expect_status 0 "traversability --json"
python3 -c '
import json, sys
d = json.load(open(sys.argv[1]))
for k in ("traversable_pct", "high_risk_pct", "impassable_pct", "nodata_pct", "rows", "cols", "cell_size_m"):
    assert k in d, k
assert d["rows"] == 64 and d["cols"] == 64 and abs(d["cell_size_m"] - 0.5) < 1e-9
total = d["traversable_pct"] + d["high_risk_pct"] + d["impassable_pct"] + d["nodata_pct"]
assert abs(total - 100) < 1e-6, total
' "$OUT" || fail "traversability --json: bad JSON"
[ -s "$TMP/classes.tif" ] || fail "traversability --out: no classes GeoTIFF"
pass "traversability prints the class shares and writes the classes"

# A DEM whose georeferencing is not a place (issue 22): a NaN pixel size and a latitude of 95° are
# one line naming the geotransform's part and exit status 2, as an upload is a 400 naming it.
if command -v gdal_translate >/dev/null && command -v gdal_edit.py >/dev/null; then
  cp "$TMP/t.tif" "$TMP/nan.tif" && gdal_edit.py -a_ullr 0 nan 100 0 "$TMP/nan.tif"
  run traversability "$TMP/nan.tif" --json
  expect_status 2 "traversability on a NaN geotransform"
  [ "$(lines "$ERR")" -eq 1 ] || fail "NaN geotransform: expected one stderr line, got $(lines "$ERR")"
  grep -q "pixel_height is nan" "$ERR" || fail "NaN geotransform: the message does not name pixel_height"
  gdal_translate -q -a_srs EPSG:4326 -a_ullr 10 95 10.01 94.99 "$TMP/t.tif" "$TMP/lat95.tif"
  run traversability "$TMP/lat95.tif" --json
  expect_status 2 "traversability at latitude 95"
  grep -q "latitude of 95° is outside \[-90, 90\]°" "$ERR" || fail "latitude 95: not named"
  pass "a NaN pixel size or latitude 95 is one line and exit status 2"
else
  echo "skip: gdal_translate/gdal_edit.py not found (Debian gdal-bin)"
fi

# The DEM import options the upload route shares (maps/dem_import_options): a pixel window, a
# body, and bad values naming their option.
run traversability "$TMP/t.tif" --crop-px 8,4,32,16 --vertical-scale 2 --json
expect_status 0 "traversability --crop-px"
python3 -c '
import json, sys
d = json.load(open(sys.argv[1]))
assert d["rows"] == 16 and d["cols"] == 32, (d["rows"], d["cols"])
' "$OUT" || fail "traversability --crop-px: not a 32 x 16 window"
run coverage --dem "$TMP/t.tif" --body moon --coverage 0.2 --json
expect_status 0 "coverage --dem --body moon"
python3 -c '
import json, sys
d = json.load(open(sys.argv[1]))
assert d["world"]["body"] == "moon", d["world"]
assert abs(d["metrics"]["gravity_m_s2"] - 1.62) < 1e-9, d["metrics"]["gravity_m_s2"]
' "$OUT" || fail "coverage --body moon: not planned on the Moon"
for bad in "--crop-px 0,0,100,10" "--crop-px 1,2,3" "--crop 1,2,3,4 --crop-px 1,2,3,4" "--body pluto" "--vertical-scale 0"; do
  # shellcheck disable=SC2086
  run traversability "$TMP/t.tif" $bad
  expect_status 2 "traversability $bad"
  [ "$(lines "$ERR")" -eq 1 ] || fail "traversability $bad: expected one stderr line"
done
grep -q -- "--vertical-scale" "$ERR" || fail "--vertical-scale 0: stderr does not name the option"
pass "DEM import options: a pixel window, a declared body, bad values exit 2"

printf 'not a raster\n' > "$TMP/notes.txt"
for bad in "$TMP/notes.txt" "$TMP/missing.tif"; do
  run traversability "$bad"
  expect_status 2 "traversability $bad"
  [ "$(lines "$ERR")" -eq 1 ] || fail "traversability $bad: expected one stderr line"
  grep -q -- "$bad" "$ERR" || fail "traversability $bad: stderr does not name the file"
done
pass "bad DEM files exit 2 with one line naming the file"

run slope "$TMP/t.tif" --out "$TMP/slope.tif"
expect_status 0 "slope"
[ -s "$TMP/slope.tif" ] || fail "slope: no GeoTIFF"
pass "slope writes a GeoTIFF"

run pdm "$TMP/t.tif" --random 4 --seed 2 --out "$TMP/pdm.tif"
expect_status 0 "pdm --random 4"
grep -q "total mass 1" "$OUT" || fail "pdm: mass does not sum to 1"
pass "pdm writes a normalised PDM"

run render slope "$TMP/t.tif" --out "$TMP/slope.png"
expect_status 0 "render slope"
head -c 8 "$TMP/slope.png" | od -An -c | grep -q "P   N   G" || fail "render: not a PNG"
pass "render writes a PNG"

run coverage --dem "$TMP/t.tif" --coverage-cell 1 --start 5,5,0 --json --geojson "$TMP/paths.geojson"
expect_status 0 "coverage --dem"
if command -v ogrinfo >/dev/null; then
  ogrinfo -ro -al -so "$TMP/paths.geojson" >/dev/null 2>&1 || fail "coverage --geojson: ogrinfo cannot read it"
fi
python3 -c '
import json, sys
d = json.load(open(sys.argv[1]))
assert d["world"]["rows"] == 32, d["world"]
assert d["metrics"]["coverage"] > 0
' "$OUT" || fail "coverage --dem: bad JSON"
pass "coverage on a DEM"

# On a DEM the frontier stop is the default; --no-frontier gives paper 002's rule back.
python3 -c '
import json, sys
d = json.load(open(sys.argv[1]))
assert d["assumptions"]["stop_rule"].startswith("frontier"), d["assumptions"]
' "$OUT" || fail "coverage --dem: not the frontier stop by default"
run coverage --dem "$TMP/t.tif" --coverage-cell 1 --start 5,5,0 --no-frontier --json
expect_status 0 "coverage --dem --no-frontier"
python3 -c '
import json, sys
d = json.load(open(sys.argv[1]))
assert d["assumptions"]["stop_rule"].startswith("paper"), d["assumptions"]
' "$OUT" || fail "coverage --no-frontier: not the paper stop rule"
run coverage --dem "$TMP/t.tif" --frontier --no-frontier
expect_status 2 "coverage --frontier --no-frontier"
pass "frontier is the default on a DEM; --no-frontier turns it off; both at once exit 2"

run coverage --dem "$TMP/t.tif" --start 999,5,0
expect_status 2 "coverage --dem with a start outside the map"
grep -q -- "--start" "$ERR" || fail "coverage --start outside: stderr does not name --start"
pass "a start outside the DEM exits 2 naming --start"

# Team mission (paper 001): metrics keys, determinism, GeoJSON, errors.
run mission --dem "$TMP/t.tif" --random-pdm 4 --rovers 3 --targets 4 --seed 3 --json --geojson "$TMP/team.geojson"
expect_status 0 "mission --json"
cp "$OUT" "$TMP/mission1.json"
python3 -c '
import json, sys
d = json.load(open(sys.argv[1]))
m = d["metrics"]
for k in ["mean_trajectory_m", "mission_time_s", "samples", "exceedances", "exceedance_fraction",
          "collisions", "min_separation_m", "accumulated_probability", "targets_reached",
          "targets_skipped", "plan_wall_s"]:
    assert k in m, k
assert m["collisions"] == 0, m
assert len(d["rovers"]) == 3
assert d["overlays"][0]["key"] == "route" and len(d["overlays"][0]["points"]) == 5
' "$OUT" || fail "mission --json: bad JSON"
if command -v ogrinfo >/dev/null; then
  ogrinfo -ro -al -so "$TMP/team.geojson" >/dev/null 2>&1 || fail "mission --geojson: ogrinfo cannot read it"
fi
run mission --dem "$TMP/t.tif" --random-pdm 4 --rovers 3 --targets 4 --seed 3 --json
python3 -c '
import json, sys
a, b = (json.load(open(p)) for p in sys.argv[1:3])
for d in (a, b): d["metrics"].pop("plan_wall_s")
assert a["metrics"] == b["metrics"] and a["rovers"] == b["rovers"], "not reproducible"
' "$TMP/mission1.json" "$OUT" || fail "mission: the same seed gave another result"
pass "mission --json reports the metrics, reproducibly"

run mission --dem "$TMP/t.tif" --planner hybrid --rovers 2 --targets 2
expect_status 0 "mission --planner hybrid"
grep -q "^team " "$OUT" || fail "mission: no summary"
pass "hybrid mission prints a summary"

run mission --random-pdm 4
expect_status 2 "mission without --dem"
grep -q -- "--dem" "$ERR" || fail "mission without --dem: stderr does not name --dem"
run mission --dem "$TMP/t.tif" --targets 0
expect_status 2 "mission --targets 0"
grep -q -- "--targets" "$ERR" || fail "mission --targets 0: stderr does not name --targets"
run mission --dem "$TMP/t.tif" --start "999,5,0"
expect_status 2 "mission with a start off the map"
grep -q -- "--start" "$ERR" || fail "mission --start off the map: stderr does not name --start"
run mission --dem "$TMP/t.tif" --random-pdm 4 --pdm "$TMP/nope.json"
expect_status 2 "mission with two PDM sources"
pass "mission errors exit 2 naming the option"

# Keep-out zones (issue 13): a 60 x 60 random world, a wall x 20..30 m across all but the top
# 10 m; the coverage path never enters it; a bad file is one line naming the option.
cat >"$TMP/zones.geojson" <<'JSON'
{"type": "FeatureCollection", "features": [{"type": "Feature", "properties": {},
 "geometry": {"type": "Polygon", "coordinates": [[[20, -1], [30, -1], [30, 50], [20, 50], [20, -1]]]}}]}
JSON
run coverage --seed 3 --start "5.5,5.5,0" --frontier --keep-out "$TMP/zones.geojson" --json
expect_status 0 "coverage --keep-out"
python3 -c '
import json, sys
j = json.load(open(sys.argv[1]))
pts = [p for r in j["rovers"] for p in r["path"]]
inside = [p for p in pts if 20 < p[0] < 30 and p[1] < 50]
assert not inside, inside[:3]
assert any(p[0] > 30 for p in pts), "never went round the zone"
assert j["metrics"]["keep_out_cells"] >= 400, j["metrics"]["keep_out_cells"]
' "$OUT" || fail "coverage --keep-out: a path point inside the zone"
echo '{"type": "FeatureCollection", "features": [{"type": "Feature", "geometry": {"type": "Polygon", "coordinates": [[[1, 1], [2, 2], [3, 1]]]}}]}' >"$TMP/open.geojson"
run coverage --keep-out "$TMP/open.geojson"
expect_status 2 "coverage with an open ring"
[ "$(lines "$ERR")" -eq 1 ] && grep -q -- "--keep-out" "$ERR" && grep -q "geometry.coordinates" "$ERR" || fail "coverage --keep-out bad file: stderr"
# t.tif is 32 x 32 m: a zone x 22..26 east of the formation at the centre.
echo '{"type": "FeatureCollection", "features": [{"type": "Feature", "geometry": {"type": "Polygon", "coordinates": [[[22, 2], [26, 2], [26, 30], [22, 30], [22, 2]]]}}]}' >"$TMP/small.geojson"
run mission --dem "$TMP/t.tif" --rovers 2 --targets 2 --keep-out "$TMP/small.geojson"
expect_status 0 "mission --keep-out"
grep -q "^keep-out " "$OUT" || fail "mission --keep-out: no keep-out line in the summary"
pass "coverage and mission keep out of --keep-out zones; a bad file exits 2 naming it"

# Mission area (issue 24): --area plans in that rectangle at the DEM's resolution, reading only its
# window (+ 4 cells); everything printed is in the whole DEM's frame. m.tif: 200 x 200 cells of
# 0.5 m; the area 40 x 40 m (a team needs room to leave its formation: 10 safety distances).
run terrain --preset mars --size 200 --cell 0.5 --seed 3 --out "$TMP/m.tif"
expect_status 0 "terrain m.tif"
run mission --dem "$TMP/m.tif" --area 30,25,70,65 --rovers 2 --targets 3 --seed 3 --json
expect_status 0 "mission --area"
python3 -c '
import json, sys
d = json.load(open(sys.argv[1]))
assert d["area"] == {"bbox": [30, 25, 70, 65]}, d["area"]
w = d["planning_window"]
near = lambda a, b: abs(a - b) < 1e-6
assert near(w["origin"][0], 28) and near(w["origin"][1], 23), w
assert w["cols"] == 88 and w["rows"] == 88 and w["col0"] == 56 and w["row0"] == 66, w
assert d["map"]["rows"] == 200 and d["map"]["cols"] == 200, d["map"]
n = 0
for r in d["rovers"]:
    for x, y in r["path"]:
        assert 30 <= x <= 70 and 25 <= y <= 65, (x, y)
        n += 1
for s in d["starts"]:
    assert 30 <= s["x"] <= 70 and 25 <= s["y"] <= 65, s
for t in d["targets"]:
    assert 30 <= t["x"] <= 70 and 25 <= t["y"] <= 65, t
assert n > 10, n
# no PDM: uniform over the area; only search cells across its edge count as keep-out
assert d["metrics"]["keep_out_probability"] < 0.1, d["metrics"]["keep_out_probability"]
' "$OUT" || fail "mission --area: a point outside the area, or a bad window"
run coverage --dem "$TMP/t.tif" --area 4,4,12,12 --seed 2 --json
expect_status 0 "coverage --area"
python3 -c '
import json, sys
d = json.load(open(sys.argv[1]))
o = d["planning_window"]["origin"]
assert abs(o[0] - 2) < 1e-6 and abs(o[1] - 2) < 1e-6, o
assert d["world"]["dem_rows"] == 64
for r in d["rovers"]:
    for x, y in r["path"]:
        assert 4 <= x <= 12 and 4 <= y <= 12, (x, y)
' "$OUT" || fail "coverage --area: a point outside the area"
run mission --dem "$TMP/m.tif" --area 30,25,170,65
expect_status 2 "mission --area off the map"
[ "$(lines "$ERR")" -eq 1 ] && grep -q -- "--area" "$ERR" && grep -q "off the map" "$ERR" || fail "mission --area off the map: stderr"
run mission --dem "$TMP/m.tif" --area 30,25,70
expect_status 2 "mission --area with 3 numbers"
grep -q -- "--area" "$ERR" || fail "mission --area 3 numbers: stderr does not name --area"
run mission --dem "$TMP/m.tif" --area 30,25,70,65 --cell 1
expect_status 2 "mission --area with --cell"
grep -q -- "--area" "$ERR" || fail "mission --area --cell: stderr does not name --area"
run coverage --area 4,4,12,12
expect_status 2 "coverage --area without --dem"
pass "mission and coverage --area plan inside the area and report in the DEM's frame; bad areas exit 2"

echo "$passed passed, 0 failed"
exit 0
