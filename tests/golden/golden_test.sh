#!/usr/bin/env bash
# Golden results (issue 23): every planner with fixed seeds, on the default map, a random grid
# world and the HiRISE Gale and Kepler rover sites of ../shared/dems, must print byte-identical
# result JSON (`--json`: metrics, trajectories, curves, incidents; no timings) before and after a
# refactor. The SHA-256 of each result is kept in results.sha256 beside this script. Timings are
# not results: the team planners' `plan_wall_s` metric is blanked before hashing.
#   golden_test.sh ROVERPLAN_BIN            check every case against results.sha256
#   golden_test.sh ROVERPLAN_BIN --update   write results.sha256 anew (only for a change of results
#                                           that is meant, said in the commit message)
# ROVER_SHARED_DEMS names the DEM folder (default ../shared/dems beside the checkout); cases on an
# absent DEM are reported as skipped, never passed silently.
set -euo pipefail
bin=$(realpath "$1")
mode=${2:-check}
here=$(cd "$(dirname "$0")" && pwd)
dems=${ROVER_SHARED_DEMS:-$here/../../../shared/dems}
golden=$here/results.sha256
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
cd "$tmp"

"$bin" terrain --out default.tif >/dev/null
# The result JSON names the DEM as given: the shared DEMs are linked under fixed names here, so
# the hashes do not depend on where the checkout is.
gale=gale.tif
kepler=kepler_site.tif
[ -f "$dems/mars_gale_hirise_1m/missionDEM.tif" ] && ln -s "$dems/mars_gale_hirise_1m/missionDEM.tif" "$gale"
[ -f "$dems/moon_kepler_rescaled_025m/kepler_site.tif" ] && ln -s "$dems/moon_kepler_rescaled_025m/kepler_site.tif" "$kepler"

: >actual.sha256
skipped=0
# case NAME DEM|- ARGS...: runs `roverplan ARGS --json`, records the hash of its output.
case_() {
  local name=$1 dem=$2
  shift 2
  if [ "$dem" != - ] && [ ! -f "$dem" ]; then
    echo "SKIPPED $name: $dem absent"
    skipped=$((skipped + 1))
    return
  fi
  "$bin" "$@" --json | python3 -c 'import re, sys
sys.stdout.write(re.sub(r"\"plan_wall_s\":[^,}]*", "\"plan_wall_s\":null", sys.stdin.read()))' >"$name.json"
  echo "$(sha256sum <"$name.json" | cut -d' ' -f1)  $name" >>actual.sha256
}

# Coverage (papers 002/000, SPEC §1-2): random worlds, one and three rovers, overlap and Voronoi.
case_ cov-grid-1 - coverage --seed 7
case_ cov-grid-3-voronoi - coverage --seed 7 --rovers 3 --mode voronoi --circumnavigate
case_ cov-grid-frontier - coverage --seed 11 --rovers 2 --frontier --sense 2 --pattern boustrophedon
case_ cov-grid-localisation - coverage --seed 5 --rovers 2 --odometry-noise 2 --heading-noise 1 \
  --slip-per-deg 0.5 --loop-closure --noise-seed 9
# Coverage on the default map (SPEC §2: β, energy, pitch).
case_ cov-default-overlap - coverage --dem default.tif --seed 2 --rovers 3 --alpha 0.6 --beta 0.4
case_ cov-default-voronoi - coverage --dem default.tif --seed 2 --rovers 4 --mode voronoi --frontier
# Team missions (paper 001, SPEC §3) and the hybrid (SPEC §4) on the default map.
case_ team-default - mission --dem default.tif --random-pdm 4 --pdm-seed 3 --seed 1 --targets 16
case_ team-default-paper - mission --dem default.tif --random-pdm 4 --pdm-seed 3 --seed 2 --targets 8 \
  --coordination paper --route lhc --slip
case_ team-default-lawnmower - mission --dem default.tif --random-pdm 2 --pdm-seed 4 --seed 1 --targets 8 \
  --route lawnmower --rovers 3
case_ hybrid-default - mission --dem default.tif --random-pdm 4 --pdm-seed 3 --seed 1 --planner hybrid --targets 6
# Real rover-scale sites.
case_ team-gale "$gale" mission --dem "$gale" --random-pdm 3 --pdm-seed 5 --seed 1 --targets 12
case_ cov-gale "$gale" coverage --dem "$gale" --seed 3 --rovers 2 --max-steps 4000
case_ team-kepler "$kepler" mission --dem "$kepler" --random-pdm 3 --pdm-seed 2 --seed 4 --targets 12
case_ hybrid-kepler "$kepler" mission --dem "$kepler" --random-pdm 2 --pdm-seed 2 --seed 4 --planner hybrid --targets 4

if [ "$mode" = --update ]; then
  [ "$skipped" = 0 ] || { echo "refusing to update with $skipped skipped cases" >&2; exit 1; }
  cp actual.sha256 "$golden"
  echo "wrote $(wc -l <"$golden") hashes to $golden"
  exit 0
fi
status=0
while read -r hash name; do
  want=$(awk -v n="$name" '$2 == n {print $1}' "$golden")
  if [ -z "$want" ]; then
    echo "FAIL $name: no golden hash"; status=1
  elif [ "$want" != "$hash" ]; then
    echo "FAIL $name: result changed ($hash, golden $want)"; status=1
  else
    echo "ok   $name"
  fi
done <actual.sha256
exit $status
