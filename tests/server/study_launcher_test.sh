#!/usr/bin/env bash
# roverplan serve --study-launcher (issue 12): a study runs as the launcher + `roverplan study run`
# child process (no shell), its progress read from the database the child writes; a failing or
# missing launcher fails the study with a message; DELETE cancels the child; with Open MPI the
# study runs on `mpirun -np 2` ranks. Usage: study_launcher_test.sh path/to/roverplan
set -u
BIN=$1
TMP=$(mktemp -d "${TMPDIR:-/tmp}/roverplan_launcher_test.XXXXXX")
PID=""
cleanup() { [ -n "$PID" ] && { kill -TERM "$PID" 2>/dev/null; wait "$PID" 2>/dev/null; }; rm -rf "$TMP"; }
trap cleanup EXIT
passed=0
fail() { echo "FAIL: $*" >&2; echo "--- server log:" >&2; tail -20 "$TMP/log" >&2; echo "$passed passed, 1 failed"; exit 1; }
pass() { passed=$((passed + 1)); echo "ok: $*"; }
json() { python3 -c "import json,sys; d=json.load(sys.stdin); print($1)"; }

start() {  # start LAUNCHER
  [ -n "$PID" ] && { kill -TERM "$PID"; wait "$PID" 2>/dev/null; }
  "$BIN" serve --port 0 --data "$TMP/data" --quiet --study-launcher "$1" > "$TMP/log" 2>&1 &
  PID=$!
  for _ in $(seq 1 150); do
    PORT=$(sed -n 's|.*http://127.0.0.1:\([0-9]*\)/.*|\1|p' "$TMP/log" | head -1)
    [ -n "$PORT" ] && curl -fs "http://127.0.0.1:$PORT/api/health" >/dev/null 2>&1 && return 0
    sleep 0.1
  done
  fail "server did not start"
}
api() { curl -s "http://127.0.0.1:$PORT$1" "${@:2}"; }
launch() { api /api/studies -H 'Content-Type: application/json' -d "$1" | json 'd["id"]'; }
wait_ended() {
  for _ in $(seq 1 600); do
    S=$(api "/api/studies/$1" | json 'd["status"]')
    case "$S" in succeeded|failed|cancelled) echo "$S"; return;; esac
    sleep 0.1
  done
  echo timeout
}
TINY='{"name":"tiny","planner":"coverage","runs":RUNS,"worlds":[{"grid":{"rows":30,"cols":30}}],"grid":{"pattern":["spiral","boustrophedon"]}}'

# A launcher string with a quoted word: env sets a variable whose value holds a blank.
start "env 'ROVER_LAUNCHER_TEST=a b'"
ID=$(launch "${TINY/RUNS/10}")
[ "$(wait_ended "$ID")" = succeeded ] || fail "launched study did not succeed: $(api "/api/studies/$ID")"
[ "$(api "/api/studies/$ID" | json 'd["runs_done"]')" = 20 ] || fail "runs_done"
[ "$(api "/api/studies/$ID/runs.csv" | tail -n +2 | cut -d, -f1 | sort -u | wc -l)" = 20 ] || fail "runs.csv rows"
pass "a study runs as the launcher's child; progress and runs come from its database"

ID=$(launch "${TINY/RUNS/20000}")
for _ in $(seq 1 100); do [ "$(api "/api/studies/$ID" | json 'd["runs_done"]')" != 0 ] && break; sleep 0.1; done
[ "$(api "/api/studies/$ID" -X DELETE | json 'd["status"]')" = cancelling ] || fail "DELETE did not cancel"
[ "$(wait_ended "$ID")" = cancelled ] || fail "the launched study was not cancelled"
pgrep -f "study run --spec .*$ID" >/dev/null && fail "the study child still runs"
pass "DELETE stops the launched child; the study is cancelled"

start "false"
ID=$(launch "${TINY/RUNS/2}")
[ "$(wait_ended "$ID")" = failed ] || fail "a failing launcher did not fail the study"
api "/api/studies/$ID" | json 'd["message"]' | grep -q "exited with status 1" || fail "message: $(api "/api/studies/$ID")"
pass "a launcher exiting non-zero fails the study with its status"

start "/nonexistent/launcher"
ID=$(launch "${TINY/RUNS/2}")
[ "$(wait_ended "$ID")" = failed ] || fail "a missing launcher did not fail the study"
api "/api/studies/$ID" | json 'd["message"]' | grep -q "could not be started" || fail "message: $(api "/api/studies/$ID")"
pass "a missing launcher fails the study, saying so"

kill -TERM "$PID"; wait "$PID" 2>/dev/null; PID=""
if "$BIN" serve --port 0 --data "$TMP/data" --quiet --study-launcher "mpirun 'open" > "$TMP/log" 2>&1; then fail "a bad launcher string was accepted"; fi
grep -q "study-launcher" "$TMP/log" || fail "no word about the launcher string"
pass "an unclosed quote in the launcher string stops serve with one line"

if command -v mpirun >/dev/null 2>&1 && "$BIN" study run --help 2>&1 | grep -q . ; then
  ROOT=""; [ "$(id -u)" = 0 ] && ROOT="--allow-run-as-root"
  start "mpirun -np 2 --oversubscribe $ROOT"
  ID=$(launch "${TINY/RUNS/50}")
  S=$(wait_ended "$ID")
  if [ "$S" = succeeded ]; then
    [ "$(api "/api/studies/$ID/runs.csv" | tail -n +2 | cut -d, -f1 | sort -u | wc -l)" = 100 ] || fail "mpirun runs.csv rows"
    pass "a study launched as mpirun -np 2 ranks"
  elif api "/api/studies/$ID" | json 'd["message"]' | grep -q "exited"; then
    echo "skip: mpirun is here but this roverplan was not built with MPI or mpirun cannot start ranks"
  else
    fail "mpirun study: $S"
  fi
fi
echo "$passed passed, 0 failed"
