#!/usr/bin/env python3
"""Mission budgets (issue 22, "budgets that are true"), printed, never asserted: for each mission
below, the admission estimate (read from a 413 of a server whose budget is 1 MiB), then on a fresh
`roverplan serve` the peak resident size over the idle server while it runs (sampled every 20 ms
from /proc), the ratio, the cancel latency (DELETE until the status is final) when it is cancelled,
the result files and the resident size 2 s after it ended against the one before it started.

  tests/bench/mission_budget.py [ROVERPLAN] [--only NAME] [--cancel-after S] [--budget-mb M]

A mission that is refused (413) is printed with the reason. On a shared machine the figures in
MiB hold; times vary with the load (printed first)."""
import json, os, re, shutil, socket, subprocess, sys, tempfile, time, urllib.request

root = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
args = sys.argv[1:]
binary = args.pop(0) if args and not args[0].startswith("--") else os.path.join(root, "build/bin/roverplan")
opts = {"--only": None, "--cancel-after": None, "--budget-mb": None}
while args:
    k = args.pop(0)
    opts[k] = args.pop(0)


def rovers(n, x0=60.5, y0=60.5, step=4.0, per_row=8):
    return [{"x": x0 + step * (k % per_row), "y": y0 + step * (k // per_row), "heading": 0} for k in range(n)]


# name, planner, rovers, params, cancel after (s; None: runs to its end)
MISSIONS = [
    ("issue-22 coverage (no max_steps)", "coverage", rovers(4), {"frontier": False, "coverage": 1}, None),
    ("issue-22 coverage max_steps 1e9", "coverage", rovers(4), {"frontier": False, "coverage": 1, "max_steps": 1e9}, 3),
    ("issue-22 coverage max_steps 1e6, cancelled", "coverage", rovers(4), {"frontier": False, "coverage": 1, "max_steps": 1000000}, 3),
    ("coverage overlap 4 rovers", "coverage", rovers(4), {"frontier": False, "coverage": 1, "max_steps": 20000}, None),
    ("coverage voronoi 4 rovers", "coverage", rovers(4), {"frontier": False, "coverage": 1, "mode": "voronoi", "max_steps": 20000}, None),
    ("coverage frontier 2 rovers", "coverage", rovers(2), {"frontier": True, "coverage": 1}, None),
    ("coverage localisation 2 rovers", "coverage", rovers(2), {"frontier": False, "coverage": 1, "odometry_noise": 2.0, "heading_noise": 0.5, "max_steps": 20000}, None),
    ("coverage 0.25 m 1 rover", "coverage", rovers(1), {"coverage_cell": 0.25, "frontier": False, "coverage": 1}, None),
    ("team-search 2 rovers 6 targets", "team-search", rovers(2), {"targets": 6}, None),
    ("team-search 8 rovers 64 targets", "team-search", rovers(8), {"targets": 64}, None),
    ("hybrid 2 rovers 3 targets", "hybrid", rovers(2), {"targets": 3}, None),
    ("team-search 64 rovers 10000 targets, cancelled", "team-search", rovers(64, 30.5, 30.5, 3.0, 16), {"targets": 10000}, 10),
]


class Server:
    def __init__(self, extra=()):
        self.data = tempfile.mkdtemp(prefix="mission-budget-")
        s = socket.socket(); s.bind(("127.0.0.1", 0)); self.port = s.getsockname()[1]; s.close()
        self.proc = subprocess.Popen([binary, "serve", "--port", str(self.port), "--data", self.data, "--quiet", *extra],
                                     stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
        for _ in range(600):
            try:
                if self.call("GET", "/api/health")[0] == 200: break
            except OSError: time.sleep(0.1)
        self.map = self.call("GET", "/api/maps")[1][0]["id"]

    def call(self, method, path, body=None):
        req = urllib.request.Request(f"http://127.0.0.1:{self.port}{path}", method=method,
                                     data=None if body is None else json.dumps(body).encode(),
                                     headers={"Content-Type": "application/json"})
        try:
            with urllib.request.urlopen(req, timeout=300) as r:
                return r.status, json.loads(r.read() or b"null")
        except urllib.error.HTTPError as e:
            return e.code, json.loads(e.read() or b"null")

    def rss(self, key="VmRSS"):
        for line in open(f"/proc/{self.proc.pid}/status"):
            if line.startswith(key + ":"): return int(line.split()[1]) / 1024
        return 0.0

    def stop(self):
        self.proc.terminate(); self.proc.wait(); shutil.rmtree(self.data, ignore_errors=True)


def mib(text):
    m = re.search(r"needs about ([0-9.]+) (MiB|GiB|TiB)", text)
    if not m: return None
    return float(m.group(1)) * {"MiB": 1, "GiB": 1024, "TiB": 1024 * 1024}[m.group(2)]


print("load:", os.getloadavg(), "binary:", binary)
chosen = [m for m in MISSIONS if not opts["--only"] or opts["--only"] in m[0]]
probe = Server(["--mission-memory-mb", "1"])
estimates = {}
for name, planner, rv, params, _ in chosen:
    st, j = probe.call("POST", "/api/missions", {"map": probe.map, "planner": planner, "rovers": rv, "params": params})
    estimates[name] = mib(j["error"]["message"]) if st == 413 else None
probe.stop()

extra = ["--mission-memory-mb", opts["--budget-mb"]] if opts["--budget-mb"] else []
for name, planner, rv, params, cancel_after in chosen:
    if opts["--cancel-after"]: cancel_after = float(opts["--cancel-after"])
    srv = Server(extra)
    time.sleep(1.0)
    idle = srv.rss()
    st, m = srv.call("POST", "/api/missions", {"map": srv.map, "planner": planner, "rovers": rv, "params": params})
    if st != 202:
        print(f"{name}: {st} {m['error']['code']} ({m['error']['field']}): {m['error']['message']}")
        srv.stop(); continue
    mid, t0, peak, status, cancel_s = m["id"], time.time(), idle, "queued", None
    while status in ("queued", "running"):
        peak = max(peak, srv.rss())
        if cancel_after is not None and cancel_s is None and time.time() - t0 >= cancel_after:
            tc = time.time(); srv.call("DELETE", f"/api/missions/{mid}"); cancel_s = -tc
        status = srv.call("GET", f"/api/missions/{mid}")[1]["status"]
        time.sleep(0.02)
    if cancel_s is not None: cancel_s += time.time()
    ran = time.time() - t0
    time.sleep(2.0)
    peak = max(peak, srv.rss("VmHWM"))
    after = srv.rss()
    files = sum(os.path.getsize(os.path.join(d, f)) for d, _, fs in os.walk(os.path.join(srv.data, "missions")) for f in fs)
    est = estimates.get(name)
    ratio = f"{(peak - idle) / est:.2f}x" if est else "-"
    print(f"{name}: {status} in {ran:.1f} s; estimate {est} MiB; peak {peak - idle:.0f} MiB over idle "
          f"{idle:.0f} MiB ({ratio}); cancel {'-' if cancel_s is None else f'{cancel_s:.2f} s'}; "
          f"after {after:.0f} MiB ({(after - idle) / idle * 100:+.0f} %); files {files / 1e6:.1f} MB", flush=True)
    srv.stop()
