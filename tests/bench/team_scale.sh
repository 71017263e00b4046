#!/usr/bin/env bash
# Benchmark (issue 25): a team mission as the team grows, on the default map (600² × 0.25 m
# synthetic Mars) or, with --dem FILE, on another DEM (e.g. the Kepler rover site,
# ../shared/dems/moon_kepler_rescaled_025m/kepler_site.tif), PDM `--random-pdm 4 --pdm-seed 3`,
# 64 targets, seed 1, the generated formation at the map's centre (core/team/formation.hpp).
# Prints per team size the plan's wall time, its user CPU seconds (all threads; the figure to
# compare on a shared machine) and peak memory with the plan's own counts: sub-teams
# (core/team/sub_teams.hpp; 1 = one team), legs reached, skipped and short, rover slots without
# ground, RRT* calls, collisions, attitude exceedances and the closest approach; then the issue's
# two ratios: legs reached of the legs to reachable targets (every leg: in the timed mode the
# route's targets and every leg's goal lie on ground the lattice reaches from the starts, so the
# unreachable part of a map never gets a leg; "unreach m²" says how much there is) and slots
# without ground of all rover slots (legs + slots without ground). Timings vary with the
# machine; the counts do not (fixed seeds). Extra mission options go in ROVERPLAN_OPTS (e.g.
# "--edge-evaluation sampled", "--route orienteering", or "--sub-team-size 0" to fly one team of
# every rover).
#   tests/bench/team_scale.sh [--dem FILE] [ROVERPLAN] [N ...]     (default N: 5 10 20 40 64)
set -euo pipefail
root=$(cd "$(dirname "$0")/../.." && pwd)
dem=""
if [ "${1:-}" = "--dem" ]; then
  [ -n "${2:-}" ] && [ -r "$2" ] || { echo "--dem: no readable file '${2:-}'" >&2; exit 2; }
  dem=$(realpath "$2")
  shift 2
fi
roverplan=$(realpath "${1:-$root/build/bin/roverplan}")
shift || true
sizes=("$@")
[ ${#sizes[@]} -gt 0 ] || sizes=(5 10 20 40 64)
[ -x /usr/bin/time ] || { echo "/usr/bin/time not found (Debian time)" >&2; exit 2; }
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
if [ -z "$dem" ]; then
  "$roverplan" terrain --out "$work/default.tif" >/dev/null
  dem="$work/default.tif"
fi
echo "map: $dem"

printf '%7s %7s %7s %8s %5s %8s %8s %6s %8s %9s %11s %12s %9s %11s %9s %10s\n' rovers "wall s" "user s" \
  "peak MiB" teams reached skipped short "no slot" "rrt calls" collisions exceedances "min sep" \
  "reached %" "no slot %" "unreach m²"
for n in "${sizes[@]}"; do
  # shellcheck disable=SC2086  # ROVERPLAN_OPTS is a list of words
  if ! /usr/bin/time -f '%e %U %M' -o "$work/t" "$roverplan" mission --dem "$dem" --random-pdm 4 \
       --pdm-seed 3 --seed 1 --targets 64 --rovers "$n" ${ROVERPLAN_OPTS:-} --json >"$work/r.json" 2>"$work/err"; then
    printf '%7s  refused: %s\n' "$n" "$(head -c 100 "$work/err")"
    continue
  fi
  read -r s user kib <"$work/t"
  python3 - "$work/r.json" "$n" "$s" "$user" "$((kib / 1024))" <<'PY'
import json, sys
r = json.load(open(sys.argv[1]))
m = {x["name"]: x["value"] for x in r["metrics"]} if isinstance(r["metrics"], list) else r["metrics"]
get = lambda k: int(m.get(k, 0))
reached, skipped, short, noslot = get("targets_reached"), get("targets_skipped"), get("targets_short"), get("targets_no_slot")
legs = reached + skipped + short
print("%7s %7.1f %7.1f %8s %5d %8d %8d %6d %8d %9d %11d %12d %9.2f %11.2f %9.2f %10.0f" % (sys.argv[2],
      float(sys.argv[3]), float(sys.argv[4]), sys.argv[5], m.get("sub_teams", 1), reached, skipped, short,
      noslot, get("rrt_calls"), get("collisions"), get("exceedances"), m.get("min_separation_m", float("nan")),
      100.0 * reached / legs if legs else float("nan"), 100.0 * noslot / (legs + noslot) if legs + noslot else float("nan"),
      m.get("unreachable_area_m2", 0)))
PY
done
