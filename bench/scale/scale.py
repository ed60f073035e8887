#!/usr/bin/python3
"""Many stations on one session (issue "Many stations on one session", point 3; docs/network.md,
"Scale"): N simulated haptic users in pairs on shared objects, M headless spectators and the
audio guide on one world server, for SECONDS, with every process's cost in one table.

The world is `commons` (assets/scenes/commons.json): the triceratops' tail, head and leg and a
ball on one table. Users come in pairs: pair 1 presses the tail side by side, pair 2 the head,
pair 3 the leg (each hand 3 mm into the surface, then still), pair 4 shares the ball (one grasps
and lifts it, the other touches it from the side). More pairs repeat the four sites 15 mm
along x.

Per process: CPU (user + system time over the measured window, % of one core), resident
memory; per haptic user: its loop's rate, p99 jitter, overruns and worst step (its exit line),
its bridge's rate and p99 tick interval; the world server's tick work and interval p99; per
process the reliable samples the middleware reports lost on the way in (member_info,
scene_state, message_board, control_event, deformation: target 0) and the payload bytes it
wrote per second (all topics; device states and contact sets apart), over its whole run.

usage: scale.py --bin-dir BUILD [--users 8] [--spectators 8] [--seconds 60] [--fps 5]
                [--streams paced|full] [--sweep 2,4,6,8,... [--sweep-spectators K]] [--domain 215] [--work DIR]
                [--screen-nice N] [--busy K] [--coupling woken|polled] [--at-rest] [--csv FILE] [--png FILE]
--screen-nice N starts the spectators with `graphics_node --nice N` (default: the node's own, 10);
--busy K runs K other processes that keep a core busy each (a spin loop at nice 0) from the world
server's start to the end, as a neighbouring test or build would. The summary row counts the
nodes that said the machine was overloaded (`overloaded`) and the spin loops' CPU (`busy_cpu_pct`).
--coupling passes `haptic_node --coupling` (polled: the bridges as before the event-driven coupling);
--at-rest holds every hand above its site, touching nothing.
--sweep runs one session per user count (with as many spectators, as in the point's 8 + 8, or
--sweep-spectators K of them) and writes one summary row per session; otherwise one session, a row per process. A bench: it
asserts nothing (tests/scale_test.py runs one session and checks what must hold).
"""
import argparse
import os
import re
import signal
import subprocess
import sys
import time

HERE = os.path.dirname(os.path.abspath(__file__))
RELIABLE = ("member_info", "scene_state", "message_board", "control_event", "deformation")

# Where each pair works, as (script A, script B) bodies after "start" and "await_world". The
# press points are the surface's top from the mesh (assets/meshes, placed as in the scene) plus
# the 8 mm fingertip radius less 3 mm: the index fingertip's centre 3 mm into the surface.
SITES = [
    ("tail", [(0.225, 0.08, 0.0649)], [(0.27, 0.08, 0.0785)]),
    ("head", [(-0.18, 0.04, 0.095)], [(-0.16, 0.06, 0.093)]),
    ("leg", [(0.045, 0.108, 0.176)], [(0.045, 0.132, 0.176)]),
    ("ball", None, None),
]
BALL = (0.0, -0.12, 0.04)  # its centre in the commons, radius 40 mm


def hand_script(pair, member, hold_s, at_rest=False):
    """The hand script of member 0 or 1 of pair `pair` (0-based); at_rest: the hand waits 4 cm
    above its site (or 12 cm above the ball) and never touches."""
    site, a, b = SITES[pair % len(SITES)]
    dx = 0.015 * (pair // len(SITES))
    lines = [f"# bench/scale/scale.py: pair {pair + 1} ({site}), member {member + 1}"]
    if at_rest:
        x, y, z = (a if member == 0 else b)[0] if site != "ball" else BALL
        lines += [f"start {x + dx:.4f} {y:.4f} {z + (0.04 if site != 'ball' else 0.12):.4f}", "await_world commons",
                  f"hold {hold_s}"]
    elif site != "ball":
        x, y, z = (a if member == 0 else b)[0]
        x += dx
        lines += [f"start {x:.4f} {y:.4f} {z + 0.04:.4f}", "await_world commons", "hold 0.5",
                  f"poke 1.5 {x:.4f} {y:.4f} {z:.4f}", f"hold {hold_s}"]
    elif member == 0:
        x, y, z = BALL
        x += dx
        lines += [f"start {x:.4f} {y:.4f} {z + 0.12:.4f}", "await_world commons", "hold 0.5",
                  f"grasp 1.5 {x:.4f} {y:.4f} {z:.4f} 0.04 0.002", "lift 1.5 0.05", f"hold {hold_s}"]
    else:
        x, y, z = BALL
        x += dx
        # After the lift (the ball's centre 50 mm up), the index fingertip 3 mm into its +x side.
        lines += [f"start {x + 0.10:.4f} {y:.4f} {z + 0.05:.4f}", "await_world commons", "hold 4.0",
                  f"poke 1.5 {x + 0.045:.4f} {y:.4f} {z + 0.05:.4f}", f"hold {hold_s}"]
    return "\n".join(lines) + "\n"


def cpu_seconds(pid, tid=None):
    """User + system CPU seconds of a live process (or of its thread tid), or None."""
    try:
        with open(f"/proc/{pid}/stat" if tid is None else f"/proc/{pid}/task/{tid}/stat") as f:
            fields = f.read().rsplit(")", 1)[1].split()
        return (int(fields[11]) + int(fields[12])) / os.sysconf("SC_CLK_TCK")
    except (OSError, IndexError, ValueError):
        return None


def rss_mb(pid):
    try:
        with open(f"/proc/{pid}/status") as f:
            return int(re.search(r"VmRSS:\s+(\d+)", f.read()).group(1)) / 1024.0
    except (OSError, AttributeError):
        return None


def parse_traffic(log):
    """{topic: {"out": n, "kB": x, "in": n, "lost": n}} from a node's "traffic:" line."""
    lines = re.findall(r"traffic: ([^\n]*)", log)
    out = {}
    if not lines or lines[-1].strip() == "none":
        return out
    for part in lines[-1].split("; "):
        m = re.match(r"(\w+)(?: out (\d+) \(([\d.]+) kB\))?(?: in (\d+))?(?: lost (\d+))?", part.strip())
        if m:
            out[m.group(1)] = {"out": int(m.group(2) or 0), "kB": float(m.group(3) or 0.0),
                               "in": int(m.group(4) or 0), "lost": int(m.group(5) or 0)}
    return out


def parse_haptic(log):
    """The haptic node's exit lines as numbers (empty if it has none: killed)."""
    r = {}
    m = re.search(r"loop statistics: rate ([\d.]+) Hz, steps (\d+), jitter p50 (\d+) us p99 (\d+) us max (\d+) us, "
                  r"step p50 ([\d.]+) us p99 ([\d.]+) us, overruns (\d+)", log)
    if m:
        r.update(loop_Hz=float(m.group(1)), steps=int(m.group(2)), jitter_p99_us=int(m.group(4)),
                 jitter_max_us=int(m.group(5)), step_p99_us=float(m.group(7)), overruns=int(m.group(8)))
    m = re.search(r"bridge: (\d+) ticks, ([\d.]+) Hz of (\d+), interval p50 ([\d.]+) ms p99 ([\d.]+) ms max ([\d.]+) ms; "
                  r"streams (\w+): device states (\d+), contact sets (\d+) \((\d+) at the full rate", log)
    if m:
        r.update(bridge_ticks=int(m.group(1)), bridge_Hz=float(m.group(2)), bridge_p99_ms=float(m.group(5)), device_states=int(m.group(8)),
                 contact_sets=int(m.group(9)), contact_sets_shared=int(m.group(10)))
    return r


def parse_server(log):
    m = re.search(r"ticks: (\d+) at (\d+) Hz, work p50 (\d+) us p99 (\d+) us max (\d+) us, "
                  r"interval p99 ([\d.]+) ms max ([\d.]+) ms", log)
    return {"tick_work_p99_us": int(m.group(4)), "tick_interval_p99_ms": float(m.group(6)),
            "tick_work_max_us": int(m.group(5))} if m else {}


def wait_for(path, pattern, timeout, procs):
    """Waits until the log at `path` matches `pattern`; fails early if a process ended."""
    end = time.monotonic() + timeout
    while time.monotonic() < end:
        with open(path) as f:
            if re.search(pattern, f.read()):
                return
        for label, p in procs.items():
            if p.poll() is not None:
                raise RuntimeError(f"{label} ended (exit {p.returncode}) while waiting for /{pattern}/ in {path}")
        time.sleep(0.2)
    raise RuntimeError(f"timed out after {timeout} s waiting for /{pattern}/ in {path}")


def run_session(bin_dir, work, domain, users=8, spectators=8, seconds=60.0, fps=5.0, streams="paced", cache="",
                screen_nice=None, busy=0, coupling="woken", at_rest=False):
    """Runs one session (FEM models cached in `cache`, default WORK/fem_cache) and returns {"rows": [per-process dict], "window_s": s, "logs": {label: text},
    "load": (before, after)}. Raises RuntimeError if a process fails to start or ends early.
    coupling: the haptic nodes' `--coupling`; at_rest: no hand touches anything (hand_script)."""
    os.makedirs(work, exist_ok=True)
    session = f"scale-{os.getpid()}-{users}"
    cache = cache or os.path.join(work, "fem_cache")
    env = dict(os.environ, HANDSHARE_CACHE=cache)
    exe = lambda folder, name: os.path.join(bin_dir, folder, name)  # noqa: E731
    subprocess.run([exe("core/world", "world_prepare"), "--cache", cache, "--scenes", "commons"],
                   check=True, capture_output=True, timeout=900, env=env)
    common = ["--domain", str(domain), "--session", session]
    hold = int(seconds + 120)
    commands = {"world_server": [exe("world_server", "world_server"), *common, "--scene", "commons"],
                "audio_guide": [exe("audio_guide", "audio_guide"), *common, "--out", os.path.join(work, "speech")]}
    names = [f"user{k + 1}" for k in range(users)]
    for k, name in enumerate(names):
        script = os.path.join(work, f"{name}.hand")
        with open(script, "w") as f:
            f.write(hand_script(k // 2, k % 2, hold, at_rest))
        commands[name] = [exe("haptic_node", "haptic_node"), *common, "--user", name, "--script", script,
                          "--streams", streams, "--coupling", coupling]
    for k in range(spectators):
        commands[f"screen{k + 1}"] = [exe("graphics_node", "graphics_node"), *common, "--name", f"screen{k + 1}",
                                      "--headless", "--fps", str(fps), "--frames", str(int((seconds + 300) * fps)),
                                      "--out", os.path.join(work, f"screen{k + 1}"),
                                      *([] if screen_nice is None else ["--nice", str(screen_nice)])]
    procs, logs, started, ended = {}, {}, {}, {}
    spinners = []
    paths = {label: os.path.join(work, label + ".log") for label in commands}
    try:
        for label, argv in commands.items():
            logs[label] = open(paths[label], "w")
            procs[label] = subprocess.Popen(argv, stdout=logs[label], stderr=subprocess.STDOUT, env=env)
            started[label] = time.monotonic()
            if label == "world_server":
                wait_for(paths[label], r"scene 'commons'", 60, procs)
                spinners = [subprocess.Popen([sys.executable, "-c", "while True: pass"]) for _ in range(busy)]
        # Every user has its world and has begun its script; every screen has the world.
        for name in names:
            wait_for(paths[name], r"scene 'commons' revision", 120, procs)
            wait_for(paths["world_server"], rf"member joined: user={name}\b", 60, procs)
        for k in range(spectators):
            wait_for(paths[f"screen{k + 1}"], r"scene 'commons' revision \d+ received", 120, procs)
        time.sleep(6.0)  # the scripts' reach to their sites (at most 5.5 s after the world): not measured
        load_before = open("/proc/loadavg").read().split()[0]
        cpu0 = {label: cpu_seconds(p.pid) for label, p in procs.items()}
        main0 = {label: cpu_seconds(p.pid, p.pid) for label, p in procs.items()}
        spin0 = [cpu_seconds(p.pid) for p in spinners]
        t0 = time.monotonic()
        time.sleep(seconds)  # the measured window
        window = time.monotonic() - t0
        cpu1 = {label: cpu_seconds(p.pid) for label, p in procs.items()}
        main1 = {label: cpu_seconds(p.pid, p.pid) for label, p in procs.items()}
        spin_pct = sum(100.0 * (cpu_seconds(p.pid) - c) / window for p, c in zip(spinners, spin0))
        rss = {label: rss_mb(p.pid) for label, p in procs.items()}
        load_after = open("/proc/loadavg").read().split()[0]
        for label, p in procs.items():
            if p.poll() is not None:
                raise RuntimeError(f"{label} ended during the run (exit {p.returncode}):\n"
                                   + open(paths[label]).read()[-3000:])
    finally:
        for p in spinners:
            p.kill()
            p.wait()
        # The haptic nodes first (their last contact sets end the presses), the server last.
        order = sorted(procs, key=lambda l: (l == "world_server", l))
        for label in order:
            if procs[label].poll() is None:
                procs[label].send_signal(signal.SIGTERM)
        for label in order:
            try:
                procs[label].wait(timeout=60)
            except subprocess.TimeoutExpired:
                procs[label].kill()
                procs[label].wait()
            ended[label] = time.monotonic()
            logs[label].close()
    text = {label: open(paths[label]).read() for label in commands}
    rows = []
    for label in commands:
        kind = ("world_server" if label == "world_server" else "audio_guide" if label == "audio_guide"
                else "haptic" if label.startswith("user") else "spectator")
        traffic = parse_traffic(text[label])
        run_s = ended[label] - started[label]  # what the traffic counts cover (joining to the end)
        kB_s = lambda topics: sum(t["kB"] for topic, t in traffic.items() if topic in topics) / run_s  # noqa: E731
        row = {"node": label, "kind": kind, "exit": procs[label].returncode,
               "cpu_pct": 100.0 * (cpu1[label] - cpu0[label]) / window if cpu1[label] is not None else None,
               # The main thread's share: a haptic node's bridge, the world server's tick.
               "main_cpu_pct": 100.0 * (main1[label] - main0[label]) / window
               if main1[label] is not None and main0[label] is not None else None,
               "rss_mb": rss[label],
               "reliable_lost": sum(t["lost"] for topic, t in traffic.items() if topic in RELIABLE),
               "best_effort_lost": sum(t["lost"] for topic, t in traffic.items() if topic not in RELIABLE),
               "out_kB_per_s": sum(t["kB"] for t in traffic.values()) / run_s,
               "device_kB_per_s": kB_s(("device_state",)),
               "contact_kB_per_s": kB_s(("contact_set",)),
               "run_s": run_s,
               "traffic": traffic,
               "overloaded": "the machine is overloaded" in text[label]}
        if kind == "haptic":
            row.update(parse_haptic(text[label]))
        if kind == "world_server":
            row.update(parse_server(text[label]))
        rows.append(row)
    return {"rows": rows, "window_s": window, "logs": text, "load": (load_before, load_after), "session": session,
            "busy": busy, "busy_cpu_pct": spin_pct}


COLUMNS = ["users", "spectators", "node", "kind", "cpu_pct", "server_cpu_pct", "haptic_cpu_pct", "spectator_cpu_pct", "rss_mb", "loop_Hz", "jitter_p99_us", "jitter_max_us",
           "overruns", "step_p99_us", "bridge_Hz", "bridge_p99_ms", "tick_work_p99_us", "tick_interval_p99_ms",
           "reliable_lost", "out_kB_per_s", "device_kB_per_s", "contact_kB_per_s", "load", "overloaded", "busy", "busy_cpu_pct"]


def fmt(v):
    if v is None:
        return ""
    return f"{v:.2f}" if isinstance(v, float) else str(v)


def summary_row(users, spectators, result):
    """One row for a sweep: the worst haptic loop, the server's tick, the totals."""
    rows = result["rows"]
    haptic = [r for r in rows if r["kind"] == "haptic" and "loop_Hz" in r]
    server = next(r for r in rows if r["kind"] == "world_server")
    mean = lambda values: sum(values) / len(values) if values else None  # noqa: E731
    return {"users": users, "spectators": spectators, "node": "all", "kind": "summary",
            "cpu_pct": sum(r["cpu_pct"] or 0.0 for r in rows),
            "server_cpu_pct": server["cpu_pct"],
            "haptic_cpu_pct": mean([r["cpu_pct"] or 0.0 for r in haptic]),
            "spectator_cpu_pct": mean([r["cpu_pct"] or 0.0 for r in rows if r["kind"] == "spectator"]),
            "rss_mb": sum(r["rss_mb"] or 0.0 for r in rows),
            "loop_Hz": min((r["loop_Hz"] for r in haptic), default=None),
            "jitter_p99_us": max((r["jitter_p99_us"] for r in haptic), default=None),
            "jitter_max_us": max((r["jitter_max_us"] for r in haptic), default=None),
            "overruns": max((r["overruns"] for r in haptic), default=None),
            "step_p99_us": max((r["step_p99_us"] for r in haptic), default=None),
            "bridge_Hz": min((r.get("bridge_Hz", 0.0) for r in haptic), default=None),
            "bridge_p99_ms": max((r.get("bridge_p99_ms", 0.0) for r in haptic), default=None),
            "tick_work_p99_us": server.get("tick_work_p99_us"),
            "tick_interval_p99_ms": server.get("tick_interval_p99_ms"),
            "reliable_lost": sum(r["reliable_lost"] for r in rows),
            "out_kB_per_s": sum(r["out_kB_per_s"] for r in rows),
            "device_kB_per_s": sum(r["device_kB_per_s"] for r in rows),
            "contact_kB_per_s": sum(r["contact_kB_per_s"] for r in rows),
            "load": "->".join(result["load"]),
            "overloaded": sum(1 for r in rows if r["overloaded"]),
            "busy": result["busy"], "busy_cpu_pct": result["busy_cpu_pct"]}


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--bin-dir", required=True)
    ap.add_argument("--users", type=int, default=8)
    ap.add_argument("--spectators", type=int, default=8)
    ap.add_argument("--seconds", type=float, default=60.0)
    ap.add_argument("--fps", type=float, default=5.0)
    ap.add_argument("--streams", choices=("paced", "full"), default="paced")
    ap.add_argument("--sweep", default="")
    ap.add_argument("--sweep-spectators", type=int, default=-1)
    ap.add_argument("--domain", type=int, default=215)
    ap.add_argument("--work", default="/tmp/handshare-scale")
    ap.add_argument("--csv", default="")
    ap.add_argument("--png", default="")
    ap.add_argument("--screen-nice", type=int, default=None)
    ap.add_argument("--busy", type=int, default=0)
    ap.add_argument("--coupling", choices=("woken", "polled"), default="woken")
    ap.add_argument("--at-rest", action="store_true")
    a = ap.parse_args()
    out_rows = []
    if a.sweep:
        for users in [int(u) for u in a.sweep.split(",")]:
            screens = users if a.sweep_spectators < 0 else a.sweep_spectators
            result = run_session(a.bin_dir, os.path.join(a.work, f"u{users}"), a.domain, users, screens, a.seconds, a.fps,
                                 a.streams, screen_nice=a.screen_nice, busy=a.busy, coupling=a.coupling,
                                 at_rest=a.at_rest)
            row = summary_row(users, screens, result)
            out_rows.append(row)
            print(", ".join(f"{c} {fmt(row.get(c))}" for c in COLUMNS), flush=True)
    else:
        result = run_session(a.bin_dir, a.work, a.domain, a.users, a.spectators, a.seconds, a.fps, a.streams,
                             screen_nice=a.screen_nice, busy=a.busy, coupling=a.coupling, at_rest=a.at_rest)
        for r in result["rows"]:
            r.update(users=a.users, spectators=a.spectators, load="->".join(result["load"]))
            out_rows.append(r)
        out_rows.append(summary_row(a.users, a.spectators, result))
    text = ",".join(COLUMNS) + "\n" + "".join(",".join(fmt(r.get(c)) for c in COLUMNS) + "\n" for r in out_rows)
    if a.csv:
        with open(a.csv, "w") as f:
            f.write(text)
    print(text, end="")
    if a.png and a.sweep:
        import matplotlib
        matplotlib.use("Agg")
        import matplotlib.pyplot as plt
        fig, (ax1, ax2) = plt.subplots(1, 2, figsize=(11, 4.5))
        n = [r["users"] for r in out_rows]
        ax1.plot(n, [r["jitter_p99_us"] for r in out_rows], marker="o", label="worst loop's jitter p99 (us)")
        ax1.plot(n, [r["jitter_max_us"] / 10.0 for r in out_rows], marker="s", label="worst loop's jitter max / 10 (us)")
        ax1.plot(n, [r["overruns"] for r in out_rows], marker="^", label="most overruns of one loop")
        screens = "as many spectators" if a.sweep_spectators < 0 else (
            f"{a.sweep_spectators} spectator" + ("" if a.sweep_spectators == 1 else "s"))
        ax1.set_xlabel(f"haptic users ({screens} at {a.fps:g} fps)")
        ax1.set_title(f"haptic loops, {a.seconds:g} s")
        ax1.legend(fontsize=8)
        ax2.plot(n, [r["cpu_pct"] for r in out_rows], marker="o", label="CPU, all processes (% of one core)")
        ax2.plot(n, [r["bridge_Hz"] for r in out_rows], marker="s", label="slowest bridge (Hz, of 100)")
        ax2.axhline(200, color="grey", lw=0.8, ls="--")
        ax2.set_xlabel("haptic users")
        ax2.set_title("CPU (2 cores = 200 %) and bridge rate")
        ax2.legend(fontsize=8)
        fig.tight_layout()
        fig.savefig(a.png, dpi=100)
    return 0


if __name__ == "__main__":
    sys.exit(main())
