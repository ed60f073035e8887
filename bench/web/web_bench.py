#!/usr/bin/python3
"""The web console measured (issue 46, docs/web_console.md "Measured"): the live view's frame
rate in headless chromium with software WebGL, the console's CPU and bytes per second per
viewer, and how many viewers one console holds on this machine.

For each world a session of its own: a world server in that world, alice's simulated haptic
node with a scripted hand, and the console (web_console), its output in WORK/NAME.log.

  view: chromium, headless, software WebGL (SwiftShader: --use-angle=swiftshader
      --enable-unsafe-swiftshader, as tests/web_console_test.py), opens `/`; once the page has
      drawn the world with every mesh, a requestAnimationFrame chain injected into the page
      stamps every frame for --seconds (the view renders once per animation frame, view.js
      `frame()`). Rows `view`: frames per second, frame interval p50/p99/max, and the console's
      CPU meanwhile.
  viewers: 1, 2, 4, 8, ... raw WebSocket clients on /ws (this script, one thread, non-blocking
      sockets: a viewer reads everything it is sent), for --seconds after a 2 s warm-up, until
      one is dropped, or the console's CPU reaches --cpu-limit % of one core, or --max-viewers.
      Rows `viewers`: the console's CPU (user + system time from /proc/PID/stat over the window,
      % of one core), the bytes each viewer received per second (min, mean), the documents of
      each kind per second per viewer (the fewest any viewer got), the hands documents'
      inter-arrival p50/p99 at a viewer, the fan-out lag (a document's arrival at a viewer after
      its first arrival at any viewer) p50/p99, viewers dropped (closed by the console, and the
      console's own count), and `holds`: 1 when every viewer received every document at the
      console's rates (none dropped; each viewer's state, hands, bodies and deformation counts
      equal to the most any viewer got, less one for the window's edges; at least one state a
      second).

"How many viewers one console holds" is the largest count with holds=1 (the sweep stops at the
first count without). The clients run on the same machine: their CPU is in the row too.

Worlds: start_menu and solar_system with a hand that holds still (hands documents at 20 Hz,
states once a second); dinosaur with the hand pressing the triceratops' tail where
tests/data/tail_alice.hand presses it, released and pressed again every 2 s, so that its dent
keeps changing (deformation documents up to 10 a second of up to 17 kB).

A bench: it asserts nothing. The machine's load (/proc/loadavg, 1 min) before and after each
row is in the CSV.

usage: web_bench.py --bin-dir BUILD [--worlds start_menu,solar_system,dinosaur]
                    [--sweep-worlds start_menu,dinosaur] [--seconds 10] [--max-viewers 512]
                    [--cpu-limit 90] [--domain 217] [--work DIR] [--csv FILE] [--png FILE]
"""
import argparse
import base64
import collections
import csv
import hashlib
import multiprocessing
import os
import resource
import re
import selectors
import signal
import socket
import subprocess
import sys
import time
import types
import json
import urllib.request

HERE = os.path.dirname(os.path.abspath(__file__))
ROOT = os.path.join(HERE, "..", "..")
CHROMIUM = "/usr/bin/chromium"
CHROMEDRIVER = "/usr/bin/chromedriver"
SOFTWARE_WEBGL = ("--use-angle=swiftshader", "--enable-unsafe-swiftshader", "--ignore-gpu-blocklist")
KINDS = ("state", "hands", "bodies", "deformation")

HOLD_SCRIPT = """# web_bench.py: a hand that joins and holds still
start 0 0.2 0.2
await_world
hold 3600
"""


def press_script(presses=1000):
    """The index fingertip over the triceratops' tail where tests/data/tail_alice.hand presses
    it, then pressed 3 mm in for 1 s and lifted 13 mm out for 1 s, again and again."""
    lines = ["# web_bench.py: the triceratops' tail pressed and released every 2 s",
             "start 0.27 0.08 0.2", "await_world", "reach 1.0 0.27 0.08 0.11"]
    for _ in range(presses):
        lines += ["poke 1.0 0.27 0.08 0.0785", "poke 1.0 0.27 0.08 0.095"]
    return "\n".join(lines) + "\n"


def load1():
    return float(open("/proc/loadavg").read().split()[0])


def cpu_seconds(pid):
    """user + system CPU time [s] of a process so far."""
    with open(f"/proc/{pid}/stat") as f:
        fields = f.read().rsplit(")", 1)[1].split()
    return (int(fields[11]) + int(fields[12])) / os.sysconf("SC_CLK_TCK")


def percentile(values, q):
    if not values:
        return float("nan")
    s = sorted(values)
    return s[min(len(s) - 1, max(0, int(round(q / 100.0 * (len(s) - 1)))))]


class Session:
    """World server, alice's haptic node and the console of one world; stopped in reverse order
    (SIGTERM, then killed after 30 s)."""

    def __init__(self, bin_dir, work, domain, world, cache):
        self.bin_dir, self.work, self.procs = bin_dir, work, []
        self.name = f"web-bench-{world}-{os.getpid()}"
        common = ["--domain", domain, "--session", self.name, "--duration", 3600]
        env = dict(os.environ, HANDSHARE_CACHE=cache)
        self.start("world_server", "world_server/world_server", *common, "--scene", world, env=env)
        self.wait_log("world_server", "message board #1", 600)
        script = os.path.join(work, f"alice_{world}.hand")
        with open(script, "w") as f:
            f.write(press_script() if world == "dinosaur" else HOLD_SCRIPT)
        self.start("alice", "haptic_node/haptic_node", *common, "--user", "alice", "--device", "sim",
                   "--script", script)
        self.wait_log("world_server", "member joined: user=alice", 60)
        self.console = self.start("console", "web_console/web_console", *common, "--listen", "127.0.0.1:0",
                                  "--max-connections", 10000)
        self.wait_log("console", "listening on http://127.0.0.1:", 60)
        self.port = int(re.search(r"listening on http://127\.0\.0\.1:(\d+)", self.text("console")).group(1))
        self.wait_log("console", f"world '{world}' revision", 60)
        self.wait_log("alice", "hand script starts at loop time", 120)

    def start(self, label, exe, *args, env=None):
        log = open(os.path.join(self.work, label + ".log"), "w")
        p = subprocess.Popen([os.path.join(self.bin_dir, exe), *map(str, args)], stdout=log,
                             stderr=subprocess.STDOUT, env=env)
        self.procs.append((label, p))
        return p

    def text(self, label):
        with open(os.path.join(self.work, label + ".log")) as f:
            return f.read()

    def wait_log(self, label, text, timeout):
        deadline = time.monotonic() + timeout
        while text not in self.text(label):
            if time.monotonic() > deadline:
                raise RuntimeError(f"{label}: no '{text}' within {timeout} s:\n{self.text(label)[-2000:]}")
            if dict(self.procs)[label].poll() is not None:
                raise RuntimeError(f"{label} ended without '{text}':\n{self.text(label)[-2000:]}")
            time.sleep(0.1)

    def state(self):
        with urllib.request.urlopen(f"http://127.0.0.1:{self.port}/api/state", timeout=10) as r:
            return json.loads(r.read())

    def stop(self):
        for label, p in reversed(self.procs):
            if p.poll() is None:
                p.send_signal(signal.SIGTERM)
                try:
                    p.wait(30)
                except subprocess.TimeoutExpired:
                    p.kill()
                    p.wait()


# --- the view's frame rate --------------------------------------------------------------------

FRAME_STAMPS = """
window.benchFrames = [];
const stamp = (t) => { window.benchFrames.push(t); requestAnimationFrame(stamp); };
requestAnimationFrame(stamp);
return window.handshareView.frames;
"""


def measure_view(session, world, seconds):
    from selenium import webdriver  # python3-selenium and chromium-driver (deploy/install_deps.sh)
    from selenium.webdriver.chrome.service import Service
    options = webdriver.ChromeOptions()
    options.binary_location = CHROMIUM
    for flag in (*SOFTWARE_WEBGL, "--headless", "--no-sandbox", "--disable-gpu", "--disable-dev-shm-usage",
                 "--window-size=1280,900", f"--user-data-dir={os.path.join(session.work, 'chromium-' + world)}"):
        options.add_argument(flag)
    driver = webdriver.Chrome(service=Service(CHROMEDRIVER, log_path=os.path.join(session.work, "chromedriver.log")),
                              options=options)
    try:
        meshes = sum(1 for o in session.state()["world"]["view"] if o.get("mesh"))
        driver.get(f"http://127.0.0.1:{session.port}/")
        deadline = time.monotonic() + 120
        while True:
            v = driver.execute_script("return window.handshareView || null;")
            if v and v["world"] == world and v["meshesLoaded"] == meshes and "alice" in v["hands"] and v["frames"] > 5:
                break
            if time.monotonic() > deadline:
                raise RuntimeError(f"the view of {world} not drawn within 120 s: {v}")
            time.sleep(0.2)
        load_before = load1()
        cpu0, frames0, t0 = cpu_seconds(session.console.pid), driver.execute_script(FRAME_STAMPS), time.monotonic()
        time.sleep(seconds)
        stamps, frames1 = driver.execute_script("return [window.benchFrames, window.handshareView.frames];")
        wall = time.monotonic() - t0
        cpu = cpu_seconds(session.console.pid) - cpu0
    finally:
        driver.quit()
    intervals = [b - a for a, b in zip(stamps, stamps[1:])]
    return {"kind": "view", "world": world, "viewers": 1, "seconds": round(wall, 2),
            "fps": round((frames1 - frames0) / wall, 2), "frame_p50_ms": round(percentile(intervals, 50), 2),
            "frame_p99_ms": round(percentile(intervals, 99), 2), "frame_max_ms": round(max(intervals), 2),
            "console_cpu_pct": round(100 * cpu / wall, 2), "load_before": load_before, "load_after": load1()}


# --- raw WebSocket viewers ----------------------------------------------------------------------

TYPE = re.compile(rb'"type"\s*:\s*"([a-z]+)"')


class Viewer:
    """One WebSocket client of /ws that reads everything (RFC 6455 frames from a server: never
    masked); it sends nothing after the handshake (the console closes a viewer that does)."""

    def __init__(self, port, source):
        self.sock = socket.create_connection(("127.0.0.1", port), timeout=10, source_address=(source, 0))
        key = base64.b64encode(os.urandom(16)).decode()
        self.sock.sendall((f"GET /ws HTTP/1.1\r\nHost: 127.0.0.1:{port}\r\nUpgrade: websocket\r\n"
                           f"Connection: Upgrade\r\nSec-WebSocket-Key: {key}\r\nSec-WebSocket-Version: 13\r\n\r\n")
                          .encode())
        head = b""
        while b"\r\n\r\n" not in head:
            chunk = self.sock.recv(4096)
            if not chunk:
                raise RuntimeError("the console closed a viewer's handshake")
            head += chunk
        head, self.buf = head.split(b"\r\n\r\n", 1)
        if not head.startswith(b"HTTP/1.1 101"):
            raise RuntimeError(f"the console refused a viewer: {head[:200]!r}")
        self.sock.setblocking(False)
        self.closed = False
        self.reset()

    def reset(self):
        self.bytes = 0
        self.arrivals = collections.defaultdict(list)  # kind -> monotonic times
        self.docs = []  # (digest, time) of every document

    def feed(self, now):
        """Reads what has arrived; returns False once the console closed the socket."""
        try:
            chunk = self.sock.recv(1 << 20)
        except BlockingIOError:
            return True
        except ConnectionError:
            chunk = b""
        if not chunk:
            self.closed = True
            return False
        self.bytes += len(chunk)
        self.buf += chunk
        while True:
            b = self.buf
            if len(b) < 2:
                break
            n, at = b[1] & 0x7F, 2
            if n == 126:
                if len(b) < 4:
                    break
                n, at = int.from_bytes(b[2:4], "big"), 4
            elif n == 127:
                if len(b) < 10:
                    break
                n, at = int.from_bytes(b[2:10], "big"), 10
            if len(b) < at + n:
                break
            opcode, payload = b[0] & 0x0F, b[at:at + n]
            self.buf = b[at + n:]
            if opcode == 8:
                self.closed = True
                return False
            if opcode in (1, 2):
                # The document's "type" (keys sorted: not first; a control's "type" is another word).
                kind = next((k for k in (m.decode() for m in TYPE.findall(payload)) if k in KINDS), "other")
                self.arrivals[kind].append(now)
                self.docs.append((hashlib.blake2b(payload, digest_size=8).digest(), now))
        return True


def connect(port, i):
    """Viewer i, from loopback address 127.0.0.(2 + i // 32): viewers are browsers on other
    machines, each under the console's request rate per address (20 a second, burst 40); the
    console's own limit refused (429) is waited out."""
    for _ in range(100):
        try:
            return Viewer(port, f"127.0.0.{2 + i // 32}")
        except RuntimeError as e:
            if "429" not in str(e):
                raise
            time.sleep(0.1)
    raise RuntimeError(f"viewer {i} refused (429) for 10 s")


def client_worker(port, first, count, conn, grace_s=1.0):
    """Viewers first .. first + count - 1 in this process: connects them, then reads through the
    window the parent sends and grace_s after it (what was sent in the window and is still on
    its way); sends back what each received and when."""
    sel = selectors.DefaultSelector()

    def pump(until, timeout=0.05):
        while True:
            for key, _ in sel.select(timeout=timeout):
                v = key.data
                if not v.closed and not v.feed(time.monotonic()):
                    sel.unregister(v.sock)
            if time.monotonic() >= until:
                return
    # Each viewer reads from its connection on, while the others connect: one left unread for
    # seconds would fill its queue at the console and be dropped, as a real stuck viewer is.
    viewers = []
    for i in range(first, first + count):
        viewers.append(connect(port, i))
        sel.register(viewers[-1].sock, selectors.EVENT_READ, viewers[-1])
        pump(0.0, timeout=0)
    conn.send("connected")
    while not conn.poll(0):
        pump(time.monotonic() + 0.05)
    t0, t1 = conn.recv()
    pump(t0)
    for v in viewers:
        v.reset()
    me0 = time.process_time()
    pump(t1)
    me = time.process_time() - me0
    window_bytes = [v.bytes for v in viewers]
    pump(t1 + grace_s)
    conn.send((me, [types.SimpleNamespace(bytes=b, arrivals=dict(v.arrivals), docs=v.docs, closed=v.closed)
                    for v, b in zip(viewers, window_bytes)]))
    for v in viewers:
        v.sock.close()
    conn.close()


def measure_viewers(session, world, count, seconds, processes, warmup_s=2.0):
    """count viewers, spread over `processes` client processes (a Python reader needs about a
    core for 250 viewers here), read for `seconds` after `warmup_s`."""
    mp = multiprocessing.get_context("fork")
    workers, share = [], [count // processes + (1 if k < count % processes else 0) for k in range(processes)]
    first = 0
    for n in share:
        if n == 0:
            continue
        parent, child = mp.Pipe()
        p = mp.Process(target=client_worker, args=(session.port, first, n, child))
        p.start()
        workers.append((p, parent))
        first += n
    for _, conn in workers:
        if conn.recv() != "connected":
            raise RuntimeError("a client process did not connect its viewers")
    dropped_before = session.state()["console"]["viewers_dropped"]
    t0 = time.monotonic() + warmup_s
    t1 = t0 + seconds
    for _, conn in workers:
        conn.send((t0, t1))
    time.sleep(max(0.0, t0 - time.monotonic()))
    load_before = load1()
    cpu0 = cpu_seconds(session.console.pid)
    time.sleep(max(0.0, t1 - time.monotonic()))
    cpu = cpu_seconds(session.console.pid) - cpu0
    wall = seconds
    load_after = load1()
    viewers, me = [], 0.0
    for p, conn in workers:
        used, got = conn.recv()
        me += used
        viewers += got
        p.join(30)
    state = session.state()

    alive = [v for v in viewers if not v.closed]
    closed = count - len(alive)
    console_dropped = state["console"]["viewers_dropped"] - dropped_before
    # Every document at every viewer: a viewer's reads trail the console's sends by its own lag,
    # so what the most served viewer got in the window [t0, t1] (at most one more of a kind than
    # was sent in it) is compared with what each got in [t0, t1 + grace] (all that was sent in
    # [t0, t1], whatever its lag below the grace).
    def received(v, k, end):
        return sum(1 for t in v.arrivals.get(k, ()) if t0 <= t <= end)
    most = {k: max(received(v, k, t1) for v in viewers) for k in KINDS}
    fewest = {k: min(received(v, k, float("inf")) for v in viewers) for k in KINDS}
    every_doc = all(fewest[k] >= most[k] - 1 for k in KINDS)
    hands_gaps = []
    for v in alive:
        hands = [t for t in v.arrivals.get("hands", ()) if t0 <= t <= t1]
        hands_gaps += [b - a for a, b in zip(hands, hands[1:])]
    # Fan-out lag: of the documents every viewer got exactly once (an unchanged document sent
    # again, a still hand's, cannot be told apart), each arrival after the first.
    arrivals = collections.defaultdict(list)
    for i, v in enumerate(viewers):
        for digest, t in v.docs:
            arrivals[digest].append((i, t))
    lags = []
    for got in arrivals.values():
        if not t0 <= min(t for _, t in got) <= t1:
            continue
        if count > 1 and len(got) == count and len({i for i, _ in got}) == count:
            first = min(t for _, t in got)
            lags += [t - first for _, t in got]
    per_viewer_Bps = [v.bytes / wall for v in viewers]
    holds = int(closed == 0 and console_dropped == 0 and every_doc and fewest["state"] >= int(seconds) - 1)
    missed = [f"{k} {fewest[k]} of {most[k]}" for k in KINDS if fewest[k] < most[k] - 1]
    row = {"kind": "viewers", "world": world, "viewers": count, "seconds": round(wall, 2),
           "console_cpu_pct": round(100 * cpu / wall, 2), "clients_cpu_pct": round(100 * me / wall, 2),
           "kB_per_s_per_viewer_mean": round(sum(per_viewer_Bps) / count / 1e3, 2),
           "kB_per_s_per_viewer_min": round(min(per_viewer_Bps) / 1e3, 2),
           "kB_per_s_total": round(sum(per_viewer_Bps) / 1e3, 1),
           "hands_gap_p50_ms": round(1e3 * percentile(hands_gaps, 50), 2),
           "hands_gap_p99_ms": round(1e3 * percentile(hands_gaps, 99), 2),
           "fanout_lag_p50_ms": round(1e3 * percentile(lags, 50), 3) if lags else "",
           "fanout_lag_p99_ms": round(1e3 * percentile(lags, 99), 3) if lags else "",
           "fanout_lag_max_ms": round(1e3 * max(lags), 3) if lags else "",
           "viewers_closed": closed, "console_viewers_dropped": console_dropped, "holds": holds,
           "missed": "; ".join(missed),
           "load_before": load_before, "load_after": load_after}
    for k in KINDS:
        row[f"{k}_per_s_min"] = round(min(received(v, k, t1) for v in viewers) / wall, 2)
        row[f"{k}_per_s_max"] = round(most[k] / wall, 2)
    return row


FIELDS = ["kind", "world", "viewers", "seconds", "fps", "frame_p50_ms", "frame_p99_ms", "frame_max_ms",
          "console_cpu_pct", "clients_cpu_pct", "kB_per_s_per_viewer_mean", "kB_per_s_per_viewer_min",
          "kB_per_s_total", *[f"{k}_per_s_{m}" for k in KINDS for m in ("min", "max")], "hands_gap_p50_ms",
          "hands_gap_p99_ms", "fanout_lag_p50_ms", "fanout_lag_p99_ms", "fanout_lag_max_ms", "viewers_closed",
          "console_viewers_dropped", "holds", "missed", "load_before", "load_after"]


def plot(rows, png):
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    fig, (a, b, c) = plt.subplots(1, 3, figsize=(15, 4.5))
    views = [r for r in rows if r["kind"] == "view"]
    x = range(len(views))
    a.bar([i - 0.2 for i in x], [r["frame_p50_ms"] for r in views], 0.4, label="p50")
    a.bar([i + 0.2 for i in x], [r["frame_p99_ms"] for r in views], 0.4, label="p99")
    a.set_xticks(list(x))
    a.set_xticklabels([f"{r['world']}\n{r['fps']} fps" for r in views])
    a.set_ylabel("frame interval [ms]")
    a.set_title("the view, headless chromium, SwiftShader")
    a.legend()
    for colour, world in zip(("C0", "C3", "C2"), sorted({r["world"] for r in rows if r["kind"] == "viewers"})):
        sweep = [r for r in rows if r["kind"] == "viewers" and r["world"] == world]
        n = [r["viewers"] for r in sweep]
        b.plot(n, [r["console_cpu_pct"] for r in sweep], "o-", color=colour, label=f"console, {world}")
        b.plot(n, [r["clients_cpu_pct"] for r in sweep], "x:", color=colour, label=f"the clients (this script), {world}")
        c.plot(n, [r["kB_per_s_per_viewer_mean"] for r in sweep], "o-", color=colour, label=world)
        for r in sweep:
            if not r["holds"]:
                b.annotate("not held", (r["viewers"], r["console_cpu_pct"]))
    for ax in (b, c):
        ax.set_xscale("log", base=2)
        ax.set_xlabel("WebSocket viewers")
        ax.legend(fontsize=8)
    b.set_ylabel("CPU [% of one core]")
    b.set_ylim(bottom=0)
    c.set_ylim(bottom=0)
    b.set_title("the console's CPU")
    c.set_ylabel("kB/s per viewer")
    c.set_title("bytes per viewer")
    loads = [r["load_before"] for r in rows] + [r["load_after"] for r in rows]
    fig.suptitle(f"web_console on this machine ({os.cpu_count()} cores, load {min(loads):.1f}-{max(loads):.1f})")
    fig.tight_layout()
    fig.savefig(png, dpi=90)


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--bin-dir", required=True)
    ap.add_argument("--worlds", default="start_menu,solar_system,dinosaur", help="views measured ('' for none)")
    ap.add_argument("--sweep-worlds", default="start_menu,dinosaur", help="viewer sweeps ('' for none)")
    ap.add_argument("--seconds", type=float, default=10.0)
    ap.add_argument("--max-viewers", type=int, default=512)
    ap.add_argument("--cpu-limit", type=float, default=90.0, help="stop a sweep once the console uses this %% of a core")
    ap.add_argument("--client-processes", type=int, default=2, help="processes the viewers are spread over")
    ap.add_argument("--domain", type=int, default=217)
    ap.add_argument("--work", default="/tmp/handshare-web-bench")
    ap.add_argument("--cache", default="", help="FEM model cache (default BUILD/tests/work/fem_cache)")
    ap.add_argument("--csv", default=os.path.join(HERE, "web_bench_results.csv"))
    ap.add_argument("--png", default=os.path.join(ROOT, "docs", "web_console_viewers.png"))
    args = ap.parse_args()
    # A socket per viewer here, and one per viewer in the console (started from here).
    _, hard = resource.getrlimit(resource.RLIMIT_NOFILE)
    resource.setrlimit(resource.RLIMIT_NOFILE, (hard, hard))
    os.makedirs(args.work, exist_ok=True)
    cache = args.cache or os.path.join(args.bin_dir, "tests", "work", "fem_cache")
    views = [w for w in args.worlds.split(",") if w]
    sweeps = [w for w in args.sweep_worlds.split(",") if w]
    rows = []
    print(f"uptime: {subprocess.run(['uptime'], capture_output=True, text=True).stdout.strip()}", flush=True)
    for world in dict.fromkeys(views + sweeps):
        session = Session(args.bin_dir, args.work, args.domain, world, cache)
        try:
            if world in views:
                rows.append(measure_view(session, world, args.seconds))
                print(rows[-1], flush=True)
            if world in sweeps:
                count = 1
                while count <= args.max_viewers:
                    rows.append(measure_viewers(session, world, count, args.seconds, args.client_processes))
                    print(rows[-1], flush=True)
                    if not rows[-1]["holds"] or rows[-1]["console_cpu_pct"] >= args.cpu_limit:
                        break
                    count *= 2
        finally:
            session.stop()
    print(f"uptime: {subprocess.run(['uptime'], capture_output=True, text=True).stdout.strip()}", flush=True)
    with open(args.csv, "w", newline="") as f:
        w = csv.DictWriter(f, fieldnames=FIELDS)
        w.writeheader()
        for r in rows:
            w.writerow({k: r.get(k, "") for k in FIELDS})
    plot(rows, args.png)
    print(f"wrote {args.csv} and {args.png}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
