#!/usr/bin/env bash
# roverplan serve on a full disk (issue 14): a small tmpfs mounted by the test is filled while the
# server runs. Every write answers 507 insufficient_storage, a cancelled mission whose partial result
# cannot be stored stays cancelled with the reason and no result, the server goes on; a restart on the still-full disk starts;
# deleting a PDM and a map works while full (and frees space); once space is free, writes work.
# Needs root to mount; skipped (exit 77) when it cannot. Usage: disk_full_test.sh path/to/roverplan
set -u
BIN=$1
TMP=$(mktemp -d "${TMPDIR:-/tmp}/roverplan_disk_full.XXXXXX")
MNT="$TMP/mnt"
PID=""
cleanup() {
  [ -n "$PID" ] && kill -9 "$PID" 2>/dev/null && wait "$PID" 2>/dev/null
  mountpoint -q "$MNT" && umount "$MNT"
  rm -rf "$TMP"
}
trap cleanup EXIT
mkdir -p "$MNT"
if ! mount -t tmpfs -o size=8m tmpfs "$MNT" 2>/dev/null; then
  echo "SKIP: cannot mount a tmpfs here (needs root and mount permission)"
  exit 77
fi
passed=0
fail() { echo "FAIL: $*" >&2; echo "--- server log:" >&2; tail -20 "$TMP/log" >&2; echo "$passed passed, 1 failed"; exit 1; }
pass() { passed=$((passed + 1)); echo "ok: $*"; }
json() { python3 -c "import json,sys; d=json.load(sys.stdin); print($1)"; }

start() {
  "$BIN" serve --port 0 --data "$MNT/data" --workers 1 --quiet > "$TMP/log" 2>&1 &
  PID=$!
  for _ in $(seq 1 150); do
    PORT=$(sed -n 's|.*http://127.0.0.1:\([0-9]*\)/.*|\1|p' "$TMP/log" | head -1)
    [ -n "$PORT" ] && curl -fs "http://127.0.0.1:$PORT/api/health" >/dev/null 2>&1 && return 0
    kill -0 "$PID" 2>/dev/null || break
    sleep 0.1
  done
  PID=""
  fail "server did not start"
}
api() { curl -s "http://127.0.0.1:$PORT$1" "${@:2}"; }
code() { curl -s -o "$TMP/body" -w '%{http_code}' "http://127.0.0.1:$PORT$1" "${@:2}"; }
alive() { kill -0 "$PID" 2>/dev/null && [ "$(code /api/health)" = 200 ]; }
fill() { dd if=/dev/zero of="$MNT/filler$1" bs=16k 2>/dev/null; sync; }
mission() { echo "{\"map\":\"$MAP\",\"planner\":\"coverage\",\"rovers\":[{\"x\":$1,\"y\":20,\"heading\":0}],\"params\":{\"coverage\":$2},\"pace\":$3}"; }

start
MAP=$(api /api/maps | json 'd[0]["id"]')
PDM=$(api "/api/maps/$MAP/pdms" -H 'Content-Type: application/json' -d '{"random":3,"seed":2}' | json 'd["id"]')
[ -n "$MAP" ] && [ -n "$PDM" ] || fail "no map or PDM"
# A slow mission, running while the disk fills; its result will not fit, even in the room its
# cancel's status row frees (the database's 256 KiB status reserve): on the map's 0.25 m cells its
# grid alone is 1.8 MB.
RUN=$(api /api/missions -H 'Content-Type: application/json' -d "$(mission 20 1.0 20 | sed 's/"coverage":1.0/"coverage":1.0,"coverage_cell":0.25/')" | json 'd["id"]')
for _ in $(seq 1 100); do [ "$(api "/api/missions/$RUN" | json 'd["status"]')" = running ] && break; sleep 0.05; done
pass "server on an 8 MiB tmpfs with a map, a PDM and a running mission ($(df -k "$MNT" | awk 'NR==2{print $3}') KiB used)"

fill 1
[ "$(df -k "$MNT" | awk 'NR==2{print $4}')" -le 64 ] || fail "the disk did not fill"
c=$(code /api/missions -H 'Content-Type: application/json' -d "$(mission 40 0.1 0)")
[ "$c" = 507 ] || fail "POST /api/missions on a full disk: $c $(cat "$TMP/body")"
[ "$(json 'd["error"]["code"]' < "$TMP/body")" = insufficient_storage ] || fail "507 without insufficient_storage: $(cat "$TMP/body")"
grep -q "$MNT" "$TMP/body" && fail "the 507 message shows a server path: $(cat "$TMP/body")"
alive || fail "the server died on a full disk"
pass "a mission submitted on a full disk answers 507 insufficient_storage, no path shown"

# An upload larger than the free space: the body cannot be stored. 507, its partial file removed,
# and the server still answers (it used to reset the connection with no response).
head -c 1048576 /dev/urandom > "$TMP/big.tif"
c=$(code "/api/maps?filename=big.tif&name=big" -X POST -H 'Content-Type: image/tiff' --data-binary @"$TMP/big.tif")
[ "$c" = 507 ] || fail "an upload larger than the free space: $c $(cat "$TMP/body")"
[ "$(json 'd["error"]["code"] + " " + d["error"]["field"]' < "$TMP/body")" = "insufficient_storage body" ] ||
  fail "upload on a full disk: $(cat "$TMP/body")"
grep -q "$MNT" "$TMP/body" && fail "the upload's 507 shows a server path: $(cat "$TMP/body")"
[ -z "$(ls -A "$MNT/data/tmp")" ] || fail "a partial upload left in tmp/: $(ls "$MNT/data/tmp")"
alive || fail "the server stopped answering after an upload on a full disk"
pass "an upload larger than the free space answers 507 insufficient_storage (field body), nothing left in tmp/"

# A GeoTIFF layer and a PDM written on the full disk: 507, not 400 with the layer's path.
c=$(code "/api/maps/$MAP/layers/slope.tif")
[ "$c" = 507 ] || fail "GET slope.tif on a full disk: $c $(cat "$TMP/body")"
[ "$(json 'd["error"]["code"]' < "$TMP/body")" = insufficient_storage ] || fail "slope.tif: $(cat "$TMP/body")"
grep -q "$MNT\|/maps/" "$TMP/body" && fail "the slope.tif 507 shows a server path: $(cat "$TMP/body")"
c=$(code "/api/maps/$MAP/pdms" -H 'Content-Type: application/json' -d '{"random":2,"seed":5}')
[ "$c" = 507 ] || fail "POST a PDM on a full disk: $c $(cat "$TMP/body")"
[ "$(json 'd["error"]["code"]' < "$TMP/body")" = insufficient_storage ] || fail "PDM: $(cat "$TMP/body")"
grep -q "$MNT" "$TMP/body" && fail "the PDM's 507 shows a server path: $(cat "$TMP/body")"
alive || fail "the server died writing GeoTIFFs on a full disk"
pass "a .tif layer and a PDM on the full disk answer 507 insufficient_storage, no path shown"

# 48 KiB free: a Gaussian PDM is stored as its components (a few hundred bytes, issue 22), so it
# fits where its GeoTIFF (1.4 MB) used to answer 507; nothing is left in tmp/; then the disk fills again.
truncate -s -48k "$MNT/filler1"
c=$(code "/api/maps/$MAP/pdms" -H 'Content-Type: application/json' -d '{"random":2,"seed":6}')
[ "$c" = 201 ] || fail "a Gaussian PDM in the last 48 KiB: $c $(cat "$TMP/body")"
P6=$(json 'd["id"]' < "$TMP/body")
[ "$(du -sk "$MNT/data/pdms/$P6" | cut -f1)" -le 8 ] || fail "the PDM takes $(du -sk "$MNT/data/pdms/$P6") KiB"
[ -z "$(ls -A "$MNT/data/tmp")" ] || fail "a PDM's staging left in tmp/: $(ls "$MNT/data/tmp")"
fill 3
pass "a Gaussian PDM fits in the last 48 KiB: stored as its components ($(du -sb "$MNT/data/pdms/$P6" | cut -f1) bytes)"

# The running mission is cancelled (final at once, issue 22) and cannot store its partial result:
# it stays cancelled, its message says why, and its result answers 409 no_result.
[ "$(code "/api/missions/$RUN" -X DELETE)" = 202 ] || fail "cancel on a full disk"
for _ in $(seq 1 100); do
  api "/api/missions/$RUN" > "$TMP/m.json"
  [ "$(json 'd["result"]' < "$TMP/m.json")" != pending ] && break
  sleep 0.05
done
[ "$(json 'd["status"]' < "$TMP/m.json")" = cancelled ] || fail "cancelled mission that could not store its result: $(cat "$TMP/m.json")"
[ "$(json 'd["result"]' < "$TMP/m.json")" = none ] || fail "no result stored, yet: $(cat "$TMP/m.json")"
json 'd["message"]' < "$TMP/m.json" | grep -q "insufficient storage" || fail "no reason: $(cat "$TMP/m.json")"
[ "$(code "/api/missions/$RUN/result.json")" = 409 ] && grep -q no_result "$TMP/body" || fail "result of a run without one: $(cat "$TMP/body")"
[ -z "$(ls -A "$MNT/data/tmp")" ] || fail "half-written result files left in tmp/: $(ls "$MNT/data/tmp")"
alive || fail "the server died when a worker hit the full disk"
pass "the worker that hit the full disk left its cancelled mission without a result (\"$(json 'd["message"]' < "$TMP/m.json" | cut -c1-70)...\") and the server goes on"

# Restart on the still-full disk.
kill -TERM "$PID"; wait "$PID"; PID=""
fill 2
start
grep -q "warning:" "$TMP/log" || fail "no full-disk warning at start"
[ "$(api /api/maps | json 'len(d)')" = 1 ] || fail "restart on a full disk: maps not readable"
[ "$(api "/api/missions/$RUN" | json 'd["status"]')" = cancelled ] || fail "restart: the cancelled mission's row was lost"
pass "a restart on the full disk starts ($(grep warning: "$TMP/log" | cut -c1-70)) and reads work"

c=$(code "/api/maps/$MAP/pdms/$PDM" -X DELETE)
[ "$c" = 200 ] || fail "DELETE PDM on a full disk: $c $(cat "$TMP/body")"
c=$(code "/api/maps/$MAP" -X DELETE)
[ "$c" = 200 ] || fail "DELETE map on a full disk: $c $(cat "$TMP/body")"
[ "$(api /api/maps | json 'len(d)')" = 0 ] || fail "the map is still listed"
alive || fail "server died deleting on a full disk"
pass "DELETE of a PDM and a map works on the full disk"

rm -f "$MNT"/filler*
"$BIN" terrain --size 64 --cell 0.5 --seed 3 --out "$TMP/small.tif" >/dev/null 2>&1 || fail "terrain for the upload"
c=$(code "/api/maps?filename=small.tif&name=after" -X POST -H 'Content-Type: image/tiff' --data-binary @"$TMP/small.tif")
[ "$c" = 201 ] || fail "upload once space is free: $c $(cat "$TMP/body")"
MAP=$(json 'd["id"]' < "$TMP/body")
c=$(code /api/missions -H 'Content-Type: application/json' -d "$(mission 5 0.1 0)")
[ "$c" = 202 ] || fail "mission once space is free: $c $(cat "$TMP/body")"
NEW=$(json 'd["id"]' < "$TMP/body")
for _ in $(seq 1 200); do [ "$(api "/api/missions/$NEW" | json 'd["status"]')" = succeeded ] && break; sleep 0.05; done
[ "$(api "/api/missions/$NEW" | json 'd["status"]')" = succeeded ] || fail "mission after space freed: $(api "/api/missions/$NEW")"
pass "once space is free, uploads and missions work again"

echo "$passed passed, 0 failed"
