#!/usr/bin/env bash
# roverplan serve as a process: clean stop on SIGTERM, and after kill -9 in the middle of an upload
# and of a mission nothing half-written is visible, every stored map/PDM/mission is back, and the
# mission that was running is marked interrupted. Usage: serve_restart_test.sh path/to/roverplan
set -u
BIN=$1
TMP=$(mktemp -d "${TMPDIR:-/tmp}/roverplan_serve_test.XXXXXX")
PID=""
cleanup() { [ -n "$PID" ] && kill -9 "$PID" 2>/dev/null; rm -rf "$TMP"; }
trap cleanup EXIT
passed=0
fail() { echo "FAIL: $*" >&2; echo "--- server log:" >&2; tail -20 "$TMP/log" >&2; echo "$passed passed, 1 failed"; exit 1; }
pass() { passed=$((passed + 1)); echo "ok: $*"; }
json() { python3 -c "import json,sys; d=json.load(sys.stdin); print($1)"; }

start() {
  "$BIN" serve --port 0 --data "$TMP/data" --quiet > "$TMP/log" 2>&1 &
  PID=$!
  for _ in $(seq 1 150); do
    PORT=$(sed -n 's|.*http://127.0.0.1:\([0-9]*\)/.*|\1|p' "$TMP/log" | head -1)
    [ -n "$PORT" ] && curl -fs "http://127.0.0.1:$PORT/api/health" >/dev/null 2>&1 && return 0
    sleep 0.1
  done
  fail "server did not start"
}
api() { curl -s "http://127.0.0.1:$PORT$1" "${@:2}"; }

start
MAP=$(api /api/maps | json 'd[0]["id"]')
[ -n "$MAP" ] || fail "no default map"
pass "server starts with the default map"

PDM=$(api "/api/maps/$MAP/pdms" -H 'Content-Type: application/json' -d '{"random":4,"seed":3}' | json 'd["id"]')
DONE=$(api /api/missions -H 'Content-Type: application/json' \
  -d "{\"map\":\"$MAP\",\"planner\":\"coverage\",\"rovers\":[{\"x\":20,\"y\":20,\"heading\":0}],\"params\":{\"coverage\":0.5}}" | json 'd["id"]')
for _ in $(seq 1 200); do [ "$(api "/api/missions/$DONE" | json 'd["status"]')" = succeeded ] && break; sleep 0.1; done
[ "$(api "/api/missions/$DONE" | json 'd["status"]')" = succeeded ] || fail "mission did not finish"
pass "a PDM and a finished mission are stored"

kill -TERM "$PID"
wait "$PID"; status=$?
PID=""
[ "$status" -eq 0 ] || fail "SIGTERM: exit status $status"
grep -q "stopped" "$TMP/log" || fail "SIGTERM: no clean stop message"
pass "SIGTERM stops the server cleanly"

start
[ "$(api "/api/maps" | json 'len(d)')" = 1 ] || fail "restart: map count changed"
api "/api/maps/$MAP/pdms/$PDM" | grep -q "\"id\":\"$PDM\"" || fail "restart: PDM lost"
[ "$(api "/api/missions/$DONE" | json 'd["status"]')" = succeeded ] || fail "restart: mission lost"
pass "after a clean restart every map, PDM and mission is there"

# A slow mission, then a slow upload, then kill -9 while both are in flight.
RUN=$(api /api/missions -H 'Content-Type: application/json' \
  -d "{\"map\":\"$MAP\",\"planner\":\"coverage\",\"pace\":5,\"rovers\":[{\"x\":30,\"y\":30,\"heading\":0}],\"params\":{\"coverage\":1.0}}" | json 'd["id"]')
head -c 20000000 /dev/urandom > "$TMP/big.bin"
curl -s --limit-rate 2M -o /dev/null "http://127.0.0.1:$PORT/api/maps?filename=big.tif" -H 'Content-Type: image/tiff' --data-binary @"$TMP/big.bin" &
CURL=$!
sleep 1.5
[ -n "$(ls -A "$TMP/data/tmp")" ] || fail "the upload is not streaming to disk"
kill -9 "$PID"
wait "$PID" 2>/dev/null
PID=""
wait "$CURL" 2>/dev/null
pass "kill -9 mid-upload and mid-mission"

start
[ "$(api "/api/maps" | json 'len(d)')" = 1 ] || fail "after kill -9: a half-written map is visible"
[ -z "$(ls -A "$TMP/data/tmp")" ] || fail "after kill -9: tmp/ not cleaned"
[ "$(api "/api/missions/$RUN" | json 'd["status"]')" = interrupted ] || fail "after kill -9: running mission not marked interrupted"
[ "$(api "/api/missions/$DONE" | json 'd["status"]')" = succeeded ] || fail "after kill -9: finished mission lost"
api "/api/missions/$DONE/result.geojson" | grep -q FeatureCollection || fail "after kill -9: results lost"
pass "after kill -9 nothing half-written is visible and the running mission is interrupted"

echo "$passed passed, 0 failed"
