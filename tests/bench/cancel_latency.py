#!/usr/bin/env python3
"""Cancel latency and memory returned (issue 22, "budgets that are true"), printed, never asserted.

  tests/bench/cancel_latency.py [ROVERPLAN ...] [--cancel-after S,S,...] [--repeat N] [--skip-rss]

For each binary given (default build/bin/roverplan; give two to compare a before and an after back
to back on the same inputs), on a fresh `roverplan serve` on a free loopback port:

- cancel: the issue's coverage mission (default map, frontier off, coverage 1, max_steps 1e6,
  4 rovers) cancelled S seconds after it started running. Printed: the DELETE's round trip, the
  time from sending the DELETE until GET /api/missions/{id} shows a final status, the time until
  its partial result is stored (the mission's `result` is no longer "pending"; a server without
  that field stores it before the status turns final), what GET result.json answered right after
  the final status (200, or a 409 with its code: never a truncated file), and the result's size.
- rss: VmRSS of the server before a mission (after a one-step warm-up mission on the same map,
  so the map's own caches are loaded) and once the mission has ended and its result is stored, for
  a coverage mission and a team mission (swinton's lhc_gw_conv route), each on a fresh server.

The machine's load average is printed with every line: on a shared machine compare a before and
an after measured back to back."""
import json, os, shutil, socket, subprocess, sys, tempfile, time, urllib.request

root = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
args = sys.argv[1:]
binaries = []
opts = {"--cancel-after": "3,10", "--repeat": "1", "--skip-rss": False}
while args:
    a = args.pop(0)
    if a == "--skip-rss": opts[a] = True
    elif a.startswith("--"): opts[a] = args.pop(0)
    else: binaries.append(a)
binaries = binaries or [os.path.join(root, "build/bin/roverplan")]
FINAL = {"succeeded", "completed_with_warnings", "failed", "cancelled", "interrupted"}


def rovers(n):
    return [{"x": 60.5 + 4.0 * (k % 4), "y": 60.5 + 4.0 * (k // 4), "heading": 0} for k in range(n)]


COVERAGE = {"planner": "coverage", "rovers": rovers(4),
            "params": {"frontier": False, "coverage": 1, "max_steps": 1000000}}
RSS_MISSIONS = [
    ("coverage 4 rovers max_steps 20000", {"planner": "coverage", "rovers": rovers(4),
                                           "params": {"frontier": False, "coverage": 1, "max_steps": 20000}},
     {"max_steps": 1}),
    ("team-search lhc_gw_conv 4 rovers", {"planner": "team-search", "rovers": rovers(4),
                                          "params": {"route": "lhc_gw_conv"}}, {"targets": 1}),
]


def load():
    return "load %.2f %.2f %.2f" % os.getloadavg()


class Server:
    def __init__(self, binary):
        self.data = tempfile.mkdtemp(prefix="cancel-latency-")
        s = socket.socket(); s.bind(("127.0.0.1", 0)); self.port = s.getsockname()[1]; s.close()
        self.proc = subprocess.Popen([binary, "serve", "--port", str(self.port), "--data", self.data, "--quiet"],
                                     stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
        for _ in range(600):
            try:
                if self.call("GET", "/api/health")[0] == 200: break
            except OSError: time.sleep(0.1)
        self.map = self.call("GET", "/api/maps")[1][0]["id"]

    def call(self, method, path, body=None, raw=False):
        req = urllib.request.Request(f"http://127.0.0.1:{self.port}{path}", method=method,
                                     data=None if body is None else json.dumps(body).encode(),
                                     headers={"Content-Type": "application/json"})
        try:
            with urllib.request.urlopen(req, timeout=300) as r:
                data = r.read()
                return r.status, (data if raw else json.loads(data or b"null"))
        except urllib.error.HTTPError as e:
            return e.code, json.loads(e.read() or b"null")

    def launch(self, body):
        st, m = self.call("POST", "/api/missions", dict(body, map=self.map))
        assert st == 202, (st, m)
        return m["id"]

    def mission(self, mid):
        return self.call("GET", f"/api/missions/{mid}")[1]

    def wait_stored(self, mid):
        while True:
            m = self.mission(mid)
            if m["status"] in FINAL and m.get("result") != "pending": return m
            time.sleep(0.01)

    def rss(self):
        for line in open(f"/proc/{self.proc.pid}/status"):
            if line.startswith("VmRSS:"): return int(line.split()[1]) / 1024
        return 0.0

    def files(self):
        return sum(os.path.getsize(os.path.join(d, f)) for d, _, fs in os.walk(os.path.join(self.data, "missions")) for f in fs)

    def stop(self):
        self.proc.terminate(); self.proc.wait(); shutil.rmtree(self.data, ignore_errors=True)


def cancel_once(binary, after):
    srv = Server(binary)
    mid = srv.launch(COVERAGE)
    while srv.mission(mid)["status"] == "queued": time.sleep(0.01)
    time.sleep(after)  # how far the mission gets (how big its partial result is), not a wait for an event
    t0 = time.monotonic()
    st, _ = srv.call("DELETE", f"/api/missions/{mid}")
    t_delete = time.monotonic() - t0
    while True:
        m = srv.mission(mid)
        if m["status"] in FINAL: break
    t_final = time.monotonic() - t0
    code, body = srv.call("GET", f"/api/missions/{mid}/result.json", raw=True)
    first = "200 (%.1f MB)" % (len(body) / 1e6) if code == 200 else f"{code} {body['error']['code']}"
    m = srv.wait_stored(mid)
    t_stored = time.monotonic() - t0
    code, body = srv.call("GET", f"/api/missions/{mid}/result.json", raw=True)
    stored = "%.1f MB result.json, %d moves" % (len(body) / 1e6, sum(len(r["path"]) for r in json.loads(body)["rovers"])) \
        if code == 200 else f"{code} {body['error']['code']}"
    print(f"  cancel after {after:>4} s: DELETE {st} in {t_delete:.3f} s; final ({m['status']}) at {t_final:.3f} s; "
          f"result.json then: {first}; stored at {t_stored:.3f} s ({stored}; files {srv.files() / 1e6:.1f} MB); {load()}",
          flush=True)
    srv.stop()


def rss_once(binary, name, body, warm_params):
    srv = Server(binary)
    srv.wait_stored(srv.launch(dict(body, params=dict(body["params"], **warm_params))))
    time.sleep(1.0)  # let the warm-up's trim settle before the baseline
    before = srv.rss()
    mid = srv.launch(body)
    peak = before
    while True:
        m = srv.mission(mid)
        peak = max(peak, srv.rss())
        if m["status"] in FINAL and m.get("result") != "pending": break
        time.sleep(0.02)
    ended = srv.rss()
    time.sleep(2.0)
    after = srv.rss()
    print(f"  {name}: {m['status']}; RSS before {before:.1f} MiB, peak {peak:.1f}, at the end {ended:.1f} "
          f"({(ended - before) / before * 100:+.1f} %), 2 s later {after:.1f} ({(after - before) / before * 100:+.1f} %); {load()}",
          flush=True)
    srv.stop()


for rep in range(int(opts["--repeat"])):
    for after in [float(x) for x in opts["--cancel-after"].split(",") if x]:
        for b in binaries:
            print(f"{b}:", flush=True)
            cancel_once(b, after)
    if not opts["--skip-rss"]:
        for name, body, warm in RSS_MISSIONS:
            for b in binaries:
                print(f"{b}:", flush=True)
                rss_once(b, name, body, warm)
