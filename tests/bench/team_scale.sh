#!/usr/bin/env bash
# Benchmark (issue 25): a team mission as the team grows, on the default map (600² × 0.25 m
# synthetic Mars), PDM `--random-pdm 4 --pdm-seed 3`, 64 targets, seed 1, the generated formation
# (core/team/formation.hpp: slots 2 × safety + 0.25 m apart). Prints per team size the plan's wall
# time, its user CPU seconds (all threads; the figure to compare on a shared machine) and peak
# memory with the plan's own counts: sub-teams (core/team/sub_teams.hpp; 1 = one team), legs
# reached, skipped and short, rover slots without ground, RRT* calls, collisions, attitude
# exceedances and the closest approach. Timings vary with the machine; the counts do not (fixed
# seeds). Extra mission options go in ROVERPLAN_OPTS (e.g. "--edge-evaluation sampled", or
# "--sub-team-size 0" to fly one team of every rover).
#   tests/bench/team_scale.sh [ROVERPLAN] [N ...]     (default N: 5 10 20)
set -euo pipefail
root=$(cd "$(dirname "$0")/../.." && pwd)
roverplan=$(realpath "${1:-$root/build/bin/roverplan}")
shift || true
sizes=("$@")
[ ${#sizes[@]} -gt 0 ] || sizes=(5 10 20)
[ -x /usr/bin/time ] || { echo "/usr/bin/time not found (Debian time)" >&2; exit 2; }
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
"$roverplan" terrain --out "$work/default.tif" >/dev/null

printf '%7s %9s %9s %9s %5s %8s %8s %6s %8s %9s %11s %12s %10s\n' rovers "wall s" "user s" "peak MiB" teams reached skipped short "no slot" "rrt calls" collisions exceedances "min sep m"
for n in "${sizes[@]}"; do
  # shellcheck disable=SC2086  # ROVERPLAN_OPTS is a list of words
  if ! /usr/bin/time -f '%e %U %M' -o "$work/t" "$roverplan" mission --dem "$work/default.tif" --random-pdm 4 \
       --pdm-seed 3 --seed 1 --targets 64 --rovers "$n" ${ROVERPLAN_OPTS:-} --json >"$work/r.json" 2>"$work/err"; then
    printf '%7s  refused: %s\n' "$n" "$(head -c 100 "$work/err")"
    continue
  fi
  read -r s user kib <"$work/t"
  python3 - "$work/r.json" "$n" "$s" "$user" "$((kib / 1024))" <<'EOF'
import json, sys
r = json.load(open(sys.argv[1]))
m = {x["name"]: x["value"] for x in r["metrics"]} if isinstance(r["metrics"], list) else r["metrics"]
get = lambda k: m.get(k, float("nan"))
print("%7s %9.1f %9.1f %9s %5d %8d %8d %6d %8d %9d %11d %12d %10.2f" % (sys.argv[2], float(sys.argv[3]),
      float(sys.argv[4]), sys.argv[5], m.get("sub_teams", 1), get("targets_reached"), get("targets_skipped"),
      get("targets_short"), get("targets_no_slot"), get("rrt_calls"),
      get("collisions"), get("exceedances"), get("min_separation_m")))
EOF
done
