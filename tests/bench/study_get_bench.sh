#!/usr/bin/env bash
# Cheap reads under a hostile loop (issue 22), printed, never asserted:
#   1. GET /api/studies/{id} of a 200 k-run study (laine-fig6, 50 000 runs per configuration):
#      the first GET after a start and the median / worst of the next 20;
#   2. while 20 clients on 127.0.0.1 loop on that GET, the latency of a PDM upload, a mission launch
#      and a layer render from another client (127.0.0.2), against the same three when idle.
# The study database is built once (a 1/50 shard run for real, its rows copied to 200 000 runs:
# the summary's cost depends on the number of rows, not on what they hold) and reused by both
# binaries. Usage: tests/bench/study_get_bench.sh path/to/roverplan [path/to/older/roverplan]
#   (env: RUNS_PER_CONFIG, default 50000; LOOPERS, default 20)
set -euo pipefail
BIN=${1:?usage: study_get_bench.sh path/to/roverplan [older roverplan]}
OLD=${2:-}
RUNS=${RUNS_PER_CONFIG:-50000}
LOOPERS=${LOOPERS:-20}
TMP=$(mktemp -d)
PID=""
cleanup() { [ -n "$PID" ] && kill "$PID" 2>/dev/null; wait 2>/dev/null; rm -rf "$TMP"; }
trap cleanup EXIT
echo "load: $(uptime)"

# The study database: shard 0 of 50 run for real, then its rows copied to fill every run index.
"$BIN" study run --preset laine-fig6 --runs "$RUNS" --shard 0/50 --threads 2 --quiet --out "$TMP/study.sqlite"
python3 - "$TMP/study.sqlite" <<'PY'
import sqlite3, sys
db = sqlite3.connect(sys.argv[1])
total = len(db.execute("SELECT config_id FROM configs").fetchall()) * __import__("json").loads(db.execute("SELECT spec FROM study").fetchone()[0])["runs"]
cols = [r[1] for r in db.execute("PRAGMA table_info(runs)")]
rows = db.execute("SELECT * FROM runs").fetchall()
have = {r[0] for r in rows}
free = (i for i in range(total) if i not in have)
batch = []
k = 0
for i in free:
    r = list(rows[k % len(rows)]); k += 1
    r[0] = i
    batch.append(r)
db.executemany(f"INSERT INTO runs VALUES ({','.join('?' * len(cols))})", batch)
db.commit()
print(f"study database: {db.execute('SELECT count(*) FROM runs').fetchone()[0]} runs of {total}")
PY

# A data dir holding that study as ended, as a server would have left it.
make_data() {
  local d=$1 id=0123456789abcdef
  mkdir -p "$d/studies/$id"
  cp "$TMP/study.sqlite" "$d/studies/$id/study.sqlite"
  sqlite3 "$d/studies/$id/study.sqlite" "SELECT spec FROM study" > "$d/studies/$id/spec.json"
  python3 - "$d/studies/$id/state.json" "$id" <<'PY'
import json, sys
json.dump({"id": sys.argv[2], "name": "laine-fig6", "status": "succeeded", "message": "", "created_at": "2026-01-01T00:00:00Z",
           "started_at": "2026-01-01T00:00:00Z", "finished_at": "2026-01-01T00:10:00Z", "runs_done": 200000,
           "runs_total": 200000}, open(sys.argv[1], "w"))
PY
}

run_bench() {
  local bin=$1 label=$2 d="$TMP/data-$2"
  make_data "$d"
  "$bin" serve --data "$d" --port 0 --quiet > "$TMP/log-$label" 2>&1 &
  PID=$!
  local port=""
  for _ in $(seq 1 600); do
    port=$(grep -o 'http://127.0.0.1:[0-9]*' "$TMP/log-$label" | head -1 | sed 's/.*://') || true
    [ -n "$port" ] && break
    sleep 0.1
  done
  [ -n "$port" ] || { echo "$label: the server did not start: $(cat "$TMP/log-$label")"; return 1; }
  python3 - "$port" "$label" "$LOOPERS" <<'PY'
import http.client, json, statistics, sys, threading, time
port, label, loopers = int(sys.argv[1]), sys.argv[2], int(sys.argv[3])
study = "/api/studies/0123456789abcdef"
def call(method, path, body=None, source="127.0.0.1", ctype="application/json"):
    c = http.client.HTTPConnection("127.0.0.1", port, timeout=600, source_address=(source, 0))
    t = time.perf_counter()
    c.request(method, path, body=body, headers={"Content-Type": ctype} if body is not None else {})
    r = c.getresponse(); data = r.read(); c.close()
    return time.perf_counter() - t, r.status, data
first, st, body = call("GET", study)
assert st == 200, body[:200]
runs = json.loads(body)["summary"]["runs_done"]
times = [call("GET", study)[0] for _ in range(20)]
print(f"{label}: GET study ({runs} runs): first {first*1000:.0f} ms, then median {statistics.median(times)*1000:.1f} ms, "
      f"worst {max(times)*1000:.1f} ms (20 GETs)")
maps = json.loads(call("GET", "/api/maps")[2])
m = maps[0]["id"]
n = [0]
def others(source):
    # An upload (a PDM), a launch (a coverage mission) and a render (a PNG overview not cached yet).
    n[0] += 1
    up = call("POST", f"/api/maps/{m}/pdms", json.dumps({"random": 3, "seed": n[0]}), source)
    launch = call("POST", "/api/missions", json.dumps({"map": m, "planner": "coverage",
                  "rovers": [{"x": 10.5, "y": 10.5, "heading": 0}], "params": {"coverage": 0.05}}), source)
    pdm = json.loads(up[2])["id"]
    render = call("GET", f"/api/maps/{m}/layers/pdm.png?max=512&pdm={pdm}", None, source)
    return up, launch, render
def show(what, res):
    print(f"{label}: {what}: PDM upload {res[0][0]*1000:.0f} ms ({res[0][1]}), mission launch {res[1][0]*1000:.0f} ms "
          f"({res[1][1]}), layer render {res[2][0]*1000:.0f} ms ({res[2][1]})")
show("idle", others("127.0.0.2"))
stop = threading.Event(); gets = [0]
def loop():
    while not stop.is_set():
        call("GET", study); gets[0] += 1
threads = [threading.Thread(target=loop) for _ in range(loopers)]
for t in threads: t.start()
time.sleep(2)
show(f"{loopers} clients looping on the study GET", others("127.0.0.2"))
stop.set()
for t in threads: t.join()
print(f"{label}: the loopers made {gets[0]} GETs")
PY
  kill "$PID"; wait "$PID" 2>/dev/null || true; PID=""
}

[ -n "$OLD" ] && run_bench "$OLD" before
run_bench "$BIN" after
echo "load: $(uptime)"
