#!/usr/bin/env bash
# Benchmark (issue 24, "planning cost follows the map, not the mission"): the same team mission
# (5 rovers, 64 targets, the same starts, PDM components and seed) planned
#   - in a 600 × 600 m mission area (--area) of a generated 7000² DEM of 1 m cells (49 M cells), and
#   - on that area cut out as its own 600² map (gdal_translate -srcwin),
# printing each run's wall time and peak RSS (/usr/bin/time -v) side by side and their ratio. The
# target: the area mission within 1.3× the cut-out's time. BENCH_WHOLE=1 also plans the big map
# whole (no area: its lattice and floods cover all 49 M cells; minutes and GBs). Temporary files go
# to a folder under /tmp, deleted on exit (the 7000² DEM is ~100 MB). BENCH_SIZE=20000x15000 makes
# the big map 20000 × 15000 (300 M cells, the map limit, as big_map.py's): a 10000 × 7500 terrain
# of 2 m cells resampled (cubic) to 1 m, written tiled with ZSTD (~1.2 GB, minutes to make), with
# the area at its centre (issue 24's second figure: within 1.5× the cut-out). CPU seconds (user +
# sys) are printed beside the wall: on a shared machine they compare where the wall does not.
#   [BENCH_SIZE=N|WxH] [BENCH_WHOLE=1] tests/bench/mission_area.sh [ROVERPLAN]
set -euo pipefail
root=$(cd "$(dirname "$0")/../.." && pwd)
roverplan=$(realpath "${1:-$root/build/bin/roverplan}")
[ -x /usr/bin/time ] || { echo "/usr/bin/time not found (Debian time)" >&2; exit 2; }
command -v gdal_translate >/dev/null || { echo "gdal_translate not found (gdal-bin)" >&2; exit 2; }
work=$(mktemp -d /tmp/roverplan_mission_area.XXXXXX)
trap 'rm -rf "$work"' EXIT

size=${BENCH_SIZE:-7000}   # cells of the big map (N for N × N, or W×H), 1 m each
cols=${size%x*} rows=${size#*x}
side=600   # the area: x x0..x0+side, y y0..y0+side (local metres of the big map), near its centre
x0=$((cols / 2 - 300)) y0=$((rows / 2 - 300))
# The cut-out's pixel window: columns from the west, rows from the north.
col0=$x0 row0=$((rows - y0 - side))

if [ "$cols" = "$rows" ]; then
  "$roverplan" terrain --preset mars --size "$size" --cell 1 --seed 7 --out "$work/big.tif" >/dev/null
else  # the terrain generator makes squares of at most 16384: a coarser one, resampled
  half=$(((cols > rows ? cols : rows) / 2))
  "$roverplan" terrain --preset mars --size "$half" --cell 2 --seed 7 --out "$work/coarse.tif" >/dev/null
  gdal_translate -q -srcwin 0 0 $((cols / 2)) $((rows / 2)) -outsize "$cols" "$rows" -r cubic \
    -co TILED=YES -co COMPRESS=ZSTD -co BIGTIFF=YES "$work/coarse.tif" "$work/big.tif"
  rm "$work/coarse.tif"
fi
gdal_translate -q -srcwin "$col0" "$row0" "$side" "$side" "$work/big.tif" "$work/cut.tif"

# The mission in the cut-out's own frame (its lower-left corner at 0, 0): five rovers in a row near
# the area's centre, three Gaussian components; the big map's is the same moved by (x0, y0).
starts() {  # starts DX DY
  local out="" k
  for k in 0 1 2 3 4; do out+="$(($1 + 290 + 3 * k)).5,$(($2 + 300)).5,90;"; done
  echo "${out%;}"
}
pdm() {  # pdm DX DY FILE
  cat >"$3" <<EOF
{"components": [
  {"x": $(($1 + 250)), "y": $(($2 + 340)), "sigma_x": 40, "sigma_y": 25, "rotation_deg": 30, "weight": 1},
  {"x": $(($1 + 380)), "y": $(($2 + 260)), "sigma_x": 30, "sigma_y": 30, "rotation_deg": 0, "weight": 1},
  {"x": $(($1 + 300)), "y": $(($2 + 420)), "sigma_x": 60, "sigma_y": 20, "rotation_deg": -20, "weight": 0.5}]}
EOF
}
pdm 0 0 "$work/pdm-cut.json"
pdm "$x0" "$y0" "$work/pdm-big.json"

# run NAME ARGS...: one mission under /usr/bin/time -v; NAME.json (result) and NAME.time.
run() {
  local name=$1
  shift
  if ! /usr/bin/time -v -o "$work/$name.time" "$roverplan" mission --targets 64 --seed 1 --json "$@" \
       >"$work/$name.json" 2>"$work/$name.err"; then
    echo "$name: roverplan failed: $(head -c 300 "$work/$name.err")" >&2
    exit 1
  fi
}
run cut --dem "$work/cut.tif" --start "$(starts 0 0)" --pdm "$work/pdm-cut.json"
run area --dem "$work/big.tif" --area "$x0,$y0,$((x0 + side)),$((y0 + side))" --start "$(starts "$x0" "$y0")" \
    --pdm "$work/pdm-big.json"
names=(cut area)
if [ "${BENCH_WHOLE:-0}" = 1 ]; then
  run whole --dem "$work/big.tif" --start "$(starts "$x0" "$y0")" --pdm "$work/pdm-big.json"
  names+=(whole)
fi

python3 - "$work" "$size" "${names[@]}" <<'EOF'
import json, re, sys
work, size, names = sys.argv[1], sys.argv[2], sys.argv[3:]
big = size.replace("x", " × ") if "x" in size else f"{size}²"
label = {"cut": "600² cut-out map", "area": f"--area in the {big} map", "whole": f"{big} map, no area"}
def timing(name):
    t = open(f"{work}/{name}.time").read()
    wall = re.search(r"Elapsed \(wall clock\) time.*: (.*)", t).group(1).strip()
    secs = 0.0
    for part in wall.split(":"):
        secs = secs * 60 + float(part)
    rss = int(re.search(r"Maximum resident set size \(kbytes\): (\d+)", t).group(1)) / 1024
    cpu = float(re.search(r"User time \(seconds\): ([\d.]+)", t).group(1)) + \
        float(re.search(r"System time \(seconds\): ([\d.]+)", t).group(1))
    return secs, rss, cpu
rows = {}
print("%-26s %9s %9s %10s %9s %9s %9s %10s %6s" % ("run", "wall s", "cpu s", "peak MiB", "plan s", "reached",
                                                   "skipped", "mean m", "coll"))
for n in names:
    r = json.load(open(f"{work}/{n}.json"))
    m = r["metrics"]
    wall, rss, cpu = timing(n)
    rows[n] = (wall, rss, cpu)
    print("%-26s %9.2f %9.2f %10.0f %9.2f %9d %9d %10.1f %6d" % (label[n], wall, cpu, rss, m["plan_wall_s"], m["targets_reached"],
          m["targets_skipped"], m["mean_trajectory_m"], m["collisions"]))
    if n == "area":
        w = r["planning_window"]
        print("%-26s window %d x %d cells at (%g, %g) m" % ("", w["cols"], w["rows"], w["origin"][0], w["origin"][1]))
(cw, cr, cc), (aw, ar, ac) = rows["cut"], rows["area"]
target = "1.3x" if "x" not in size and int(size) <= 7000 else "1.5x"
print("area / cut-out: wall %.2fx, cpu %.2fx, peak RSS %.2fx (target: wall <= %s)" % (aw / cw, ac / cc, ar / cr, target))
if "whole" in rows:
    ww, wr, wc = rows["whole"]
    print("whole / cut-out: wall %.2fx, cpu %.2fx, peak RSS %.2fx" % (ww / cw, wc / cc, wr / cr))
EOF
