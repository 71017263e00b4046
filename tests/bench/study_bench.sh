#!/usr/bin/env bash
# Study engine figures (issue 12), printed, never asserted:
#   1. laine-fig6 in full (12 000 runs) in one process on all cores: wall, runs/s (with OLD_BIN
#      set to an older roverplan, its `sweep --preset laine-fig6` wall beside it, same sitting);
#   2. runs/s of one process with one thread vs `mpirun -np 2 --threads 1` (RUNS per config,
#      default 750 = 3000 runs), and their ratio.
# The machine's load (uptime) is printed first and last: on a shared machine compare ratios.
# Usage: tests/bench/study_bench.sh path/to/roverplan   (env: OLD_BIN, RUNS)
set -euo pipefail
BIN=${1:?usage: study_bench.sh path/to/roverplan}
RUNS=${RUNS:-750}
TMP=$(mktemp -d)
trap 'rm -rf "$TMP"' EXIT
wall() { /usr/bin/time -f %e -o "$TMP/t" "$@" >"$TMP/out" 2>&1; cat "$TMP/t"; }
# "W s wall, C s CPU": on a loaded machine the CPU seconds compare better than the wall.
cost() { /usr/bin/time -f "%e %U %S" -o "$TMP/t" "$@" >"$TMP/out" 2>&1; read -r w u s <"$TMP/t"; echo "$w s wall, $(python3 -c "print(round($u + $s, 2))") s CPU"; }
echo "load: $(uptime)"
if [ -n "${OLD_BIN:-}" ]; then
  echo "old sweep laine-fig6 (12000 runs, all cores):  $(cost "$OLD_BIN" sweep --preset laine-fig6)"
fi
echo "study laine-fig6 (12000 runs, all cores):       $(cost "$BIN" study run --preset laine-fig6 --quiet --out "$TMP/fig6.sqlite")"
echo "sweep laine-fig6 (12000 runs, all cores):       $(cost "$BIN" sweep --preset laine-fig6)"
if [ -n "${OLD_BIN:-}" ]; then
  echo "old sweep laine-fig6 again:                     $(cost "$OLD_BIN" sweep --preset laine-fig6)"
fi
total=$((RUNS * 4))
one=$(wall "$BIN" study run --preset laine-fig6 --runs "$RUNS" --threads 1 --quiet --out "$TMP/one.sqlite")
MPIRUN=(mpirun --oversubscribe)
[ "$(id -u)" -eq 0 ] && MPIRUN+=(--allow-run-as-root)
two=$(wall "${MPIRUN[@]}" -np 2 "$BIN" study run --preset laine-fig6 --runs "$RUNS" --threads 1 --quiet --out "$TMP/mpi.sqlite")
python3 - "$total" "$one" "$two" <<'PY'
import sys
n, a, b = int(sys.argv[1]), float(sys.argv[2]), float(sys.argv[3])
print(f"1 process, 1 thread:       {n} runs in {a:.2f} s = {n / a:.1f} runs/s")
print(f"mpirun -np 2 --threads 1:  {n} runs in {b:.2f} s = {n / b:.1f} runs/s  ({a / b:.2f}x)")
PY
echo "load: $(uptime)"
