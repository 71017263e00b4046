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

# Versions (issue 26): the PDM at version 2, the zone set at version 2, each with its history; after
# kill -9 below they must come back as they were, and a stale If-Match still gets 412.
put() { curl -s -o "$TMP/put.json" -w '%{http_code}' -X PUT "http://127.0.0.1:$PORT$1" -H 'Content-Type: application/json' "${@:2}"; }
[ "$(put "/api/maps/$MAP/pdms/$PDM" -H 'If-Match: "v1"' -d '{"name":"renamed"}')" = 200 ] || fail "PDM PUT v1 -> v2"
ZONE='{"type":"FeatureCollection","features":[{"type":"Feature","properties":{"name":"Z"},"geometry":{"type":"Polygon","coordinates":[[[10,10],[30,10],[30,30],[10,10]]]}}]}'
[ "$(put "/api/maps/$MAP/zones" -d "$ZONE")" = 200 ] || fail "zone set v1"
[ "$(put "/api/maps/$MAP/zones" -H 'If-Match: "v1"' -d "$ZONE")" = 200 ] || fail "zone set v1 -> v2"
pass "a PDM and a zone set at version 2"

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

[ "$(api "/api/maps/$MAP/pdms/$PDM" | json 'd["version"], d["name"]')" = "2 renamed" ] || fail "after kill -9: PDM version lost"
api "/api/maps/$MAP/pdms/$PDM" -D - -o /dev/null | grep -qi '^etag: "v2"' || fail "after kill -9: PDM ETag"
[ "$(api "/api/maps/$MAP/pdms/$PDM/history" | json '[h["version"] for h in d]')" = "[2, 1]" ] || fail "after kill -9: PDM history"
[ "$(api "/api/maps/$MAP/zones" | json 'd["version"], len(d["features"])')" = "2 1" ] || fail "after kill -9: zone set version lost"
[ "$(put "/api/maps/$MAP/pdms/$PDM" -H 'If-Match: "v1"' -d '{"name":"stale"}')" = 412 ] || fail "after kill -9: a stale If-Match was taken"
[ "$(put "/api/maps/$MAP/pdms/$PDM" -H 'If-Match: "v2"' -d '{"name":"next"}')" = 200 ] || fail "after kill -9: the current If-Match refused"
[ "$(json 'd["version"]' < "$TMP/put.json")" = 3 ] || fail "after kill -9: the next version is not 3"
pass "after kill -9 versions, ETags and history are as they were, and a stale write still gets 412"

echo "$passed passed, 0 failed"
