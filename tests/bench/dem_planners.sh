#!/usr/bin/env bash
# Benchmark (issue 23): how long the planners take on the real DEMs of ../shared/dems, the figure
# tests/maps/test_team_dems.cpp and test_coverage_dems.cpp used to time themselves (tests assert
# results, not times). Each case is `roverplan` as a whole process (read, plan, result JSON), the
# settings of those tests: team-search and hybrid with 3 rovers and 4 targets (seed 3), the
# footprint raised to 8 pixels (at most 1 km) on orbital rasters; coverage with the frontier on.
# Prints wall seconds and peak memory per case; a case the planner refuses is shown as such.
#   tests/bench/dem_planners.sh [ROVERPLAN]
# ROVER_SHARED_DEMS names the DEM folder (default ../shared/dems beside the checkout).
set -euo pipefail
root=$(cd "$(dirname "$0")/../.." && pwd)
roverplan=$(realpath "${1:-$root/build/bin/roverplan}")
dems=${ROVER_SHARED_DEMS:-$root/../shared/dems}
[ -x /usr/bin/time ] || { echo "/usr/bin/time not found (Debian time)" >&2; exit 2; }
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT

# case NAME ARGS...: one timed run; prints the wall time and peak memory, or the refusal.
case_() {
  local name=$1
  shift
  if /usr/bin/time -f '%e %M' -o "$work/t" "$roverplan" "$@" --json >/dev/null 2>"$work/err"; then
    read -r s kib <"$work/t"
    printf '%-58s %8.2f %10.0f\n' "$name" "$s" "$((kib / 1024))"
  else
    printf '%-58s %8s %10s  %s\n' "$name" "-" "-" "$(grep -v '^Command exited' "$work/err" | head -c 60)"
  fi
}

printf '%-58s %8s %10s\n' "case" "wall s" "peak MiB"
for file in mars_gale_hirise_1m/missionDEM.tif moon_kepler_rescaled_025m/kepler_site.tif \
            moon_lola_kepler_crater/kepler.tif moon_lola_ldem4_global/LDEM_4.IMG earth_luxembourg_srtm/elev.tif; do
  dem=$dems/$file
  if [ ! -f "$dem" ]; then
    echo "SKIPPED $file: absent"
    continue
  fi
  # The larger side of a pixel in metres, as the planners see it.
  pixel=$("$roverplan" traversability "$dem" --json |
          python3 -c 'import json, sys; t = json.load(sys.stdin); print(max(t["cell_size_m"], t["cell_height_m"]))')
  footprint=()
  if awk -v p="$pixel" 'BEGIN { exit !(p > 5) }'; then
    fp=$(awk -v p="$pixel" 'BEGIN { f = 8 * p; print (f > 1000 ? 1000 : f) }')
    if awk -v p="$pixel" -v f="$fp" 'BEGIN { exit !(f < p) }'; then
      echo "SKIPPED $file team planners: pixels of $pixel m, larger than any team footprint"
      case_ "$file coverage" coverage --dem "$dem" --frontier
      continue
    fi
    footprint=(--footprint-m "$fp")
  fi
  for planner in team-search hybrid; do
    case_ "$file $planner" mission --dem "$dem" --planner "$planner" --rovers 3 --targets 4 \
      --random-pdm 4 --pdm-seed 3 --seed 3 "${footprint[@]}"
  done
  case_ "$file coverage" coverage --dem "$dem" --frontier
done
