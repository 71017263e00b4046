#!/usr/bin/env bash
# Every DEM in ../shared/dems through the tile API (issue 24): each is uploaded to a fresh server
# (the PDS3 pair as two files); every tiled layer answers 200 at zoom 0, the native zoom and the
# deepest zoom; at the native zoom every elevation and slope .f32 tile equals its crop of the
# whole-layer .f32 (NaN where the DEM has none, e.g. SRTM voids, and beyond the map), and
# addresses outside the grid are 404. Skipped (77) without ../shared/dems.
# Usage: tiles_dems_test.sh path/to/roverplan path/to/shared/dems
set -u
BIN=$1
DEMS=$2
[ -d "$DEMS" ] || { echo "SKIP: no DEM folder at $DEMS"; exit 77; }
TMP=$(mktemp -d "${TMPDIR:-/tmp}/roverplan_tiles_dems.XXXXXX")
PID=""
cleanup() {
  [ -n "$PID" ] && kill -9 "$PID" 2>/dev/null && wait "$PID" 2>/dev/null
  rm -rf "$TMP"
}
trap cleanup EXIT
fail() { echo "FAIL: $*" >&2; tail -20 "$TMP/log" >&2; exit 1; }

"$BIN" serve --port 0 --data "$TMP/data" --quiet > "$TMP/log" 2>&1 &
PID=$!
# Waits for the server's first answer; the deadline only catches a hang.
deadline=$((SECONDS + 600))
PORT=""
while [ $SECONDS -lt $deadline ]; do
  kill -0 "$PID" 2>/dev/null || fail "the server exited"
  PORT=$(sed -n 's|.*http://127.0.0.1:\([0-9]*\)/.*|\1|p' "$TMP/log" | head -1)
  [ -n "$PORT" ] && curl -fs "http://127.0.0.1:$PORT/api/health" >/dev/null 2>&1 && break
  sleep 0.2
done
S="http://127.0.0.1:$PORT"
upload() {  # name, then curl -F arguments
  local name=$1 code
  shift
  code=$(curl -s -o "$TMP/up.json" -w '%{http_code}' -X POST "$S/api/maps?name=$name" "$@")
  [ "$code" = 201 ] || fail "upload of $name: $code $(cat "$TMP/up.json")"
}
upload lux -F file=@"$DEMS/earth_luxembourg_srtm/elev.tif"
upload gale -F file=@"$DEMS/mars_gale_hirise_1m/missionDEM.tif"
upload kepler_site -F file=@"$DEMS/moon_kepler_rescaled_025m/kepler_site.tif"
upload kepler -F file=@"$DEMS/moon_lola_kepler_crater/kepler.tif"
upload ldem4 -F file=@"$DEMS/moon_lola_ldem4_global/LDEM_4.IMG" -F file=@"$DEMS/moon_lola_ldem4_global/LDEM_4.LBL"
# LDEM_4 with the offset its warning names: heights, only the coarse cell left to say.
upload ldem4h -F file=@"$DEMS/moon_lola_ldem4_global/LDEM_4.IMG" -F file=@"$DEMS/moon_lola_ldem4_global/LDEM_4.LBL" -F vertical_offset=-1737400
# The Kepler site as a file of lunar radii (issue 27's ISIS3 cube): the map says so and names the fix.
upload radii -F file=@"$DEMS/moon_kepler_rescaled_025m/kepler_site.tif" -F vertical_offset=1737400

python3 - "$S" <<'PY' || fail "tile checks"
import json, math, struct, sys, urllib.request, urllib.error
S = sys.argv[1]
def get(path):
    try:
        with urllib.request.urlopen(S + path, timeout=600) as r:
            return r.status, r.read(), r.headers
    except urllib.error.HTTPError as e:
        return e.code, e.read(), e.headers
def floats(b):
    return struct.unpack(f"<{len(b) // 4}f", b)
def same(a, b):
    return (math.isnan(a) and math.isnan(b)) or a == b
failures = 0
# Honest scale (issue 27): what each shared DEM's cells and heights say to a micro-rover planner.
# LDEM_4 really holds lunar radii (its label: OFFSET 1737400, SCALING_FACTOR 0.5).
expected = {"lux": ["coarse_cell"], "gale": [], "kepler_site": [], "kepler": ["coarse_cell"],
            "ldem4": ["coarse_cell", "heights_look_like_radii"], "ldem4h": ["coarse_cell"],
            "radii": ["heights_look_like_radii"]}
for m in json.loads(get("/api/maps")[1]):
    codes = [w["code"] for w in m["warnings"]]
    if m["name"] in expected and codes != expected[m["name"]]:
        print(f"{m['name']}: warnings {codes}, expected {expected[m['name']]}"); failures += 1
    if m["name"] == "radii" and not any("vertical_offset=-1737400" in w["message"] for w in m["warnings"]):
        print(f"radii: the warning does not name the offset: {m['warnings']}"); failures += 1
    if m["name"] in expected:
        print(f"ok: {m['name']} warns {codes or 'nothing'} (cell {m['cell_size_m']:.4g} m, heights {m['elevation']['min']:.0f} to {m['elevation']['max']:.0f} m, {m['body']})")
for m in json.loads(get("/api/maps")[1]):
    if m["name"] not in ("lux", "gale", "kepler_site", "kepler", "ldem4"):
        continue
    mid = m["id"]
    t = json.loads(get(f"/api/maps/{mid}")[1])["tiles"]
    z0, zn, zmax = t["zmin"], t["native_zoom"], t["zmax"]
    for layer in ("elevation", "hillshade", "slope", "traversability"):
        for z in (z0, zn, zmax):
            st, body, _ = get(f"/api/maps/{mid}/tiles/{layer}/{z}/0/0.png")
            if st != 200 or body[:8] != b"\x89PNG\r\n\x1a\n":
                print(f"{m['name']}: {layer} {z}/0/0.png answered {st}"); failures += 1
    checked = 0
    for layer in ("elevation", "slope"):
        st, body, h = get(f"/api/maps/{mid}/layers/{layer}.f32")
        rows, cols = int(h["X-Rows"]), int(h["X-Cols"])
        whole = floats(body)
        nx, ny = t["tile_counts"][zn]
        for ty in range(ny):
            for tx in range(nx):
                st, body, _ = get(f"/api/maps/{mid}/tiles/{layer}/{zn}/{tx}/{ty}.f32")
                tile = floats(body)
                for r in range(256):
                    for c in range(256):
                        R, C = ty * 256 + r, tx * 256 + c
                        want = whole[R * cols + C] if R < rows and C < cols else float("nan")
                        if not same(tile[r * 256 + c], want):
                            print(f"{m['name']}: {layer} tile {zn}/{tx}/{ty} pixel {r},{c}: {tile[r * 256 + c]} != {want}")
                            failures += 1
                            break
                checked += 1
    bad = [get(f"/api/maps/{mid}/tiles/slope/{p}")[0] for p in
           (f"{zmax + 1}/0/0.png", f"{z0}/1/0.png", f"{z0}/0/1.png", "-1/0/0.png", "0/0/0.jpg")]
    if any(code != 404 for code in bad):
        print(f"{m['name']}: outside the grid answered {bad}"); failures += 1
    print(f"ok: {m['name']} ({m['rows']} x {m['cols']} cells): 12 PNG tiles, {checked} native .f32 tiles equal to the whole layer, 5 outside addresses 404")
sys.exit(1 if failures else 0)
PY
kill -0 "$PID" 2>/dev/null || fail "the server exited"
echo "every shared DEM through the tile API"
