#!/usr/bin/env python3
"""A PDM's tiles and a layer's overview on a big map without loading it (issue 24), printed, never
asserted.

  tests/bench/pdm_window.py [ROVERPLAN ...] [--size 7000x7000] [--dem FILE]

The DEM is generated_dem.py's terrain (seed 24, 1 m cells: the ground big_map.py uploads), or
--dem FILE. For each binary (e.g. main's, then a
branch's), on a scratch data dir: one server imports the map and makes a {"random": 3, "seed": 1}
PDM, then stops; then for each request below a fresh server on that data dir answers it alone, so
its peak RSS (VmHWM) is that request's:
- the first PDM tile at the native zoom (the tile at the map's centre), then one at zoom 0;
- layers/elevation.png?max=1024 (the page's overview), and pdm.png?max=1024;
- layers/hillshade.tif (a full-size export: 413 where the map is too big to compute it in memory).
Seconds are the request's wall time; the server's RSS before the request is printed too."""
import http.client, json, os, shutil, socket, subprocess, sys, tempfile, time, urllib.request

here = os.path.dirname(os.path.abspath(__file__))
root = os.path.dirname(os.path.dirname(here))
args = sys.argv[1:]
opts = {"--size": "7000x7000", "--dem": ""}
binaries = []
while args:
    a = args.pop(0)
    if a in opts: opts[a] = args.pop(0)
    else: binaries.append(a)
binaries = binaries or [os.path.join(root, "build/bin/roverplan")]

sys.path.insert(0, here)
from generated_dem import make_dem  # noqa: E402


def free_port():
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


def mib(pid, key):
    with open(f"/proc/{pid}/status") as f:
        for line in f:
            if line.startswith(key + ":"):
                return int(line.split()[1]) / 1024
    return 0


class Server:
    def __init__(self, binary, data):
        self.port = free_port()
        self.proc = subprocess.Popen([binary, "serve", "--port", str(self.port), "--data", data, "--quiet"],
                                     stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
        self.base = f"http://127.0.0.1:{self.port}"
        for _ in range(600):
            try:
                urllib.request.urlopen(self.base + "/api/health")
                return
            except Exception:
                time.sleep(0.1)
        raise RuntimeError("the server did not start")

    def request(self, method, path, body=None, headers=None):
        conn = http.client.HTTPConnection("127.0.0.1", self.port, timeout=900)
        t = time.perf_counter()
        conn.request(method, path, body=body, headers=headers or {})
        r = conn.getresponse()
        data = r.read()
        return r.status, data, time.perf_counter() - t

    def stop(self):
        self.proc.terminate()
        self.proc.wait(timeout=60)


def one(binary, data, label, path):
    """`path` answered by a fresh server: status, seconds, bytes, peak RSS."""
    s = Server(binary, data)
    try:
        rss0 = mib(s.proc.pid, "VmRSS")
        status, body, secs = s.request("GET", path)
        peak = mib(s.proc.pid, "VmHWM")
        note = "" if status == 200 else " " + body[:160].decode(errors="replace")
        print(f"  {label:<34} {status} {secs:6.2f} s {len(body) / 1e3:8.0f} kB  peak RSS {peak:6.0f} MiB "
              f"(idle {rss0:.0f}){note}")
    finally:
        s.stop()


def run(binary, dem, work):
    print(f"-- {binary}")
    data = os.path.join(work, "data")
    shutil.rmtree(data, ignore_errors=True)
    s = Server(binary, data)
    try:
        with open(dem, "rb") as f:
            status, body, secs = s.request("POST", "/api/maps?name=big&filename=dem.tif", body=f,
                                           headers={"Content-Type": "image/tiff",
                                                    "Content-Length": str(os.path.getsize(dem))})
        if status != 201:
            print(f"  upload refused: {status} {body[:300]!r}")
            return
        m = json.loads(body)
        print(f"  import {secs:.1f} s")
        status, body, secs = s.request("POST", f"/api/maps/{m['id']}/pdms",
                                       body=json.dumps({"name": "bench", "random": 3, "seed": 1}),
                                       headers={"Content-Type": "application/json"})
        if status != 201:
            print(f"  PDM refused: {status} {body[:300]!r}")
            return
        pdm = json.loads(body)["id"]
        print(f"  PDM made in {secs:.1f} s")
    finally:
        s.stop()
    t = m["tiles"]
    n = t["native_zoom"]
    across, down = t["tile_counts"][n]
    mid = f"{n}/{across // 2}/{down // 2}"
    one(binary, data, f"pdm tile {mid}", f"/api/maps/{m['id']}/tiles/pdm/{mid}.png?pdm={pdm}")
    one(binary, data, "pdm tile 0/0/0", f"/api/maps/{m['id']}/tiles/pdm/0/0/0.png?pdm={pdm}")
    one(binary, data, "layers/elevation.png?max=1024", f"/api/maps/{m['id']}/layers/elevation.png?max=1024")
    one(binary, data, "layers/pdm.png?max=1024", f"/api/maps/{m['id']}/layers/pdm.png?max=1024&pdm={pdm}")
    one(binary, data, "layers/hillshade.tif", f"/api/maps/{m['id']}/layers/hillshade.tif")


work = tempfile.mkdtemp(prefix="roverplan-pdm-window-")
try:
    print(f"load average at start: {os.getloadavg()[0]:.2f} ({os.cpu_count()} cores)")
    if opts["--dem"]:
        dem = opts["--dem"]
    else:
        cols, rows = (int(v) for v in opts["--size"].split("x"))
        dem = make_dem(work, cols, rows)
        print(f"== {cols} x {rows} ({cols * rows / 1e6:.0f} M cells), generated by big_map.py's make_dem")
    for b in binaries:
        run(b, dem, work)
finally:
    shutil.rmtree(work, ignore_errors=True)
