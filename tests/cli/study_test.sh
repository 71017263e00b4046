#!/usr/bin/env bash
# roverplan study as a user runs it: the per-run rows (all but timing/host/rank, compared with
# `roverplan study dump`) are identical on 1 thread, 2 threads, 3 shards merged and MPI ranks
# (mpirun -np 2, -np 4 --oversubscribe); a study killed with kill -9 resumes to the same rows with
# no duplicates; merge refuses another study; bad specs exit 2 with one line naming the field.
# Usage: study_test.sh path/to/roverplan
set -u

if [ $# -ne 1 ] || [ ! -x "$1" ]; then
  echo "usage: $0 path/to/roverplan (got '${1:-}')" >&2
  exit 1
fi
BIN=$1
TMP=$(mktemp -d "${TMPDIR:-/tmp}/roverplan_study_test.XXXXXX") || { echo "FAIL: mktemp" >&2; exit 1; }
BG=""
trap '[ -n "$BG" ] && kill -9 "$BG" 2>/dev/null; rm -rf "$TMP"' EXIT

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
run() {
  "$BIN" "$@" >"$OUT" 2>"$ERR"
  STATUS=$?
}
expect_status() {
  [ "$STATUS" -eq "$1" ] || fail "$2: expected exit status $1, got $STATUS"
}
lines() { wc -l <"$1" | tr -d ' '; }
# same_rows A.sqlite B.sqlite WHAT: the dumps of two study databases are identical.
same_rows() {
  "$BIN" study dump "$1" >"$TMP/a.dump" 2>"$ERR" || fail "$3: study dump $1"
  "$BIN" study dump "$2" >"$TMP/b.dump" 2>"$ERR" || fail "$3: study dump $2"
  [ "$(grep -c '^run ' "$TMP/a.dump")" -eq "$RUNS" ] || fail "$3: $1 holds $(grep -c '^run ' "$TMP/a.dump") runs, expected $RUNS"
  cmp -s "$TMP/a.dump" "$TMP/b.dump" || { diff "$TMP/a.dump" "$TMP/b.dump" | head -5 >&2; fail "$3: rows differ"; }
}

# A small study: 2 team sizes x 2 patterns x 6 runs on 14 x 14 grids.
cat >"$TMP/small.json" <<'EOF'
{"name": "small", "planner": "coverage", "runs": 6, "master_seed": 3,
 "worlds": [{"grid": {"rows": 14, "cols": 14, "obstacle_fraction": 0.08}}],
 "rovers": [1, 2], "params": {"coverage": 0.95},
 "grid": {"pattern": ["spiral", "boustrophedon"]}, "levels": [0.5, 0.9], "curve_points": 8}
EOF
RUNS=24

# --- identity across execution modes --------------------------------------------------------------
run study run --spec "$TMP/small.json" --threads 1 --out "$TMP/t1.sqlite"
expect_status 0 "study run --threads 1"
grep -q "24 runs" "$OUT" || fail "study run: does not report 24 runs"
run study run --spec "$TMP/small.json" --threads 2 --out "$TMP/t2.sqlite"
expect_status 0 "study run --threads 2"
same_rows "$TMP/t1.sqlite" "$TMP/t2.sqlite" "1 thread vs 2 threads"
pass "1 thread and 2 threads give the same rows"

for k in 0 1 2; do
  run study run --spec "$TMP/small.json" --threads 1 --shard "$k/3" --out "$TMP/shard$k.sqlite"
  expect_status 0 "study run --shard $k/3"
done
run study merge "$TMP/merged.sqlite" "$TMP/shard0.sqlite" "$TMP/shard1.sqlite" "$TMP/shard2.sqlite"
expect_status 0 "study merge"
grep -q "24/24 runs" "$OUT" || fail "study merge: does not report 24/24 runs"
same_rows "$TMP/t1.sqlite" "$TMP/merged.sqlite" "1 thread vs 3 shards merged"
pass "3 shards merged give the same rows"

if command -v mpirun >/dev/null 2>&1; then
  MPIRUN=(mpirun --oversubscribe)
  [ "$(id -u)" -eq 0 ] && MPIRUN+=(--allow-run-as-root)
  for np in 2 4; do
    "${MPIRUN[@]}" -np "$np" "$BIN" study run --spec "$TMP/small.json" --threads 1 --out "$TMP/mpi$np.sqlite" \
      >"$OUT" 2>"$ERR"
    STATUS=$?
    expect_status 0 "mpirun -np $np study run"
    grep -q "on $np ranks" "$OUT" || fail "mpirun -np $np: rank 0 does not report $np ranks"
    same_rows "$TMP/t1.sqlite" "$TMP/mpi$np.sqlite" "1 thread vs mpirun -np $np"
    ranks=$(sqlite3 "$TMP/mpi$np.sqlite" "SELECT count(DISTINCT rank) FROM runs" 2>/dev/null || echo "?")
    pass "mpirun -np $np gives the same rows (rows from $ranks ranks)"
  done
else
  echo "skip: no mpirun (install openmpi-bin) — MPI identity not checked"
fi

# --- resume after kill -9 ------------------------------------------------------------------------
cat >"$TMP/long.json" <<'EOF'
{"name": "long", "planner": "coverage", "runs": 2500, "master_seed": 5,
 "worlds": [{"grid": {"rows": 50, "cols": 50}}], "params": {"coverage": 0.95},
 "grid": {"pattern": ["spiral", "boustrophedon"]}, "curve_points": 4}
EOF
"$BIN" study run --spec "$TMP/long.json" --threads 1 --out "$TMP/killed.sqlite" >"$OUT" 2>"$ERR" &
BG=$!
done_runs=0
for _ in $(seq 1 300); do
  sleep 0.1
  done_runs=$("$BIN" study summary "$TMP/killed.sqlite" --json 2>/dev/null |
    python3 -c 'import json,sys; print(json.load(sys.stdin)["runs_done"])' 2>/dev/null || echo 0)
  [ "$done_runs" -gt 0 ] && break
done
kill -9 "$BG" 2>/dev/null
wait "$BG" 2>/dev/null
BG=""
[ "$done_runs" -gt 0 ] || fail "kill -9: the study committed nothing in 30 s"
[ "$done_runs" -lt 5000 ] || fail "kill -9: the study finished before it was killed (make it longer)"
run study run --spec "$TMP/long.json" --threads 2 --out "$TMP/killed.sqlite"
expect_status 0 "study run after kill -9"
grep -Eq "already in" "$OUT" || fail "resume: no 'already in' count"
already=$(sed -n 's/.*(\([0-9]*\) already in.*/\1/p' "$OUT")
[ "${already:-0}" -gt 0 ] || fail "resume: ran everything again (already = ${already:-none})"
run study run --spec "$TMP/long.json" --threads 2 --out "$TMP/clean.sqlite"
expect_status 0 "clean study run"
RUNS=5000
same_rows "$TMP/clean.sqlite" "$TMP/killed.sqlite" "killed + resumed vs clean"
pass "a study killed with kill -9 after $done_runs runs resumes with only the missing ones (same rows, no duplicates)"

# --- merge refuses another study ---------------------------------------------------------------
run study run --spec "$TMP/small.json" --runs 2 --threads 1 --out "$TMP/other.sqlite"
expect_status 0 "study run --runs 2"
cp "$TMP/merged.sqlite" "$TMP/keep.sqlite"
run study merge "$TMP/keep.sqlite" "$TMP/shard0.sqlite" "$TMP/other.sqlite"
expect_status 2 "study merge of another study"
[ "$(lines "$ERR")" -eq 1 ] || fail "merge of another study: expected one stderr line"
grep -q "different study" "$ERR" || fail "merge of another study: stderr does not say why"
RUNS=24
same_rows "$TMP/t1.sqlite" "$TMP/keep.sqlite" "a refused merge leaves OUT as it was"
run study run --spec "$TMP/small.json" --runs 2 --threads 1 --out "$TMP/t1.sqlite"
expect_status 2 "study run into a database of another study"
pass "merge and run refuse a database of another study"

# --- summary, bad input --------------------------------------------------------------------------
run study summary "$TMP/t1.sqlite"
expect_status 0 "study summary"
grep -q "path_length_ratio@90%" "$OUT" || fail "study summary: no path_length_ratio@90% row"
run study summary "$TMP/t1.sqlite" --json
expect_status 0 "study summary --json"
python3 -c 'import json,sys; d=json.load(open(sys.argv[1])); assert d["runs_done"] == 24 and d["rows"]' "$OUT" \
  || fail "study summary --json: bad JSON"
pass "study summary prints the table and JSON"

# --- export --ompl: an OMPL benchmark database (Planner Arena) -----------------------------------
run study export "$TMP/t1.sqlite" --ompl "$TMP/t1.ompl.db"
expect_status 0 "study export --ompl"
grep -q "$RUNS runs" "$OUT" || fail "study export: does not report $RUNS runs"
python3 - "$TMP/t1.ompl.db" "$RUNS" <<'PY' || fail "study export: not OMPL's tables or not every run"
import sqlite3, sys
db = sqlite3.connect(sys.argv[1])
tables = {r[0] for r in db.execute("SELECT name FROM sqlite_master WHERE type = 'table'")}
assert {"experiments", "plannerConfigs", "enums", "runs", "progress"} <= tables, tables
runs = db.execute("SELECT count(*) FROM plannerConfigs INNER JOIN runs ON plannerConfigs.id = runs.plannerid").fetchone()[0]
assert runs == int(sys.argv[2]), runs
PY
run study export "$TMP/t1.sqlite"
expect_status 2 "study export without --ompl"
pass "study export --ompl writes OMPL's tables with every run"

echo '{"worlds": [{"grid": {"rows": 1}}]}' >"$TMP/bad.json"
run study run --spec "$TMP/bad.json" --out "$TMP/bad.sqlite"
expect_status 2 "study run with a bad spec"
[ "$(lines "$ERR")" -eq 1 ] || fail "bad spec: expected one stderr line, got $(lines "$ERR")"
grep -q "worlds\[0\].grid.rows" "$ERR" || fail "bad spec: stderr does not name worlds[0].grid.rows"
run study run --preset nope --out "$TMP/bad.sqlite"
expect_status 2 "study run --preset nope"
grep -q "nope" "$ERR" || fail "--preset nope: stderr does not name it"
run study run --preset frontier --shard 3/3 --out "$TMP/bad.sqlite"
expect_status 2 "study run --shard 3/3"
grep -q -- "--shard" "$ERR" || fail "--shard 3/3: stderr does not name --shard"
echo 'not json' >"$TMP/bad.json"
run study run --spec "$TMP/bad.json" --out "$TMP/bad.sqlite"
expect_status 2 "study run with a spec that is not JSON"
[ "$(lines "$ERR")" -eq 1 ] || fail "not JSON: expected one stderr line"
pass "bad specs and options exit 2 with one line naming the field"

echo "$passed passed, 0 failed"
exit 0
