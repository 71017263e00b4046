#!/usr/bin/env python3
"""Full-size DEMs through the server (issue 24), printed, never asserted.

  tests/bench/big_map.py [ROVERPLAN ...] [--sizes 7000x7000,20000x15000] [--clients 16] [--tiles 128]
                         [--dem FILE] [--rounds N]

With --dem, that file is uploaded instead of a generated DEM (one "size"); with --rounds N, the
binaries take turns N times (A B A B ...), for before/after figures on a shared machine.

With several binaries (e.g. main's and a branch's), each size's DEM is made once and put through
each binary in turn, on its own fresh server: a side-by-side from one sitting on the same input.

For each size, a deterministic DEM (seed 24, generated_dem.py: GDAL's command-line tools alone,
1 m cells, a UTM CRS) is made. Then, on a fresh
`roverplan serve` (free loopback port, scratch data dir, default limits):
- upload -> first tiles: seconds from the start of the upload until the z = 0 tile and a native
  tile (elevation, hillshade) have both been answered;
- upload -> storage cog: until the map's record says its elevation is the COG (a large map is
  announced raw and compressed in the background);
- peak RSS of the server process during the import (VmHWM from /proc, reset is not possible, so
  each size runs on its own server), and of the import worker (the jail's child, sampled);
- cold tiles: T distinct tiles over every zoom (native and below, elevation/hillshade/slope/
  traversability) fetched by C concurrent clients: p50, p99, max in ms;
- warm: the same tiles again (files of the layer cache): requests/s;
- the stored DEM's layout (gdalinfo: block size, overviews, compression) and its size on disk.
The machine's load average is printed: on a shared machine compare runs made back to back."""
import concurrent.futures as cf, http.client, json, os, random, shutil, socket, subprocess, sys, tempfile
import threading, time, urllib.request

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from generated_dem import make_dem  # noqa: E402

root = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
args = sys.argv[1:]
opts = {"--sizes": "7000x7000,20000x15000", "--clients": "16", "--tiles": "128", "--dem": "", "--rounds": "1"}
binaries = []
while args:
    a = args.pop(0)
    if a in opts: opts[a] = args.pop(0)
    else: binaries.append(a)
binaries = binaries or [os.path.join(root, "build/bin/roverplan")]
clients, ntiles = int(opts["--clients"]), int(opts["--tiles"])


def free_port():
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


def pct(xs, q):
    xs = sorted(xs)
    return xs[min(len(xs) - 1, int(round(q * (len(xs) - 1))))]


def cpu_of(pid, children=True):
    """User and system CPU seconds of `pid`, and of its reaped children (an import worker run
    without bubblewrap; under bwrap, bwrap reaps it and the server never counts it)."""
    try:
        with open(f"/proc/{pid}/stat") as f:
            fields = f.read().rsplit(")", 1)[1].split()
        return sum(int(v) for v in fields[11:15 if children else 13]) / os.sysconf("SC_CLK_TCK")
    except OSError:
        return 0.0


def status_of(pid):
    try:
        with open(f"/proc/{pid}/status") as f:
            return {l.split(":")[0]: l.split(":")[1].strip() for l in f if ":" in l}
    except OSError:
        return {}


def kib(s, key):
    v = s.get(key, "0 kB").split()[0]
    return int(v)


def import_workers():
    """The pids of running `roverplan import-worker` processes (under bwrap or not)."""
    out = []
    for p in os.listdir("/proc"):
        if p.isdigit():
            try:
                with open(f"/proc/{p}/cmdline", "rb") as f:
                    argv = f.read().split(b"\0")
                # bwrap's own command line names the worker too: only the worker itself.
                if b"import-worker" in argv and not argv[0].endswith(b"bwrap") and int(p) != os.getpid():
                    out.append(int(p))
            except OSError:
                pass
    return out


def get(url, headers=None):
    req = urllib.request.Request(url, headers=headers or {})
    t = time.perf_counter()
    try:
        with urllib.request.urlopen(req, timeout=600) as r:
            body, status = r.read(), r.status
    except urllib.error.HTTPError as e:
        body, status = e.read(), e.code
    return (time.perf_counter() - t) * 1000, status, len(body)


def bench(work, cols, rows):
    if opts["--dem"]:
        dem = opts["--dem"]
        print(f"== {dem}: {os.path.getsize(dem) / 1e6:.0f} MB upload")
    else:
        print(f"== {cols} x {rows} ({cols * rows / 1e6:.0f} M cells, 1 m)")
        t = time.perf_counter()
        dem = make_dem(work, cols, rows)
        print(f"generated with gdal in {time.perf_counter() - t:.0f} s: {os.path.getsize(dem) / 1e6:.0f} MB upload")
    for round in range(int(opts["--rounds"])):
        for binary in binaries:
            if len(binaries) > 1 or round:
                print(f"-- {binary}" + (f" (round {round + 1})" if int(opts["--rounds"]) > 1 else ""))
            serve(work, dem, binary)


def serve(work, dem, binary):
    port = free_port()
    data = os.path.join(work, "data")
    server = subprocess.Popen([binary, "serve", "--port", str(port), "--data", data, "--quiet"],
                              stdout=subprocess.DEVNULL, stderr=subprocess.PIPE)
    try:
        base = f"http://127.0.0.1:{port}"
        for _ in range(600):
            try:
                urllib.request.urlopen(base + "/api/health")
                break
            except Exception:
                time.sleep(0.1)
        rss_before = kib(status_of(server.pid), "VmRSS")
        log = []  # the server's stderr: its one line per import names the stages

        def drain():
            for line in server.stderr:
                log.append(line.decode(errors="replace").rstrip())

        threading.Thread(target=drain, daemon=True).start()
        cpu0 = cpu_of(server.pid)
        worker_peak = [0]
        worker_cpu = {}  # pid -> its last CPU seconds seen (the server never sees them: bwrap reaps it)
        done = threading.Event()

        def sample():  # the import worker's resident size and CPU (a child of the server), every 50 ms
            while not done.is_set():
                for c in import_workers():
                    worker_peak[0] = max(worker_peak[0], kib(status_of(c), "VmRSS"))
                    worker_cpu[c] = max(worker_cpu.get(c, 0.0), cpu_of(c, children=False))
                time.sleep(0.05)

        sampler = threading.Thread(target=sample)
        sampler.start()
        t0 = time.perf_counter()
        conn = http.client.HTTPConnection("127.0.0.1", port, timeout=900)
        with open(dem, "rb") as f:
            conn.request("POST", "/api/maps?name=big&filename=dem.tif", body=f,
                         headers={"Content-Type": "image/tiff", "Content-Length": str(os.path.getsize(dem))})
            r = conn.getresponse()
            body = r.read()
        t_import = time.perf_counter() - t0
        if r.status != 201:
            print(f"upload refused: {r.status} {body[:300]!r}")
            return
        m = json.loads(body)
        tiles = m["tiles"]
        n = tiles["native_zoom"]
        url = base + f"/api/maps/{m['id']}/tiles/"
        across, down = tiles["tile_counts"][n]
        first = [f"elevation/0/0/0.png", f"hillshade/0/0/0.png",
                 f"elevation/{n}/{across // 2}/{down // 2}.png", f"hillshade/{n}/{across // 2}/{down // 2}.png"]
        with cf.ThreadPoolExecutor(4) as ex:
            firsts = list(ex.map(lambda a: get(url + a), first))
        t_first = time.perf_counter() - t0
        cpu_first = cpu_of(server.pid) - cpu0
        done.set()
        sampler.join()
        st = status_of(server.pid)
        # A large map is announced with its elevation raw and compressed afterwards (storage
        # "raw" -> "cog"): when its dem.tif is there, counted from the start of the upload.
        while True:
            with urllib.request.urlopen(base + f"/api/maps/{m['id']}") as resp:
                elevation = json.loads(resp.read()).get("storage", {}).get("elevation")
            if elevation != "raw":
                break
            time.sleep(0.2)
        t_cog = time.perf_counter() - t0
        rss_cog = kib(status_of(server.pid), "VmHWM")
        cpu_worker = sum(worker_cpu.values())
        print(f"upload + import: {t_import:.1f} s; upload -> first tiles (z=0 and native, elevation and hillshade): "
              f"{t_first:.1f} s (cpu {cpu_first + cpu_worker:.1f} s: server {cpu_first:.1f} s, import worker "
              f"{cpu_worker:.1f} s sampled); statuses {[x[1] for x in firsts]}")
        for line in log:
            if line.startswith("import ") or line.startswith("compressed "):
                print("  stages: " + line)
        print(f"upload -> storage cog: {t_cog:.1f} s (announced {m.get('storage', {}).get('elevation')}); "
              f"server peak RSS by then {rss_cog / 1024:.0f} MiB")
        print(f"server peak RSS {kib(st, 'VmHWM') / 1024:.0f} MiB (before the upload {rss_before / 1024:.0f} MiB); "
              f"import worker peak RSS (sampled) {worker_peak[0] / 1024:.0f} MiB")
        stored = os.path.join(data, "maps", m["id"], "dem.tif")
        info = subprocess.run(["gdalinfo", stored], capture_output=True, text=True).stdout
        layout = [l.strip() for l in info.splitlines() if "Block=" in l or "Overviews:" in l or "COMPRESSION" in l
                  or "LAYOUT" in l][:4]
        print(f"stored dem.tif: {os.path.getsize(stored) / 1e6:.0f} MB; " + "; ".join(x[:120] for x in layout))
        # Cold tiles: spread over every zoom up to the native one, four layers.
        rnd = random.Random(7)
        addrs = []
        layers = ("elevation", "hillshade", "slope", "traversability")
        while len(addrs) < ntiles:
            z = rnd.choice([n, n, n - 1, n - 2] + list(range(0, max(1, n - 2))))
            a, d = tiles["tile_counts"][z]
            addr = f"{rnd.choice(layers)}/{z}/{rnd.randrange(a)}/{rnd.randrange(d)}.png"
            if addr not in addrs and addr not in first:
                addrs.append(addr)

        def run(n=clients, todo=None):
            todo = todo or addrs
            t = time.perf_counter()
            with cf.ThreadPoolExecutor(n) as ex:
                res = list(ex.map(lambda a: get(url + a), todo))
            return res, time.perf_counter() - t

        # One client first, on other tiles: a cold tile's own service time, without queueing.
        solo_addrs = []
        while len(solo_addrs) < 24:
            z = rnd.choice(range(0, n + 1))
            a, d = tiles["tile_counts"][z]
            addr = f"{rnd.choice(layers)}/{z}/{rnd.randrange(a)}/{rnd.randrange(d)}.png"
            if addr not in addrs and addr not in first and addr not in solo_addrs:
                solo_addrs.append(addr)
        solo, _ = run(1, solo_addrs)
        ms = [x[0] for x in solo]
        print(f"cold, one client, {len(solo_addrs)} tiles over zooms 0..{n}: p50 {pct(ms, .5):.1f} ms, "
              f"p99 {pct(ms, .99):.1f} ms")

        cpu0 = cpu_of(server.pid)
        cold, secs = run()
        cpu_cold = cpu_of(server.pid) - cpu0
        ms = [x[0] for x in cold]
        print(f"cold, {len(addrs)} tiles over zooms 0..{n}, {clients} clients: p50 {pct(ms, .5):.1f} ms, "
              f"p99 {pct(ms, .99):.1f} ms, max {max(ms):.1f} ms, {len(addrs) / secs:.0f} tiles/s, cpu {1000 * cpu_cold / len(addrs):.1f} ms a tile; "
              f"statuses {sorted(set(x[1] for x in cold))}")
        warm, secs = run()
        ms = [x[0] for x in warm]
        print(f"warm, {clients} clients: p50 {pct(ms, .5):.2f} ms, p99 {pct(ms, .99):.2f} ms, "
              f"{len(addrs) / secs:.0f} requests/s")
        print(f"server peak RSS after the tiles {kib(status_of(server.pid), 'VmHWM') / 1024:.0f} MiB; "
              f"load average {os.getloadavg()[0]:.2f}")
    finally:
        server.terminate()
        server.wait(timeout=60)
        shutil.rmtree(os.path.join(work, "data"), ignore_errors=True)


work = tempfile.mkdtemp(prefix="roverplan-big-map-")
try:
    print(f"load average at start: {os.getloadavg()[0]:.2f} ({os.cpu_count()} cores)")
    for size in (["0x0"] if opts["--dem"] else opts["--sizes"].split(",")):
        cols, rows = (int(v) for v in size.split("x"))
        bench(work, cols, rows)
        for f in os.listdir(work):
            os.remove(os.path.join(work, f))
finally:
    shutil.rmtree(work, ignore_errors=True)
