#!/usr/bin/env python3
"""Tile API latency (issue 24), printed, never asserted.

  tests/bench/tile_latency.py [ROVERPLAN] [--size N] [--cell M] [--clients C] [--tiles T]

On a fresh `roverplan serve` (free loopback port, scratch data dir) with a generated N x N DEM
(default 4000, 0.5 m cells) uploaded and loaded (one tile fetched first, so the map is in memory):
- cold: T distinct tiles of the native zoom and of zoom 0..2 (rendered and written to the layer
  cache), fetched by C concurrent clients: p50, p99, max in ms, and the tile sizes;
- warm: the same tiles again (files from the cache): p50, p99, requests/s;
- 304: the same tiles with If-None-Match: p50.
The machine's load average is printed: on a shared machine compare runs made back to back."""
import concurrent.futures as cf, json, os, shutil, socket, statistics, subprocess, sys, tempfile, time
import urllib.request

root = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
args = sys.argv[1:]
opts = {"--size": "4000", "--cell": "0.5", "--clients": "16", "--tiles": "128"}
binary = os.path.join(root, "build/bin/roverplan")
while args:
    a = args.pop(0)
    if a in opts: opts[a] = args.pop(0)
    else: binary = a
size, clients, ntiles = int(opts["--size"]), int(opts["--clients"]), int(opts["--tiles"])


def free_port():
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


def get(url, headers=None):
    req = urllib.request.Request(url, headers=headers or {})
    t = time.perf_counter()
    try:
        with urllib.request.urlopen(req) as r:
            body, status, etag = r.read(), r.status, r.headers.get("ETag")
    except urllib.error.HTTPError as e:
        body, status, etag = e.read(), e.code, e.headers.get("ETag")
    return (time.perf_counter() - t) * 1000, status, len(body), etag


def server_cpu_s(pid):
    # utime + stime of the server process (all its threads), from /proc: the cost of a phase on a
    # shared machine, where its latency also measures the neighbours.
    with open(f"/proc/{pid}/stat") as f:
        fields = f.read().rsplit(")", 1)[1].split()
    return (int(fields[11]) + int(fields[12])) / os.sysconf("SC_CLK_TCK")


def pct(xs, q):
    xs = sorted(xs)
    return xs[min(len(xs) - 1, int(round(q * (len(xs) - 1))))]


work = tempfile.mkdtemp(prefix="roverplan-tiles-bench-")
server = None
try:
    dem = os.path.join(work, "dem.tif")
    subprocess.run([binary, "terrain", "--size", str(size), "--cell", opts["--cell"], "--out", dem], check=True,
                   stdout=subprocess.DEVNULL)
    port = free_port()
    server = subprocess.Popen([binary, "serve", "--port", str(port), "--data", os.path.join(work, "data"), "--quiet"],
                              stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
    base = f"http://127.0.0.1:{port}"
    for _ in range(300):
        try:
            urllib.request.urlopen(base + "/api/health")
            break
        except Exception:
            time.sleep(0.1)
    t = time.perf_counter()
    with open(dem, "rb") as f:
        req = urllib.request.Request(base + "/api/maps?name=bench&filename=dem.tif", data=f.read(),
                                     headers={"Content-Type": "image/tiff"}, method="POST")
    m = json.load(urllib.request.urlopen(req))
    print(f"upload + import of {size}x{size}: {(time.perf_counter() - t):.1f} s")
    # A map of 4 M cells or more is announced with its elevation raw and compressed afterwards
    # (storage "raw" -> "cog", on both cores): the cold tiles are measured on the stored COG, not
    # while the compression shares the cores.
    deadline = time.perf_counter() + 600
    while m.get("storage", {}).get("elevation") == "raw" and time.perf_counter() < deadline:
        time.sleep(0.1)
        m = json.load(urllib.request.urlopen(base + f"/api/maps/{m['id']}"))
    print(f"upload -> storage {m.get('storage', {}).get('elevation')}: {(time.perf_counter() - t):.1f} s")
    tiles = m["tiles"]
    url = base + f"/api/maps/{m['id']}/tiles/"
    first = get(url + "hillshade/0/0/0.png")  # loads the map into memory (not a tile's cost)
    print(f"first tile (map load + render): {first[0]:.0f} ms; zmax {tiles['zmax']}, native zoom {tiles['native_zoom']}")
    n = tiles["native_zoom"]
    across, down = tiles["tile_counts"][n]
    addrs = []
    for layer in ("elevation", "slope"):
        for k in range(ntiles // 2):
            addrs.append(f"{layer}/{n}/{(k * 7) % across}/{(k * 3 + k // across) % down}.png")
    addrs += [f"elevation/{z}/0/0.png" for z in range(1, min(3, n))]
    addrs = list(dict.fromkeys(addrs))

    def run(headers=None):
        t = time.perf_counter()
        with cf.ThreadPoolExecutor(clients) as ex:
            res = list(ex.map(lambda a: get(url + a, headers and headers(a)), addrs))
        return res, time.perf_counter() - t

    cpu0 = server_cpu_s(server.pid)
    cold, secs = run()
    cold_cpu = server_cpu_s(server.pid) - cpu0
    ms = [r[0] for r in cold]
    sizes = [r[2] for r in cold if r[1] == 200]
    print(f"cold, {len(addrs)} tiles, {clients} clients: p50 {pct(ms, .5):.1f} ms, p99 {pct(ms, .99):.1f} ms, "
          f"max {max(ms):.1f} ms, {len(addrs) / secs:.0f} tiles/s; statuses {sorted(set(r[1] for r in cold))}")
    print(f"server CPU per cold tile: {1000 * cold_cpu / len(addrs):.1f} ms")
    print(f"tile size: mean {statistics.mean(sizes) / 1024:.1f} KiB, max {max(sizes) / 1024:.1f} KiB")
    cpu0 = server_cpu_s(server.pid)
    warm, secs = run()
    warm_cpu = server_cpu_s(server.pid) - cpu0
    ms = [r[0] for r in warm]
    print(f"warm: p50 {pct(ms, .5):.2f} ms, p99 {pct(ms, .99):.2f} ms, {len(addrs) / secs:.0f} tiles/s; "
          f"server CPU per warm tile {1000 * warm_cpu / len(addrs):.1f} ms (the request and the file: "
          f"cold minus warm is a tile's making)")
    etags = {a: r[3] for a, r in zip(addrs, cold)}
    nm, secs = run(lambda a: {"If-None-Match": etags[a]})
    ms = [r[0] for r in nm]
    print(f"304: p50 {pct(ms, .5):.2f} ms; statuses {sorted(set(r[1] for r in nm))}")
    print(f"load average: {os.getloadavg()[0]:.2f}")
finally:
    if server:
        server.terminate()
        server.wait(timeout=30)
    shutil.rmtree(work, ignore_errors=True)
