#!/usr/bin/env bash
# The API contract passes the linters client generators are checked with (issue 28): the OpenAPI
# document a server answers at GET /api/openapi.json, linted by Redocly CLI (its recommended rules)
# and Spectral (spectral:oas), both as they come (tests/contract/redocly.yaml, spectral.yaml),
# with 0 errors and 0 warnings. The linters are the pinned npm packages of tests/contract
# (installed by `bash docker/setup-web.sh tests/contract`, which tests/run.sh runs); skipped (77)
# when they are not installed. Usage: contract_lint_test.sh path/to/roverplan
set -u
BIN=$1
HERE=$(cd "$(dirname "$0")/../contract" && pwd)
REDOCLY=$HERE/node_modules/.bin/redocly
SPECTRAL=$HERE/node_modules/.bin/spectral
[ -x "$REDOCLY" ] && [ -x "$SPECTRAL" ] || { echo "skipped: run bash docker/setup-web.sh tests/contract"; exit 77; }
TMP=$(mktemp -d "${TMPDIR:-/tmp}/roverplan_contract_lint.XXXXXX")
PID=""
cleanup() { [ -n "$PID" ] && kill -9 "$PID" 2>/dev/null; rm -rf "$TMP"; }
trap cleanup EXIT
passed=0
fail() { echo "FAIL: $*" >&2; echo "$passed passed, 1 failed"; exit 1; }
pass() { passed=$((passed + 1)); echo "ok: $*"; }

"$BIN" serve --port 0 --data "$TMP/data" --quiet > "$TMP/log" 2>&1 &
PID=$!
PORT=""
for _ in $(seq 1 6000); do  # a hang-only deadline (10 min): the server starts slowly on a loaded machine
  PORT=$(sed -n 's|.*http://127.0.0.1:\([0-9]*\)/.*|\1|p' "$TMP/log" | head -1)
  [ -n "$PORT" ] && curl -fs "http://127.0.0.1:$PORT/api/health" >/dev/null 2>&1 && break
  kill -0 "$PID" 2>/dev/null || { PORT=""; break; }  # it exited: no use waiting for it
  sleep 0.1
done
[ -n "$PORT" ] || fail "server did not start: $(tail -5 "$TMP/log")"
curl -fs "http://127.0.0.1:$PORT/api/openapi.json" -o "$TMP/openapi.json" || fail "GET /api/openapi.json"
kill "$PID" 2>/dev/null
wait "$PID" 2>/dev/null
PID=""

# Redocly: the JSON report's totals; Spectral: its JSON list of findings (errors are severity 0,
# warnings 1). Node prints deprecation banners on stderr: kept apart from the reports.
export NO_COLOR=1 REDOCLY_TELEMETRY=off REDOCLY_SUPPRESS_UPDATE_NOTICE=true
(cd "$HERE" && "$REDOCLY" lint "$TMP/openapi.json" --config redocly.yaml --format json) > "$TMP/redocly.json" 2> "$TMP/redocly.err"
counts=$(python3 -c "import json,sys; t=json.load(open(sys.argv[1]))['totals']; print(t['errors'], t['warnings'])" \
  "$TMP/redocly.json") || fail "no Redocly report: $(tail -5 "$TMP/redocly.err")"
read -r errors warnings <<< "$counts"
echo "redocly lint (recommended): $errors errors, $warnings warnings"
if [ "$errors" != 0 ] || [ "$warnings" != 0 ]; then
  (cd "$HERE" && "$REDOCLY" lint "$TMP/openapi.json" --config redocly.yaml --format stylish 2>/dev/null) | head -40
  fail "redocly lint: $errors errors, $warnings warnings"
fi
pass "redocly lint: 0 errors, 0 warnings"

(cd "$HERE" && "$SPECTRAL" lint "$TMP/openapi.json" -r spectral.yaml -f json --quiet) > "$TMP/spectral.json" 2> "$TMP/spectral.err"
counts=$(python3 -c "
import json,sys
d=json.load(open(sys.argv[1]))
print(sum(1 for x in d if x['severity']==0), sum(1 for x in d if x['severity']==1))
for x in d[:40]:
    if x['severity'] <= 1: print('  ', x['code'], '.'.join(map(str, x['path'])), '-', x['message'], file=sys.stderr)
" "$TMP/spectral.json") || fail "no Spectral report: $(tail -5 "$TMP/spectral.err")"
read -r errors warnings <<< "$counts"
echo "spectral lint (spectral:oas): $errors errors, $warnings warnings"
[ "$errors" = 0 ] && [ "$warnings" = 0 ] || fail "spectral lint: $errors errors, $warnings warnings"
pass "spectral lint: 0 errors, 0 warnings"
echo "$passed passed, 0 failed"
