#!/usr/bin/python3
"""Soak: the encyclopedia tour in a loop for MINUTES (default 30) with every node of a session,
sampled once a minute (issue "Many stations on one session", point 5; docs/network.md, "Soak").

A world server (session log), alice (a simulated hand) and bob (a HIRO II on its simulated
plant) with the tour's hand scripts repeated back to back, a headless spectator (a frame a
second), the audio guide (a WAV per board) and a recorder (session_record) of the whole session.
Each minute, for every process: resident memory (VmRSS), open files (/proc/PID/fd), threads;
and the entries of /dev/shm. The haptic loops' statistics (rate, overruns, jitter) come from
their loop_statistics samples in the recording, one per second.

At the end: the least-squares slope of each process's resident memory over the minutes after
the first five (growth per hour), the open files' range, /dev/shm before and after, and whether
every node saw every world change the server made (no missed world change).

usage: soak.py --bin-dir BUILD [--minutes 30] [--domain 216] [--work DIR]
               [--csv bench/soak/soak_results.csv] [--png bench/soak/soak_results.png]
Writes the per-minute rows (minute,node,rss_kb,fds,threads,shm_entries,tours,rate_Hz,overruns,
jitter_p99_us) to --csv and prints the summary (also kept in WORK/summary.txt). A bench, not a
test: it asserts nothing, and takes MINUTES plus about a minute.
"""
import argparse
import os
import re
import signal
import sqlite3
import struct
import subprocess
import sys
import time

HERE = os.path.dirname(os.path.abspath(__file__))
ROOT = os.path.join(HERE, "..", "..")
SCRIPTS = os.path.join(ROOT, "haptic_node", "scripts")


def tour_scripts(work, loops):
    """alice's and bob's tour scripts, their bodies repeated `loops` times. alice goes back to
    her start pose before each repeat; bob waits for the world after the dinosaur (microscopic)
    before he waits for the next dinosaur visit, so each visit gets one press."""
    with open(os.path.join(SCRIPTS, "tour_alice.hand")) as f:
        alice = [l for l in f.read().splitlines() if l.strip() and not l.startswith("#")]
    with open(os.path.join(SCRIPTS, "tour_bob.hand")) as f:
        bob = [l for l in f.read().splitlines() if l.strip() and not l.startswith("#")]
    a_head, a_body = alice[:2], alice[2:]
    b_head, b_body = bob[:2], bob[2:]
    start = a_head[0].split()[1:4]
    lines_a = a_head + a_body
    for _ in range(loops - 1):
        lines_a += ["reach 1.0 " + " ".join(start)] + a_body
    lines_b = b_head
    for _ in range(loops):
        lines_b += b_body + ["await_world microscopic"]
    paths = []
    for name, lines in (("alice", lines_a), ("bob", lines_b)):
        path = os.path.join(work, f"soak_{name}.hand")
        with open(path, "w") as f:
            f.write(f"# tour_{name}.hand repeated {loops} times (bench/soak/soak.py)\n" + "\n".join(lines) + "\n")
        paths.append(path)
    return paths


def proc_sample(pid):
    """(VmRSS kB, open files, threads) of a live process, or None."""
    try:
        with open(f"/proc/{pid}/status") as f:
            status = f.read()
        rss = int(re.search(r"VmRSS:\s+(\d+)", status).group(1))
        threads = int(re.search(r"Threads:\s+(\d+)", status).group(1))
        fds = len(os.listdir(f"/proc/{pid}/fd"))
        return rss, fds, threads
    except (OSError, AttributeError):
        return None


def loop_statistics(recording):
    """{user: [(unix_s, rate_Hz, jitter_p99_us, jitter_max_us, steps, overruns)]} from the
    recording's loop_statistics samples (CDR: node, session, then doubles and counters)."""
    out = {}
    with sqlite3.connect(f"file:{recording}?mode=ro", uri=True) as db:
        rows = db.execute("SELECT samples.unix_ns, samples.cdr FROM samples JOIN instances ON samples.instance = "
                          "instances.id WHERE instances.topic = 'handshare/loop_statistics' ORDER BY samples.id")
        for unix_ns, cdr in rows:
            little = cdr[1] in (1, 3)
            e = "<" if little else ">"
            body, off, strings = cdr[4:], 0, []
            for _ in range(2):
                off = (off + 3) & ~3
                (n,) = struct.unpack_from(e + "I", body, off)
                strings.append(body[off + 4:off + 4 + n - 1].decode("utf-8", "replace"))
                off += 4 + n
            off = (off + 7) & ~7
            rate, _j50, j99, jmax, _s50, _s99 = struct.unpack_from(e + "6d", body, off)
            steps, overruns = struct.unpack_from(e + "2Q", body, off + 48)
            out.setdefault(strings[0].split("/")[-1], []).append((unix_ns * 1e-9, rate, j99, jmax, steps, overruns))
    return out


def slope_per_hour(points):
    """Least-squares slope of (minute, value) points, per hour."""
    n = len(points)
    if n < 2:
        return float("nan")
    mx = sum(p[0] for p in points) / n
    my = sum(p[1] for p in points) / n
    sxx = sum((p[0] - mx) ** 2 for p in points)
    return 60.0 * sum((p[0] - mx) * (p[1] - my) for p in points) / sxx if sxx else float("nan")


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--bin-dir", required=True)
    ap.add_argument("--minutes", type=float, default=30.0)
    ap.add_argument("--domain", type=int, default=216)
    ap.add_argument("--work", default="/tmp/handshare-soak")
    ap.add_argument("--csv", default=os.path.join(HERE, "soak_results.csv"))
    ap.add_argument("--png", default=os.path.join(HERE, "soak_results.png"))
    a = ap.parse_args()
    os.makedirs(a.work, exist_ok=True)
    for f in os.listdir(a.work):
        p = os.path.join(a.work, f)
        if os.path.isfile(p):
            os.remove(p)
    session = f"soak-{os.getpid()}"
    d = str(a.domain)
    cache = os.path.join(a.work, "fem_cache")
    os.environ["HANDSHARE_CACHE"] = cache
    exe = lambda folder, name: os.path.join(a.bin_dir, folder, name)  # noqa: E731
    subprocess.run([exe("core/world", "world_prepare"), "--cache", cache, "--scenes", "dinosaur,microscopic"],
                   check=True, capture_output=True, timeout=900)
    alice_script, bob_script = tour_scripts(a.work, int(a.minutes * 60 / 30) + 2)
    shm_before = set(os.listdir("/dev/shm"))
    recording = os.path.join(a.work, "soak.rec")
    common = ["--domain", d, "--session", session]
    commands = {
        "world_server": [exe("world_server", "world_server"), *common, "--log", os.path.join(a.work, "session.db")],
        "recorder": [exe("world_server", "session_record"), *common, "--out", recording],
        "audio_guide": [exe("audio_guide", "audio_guide"), *common, "--out", os.path.join(a.work, "speech")],
        # 1 frame a second: a headless spectator takes its samples once a frame, and the shortest
        # visit of a world (the microscopic one: an arrow pressed right away) lasts about 2.5 s.
        "spectator": [exe("graphics_node", "graphics_node"), *common, "--headless", "--fps", "1", "--frames",
                      str(int(a.minutes * 60) + 100), "--out", os.path.join(a.work, "frames")],
        "alice": [exe("haptic_node", "haptic_node"), *common, "--user", "alice", "--script", alice_script],
        "bob": [exe("haptic_node", "haptic_node"), *common, "--user", "bob", "--device", "hiro", "--script", bob_script],
    }
    procs, logs = {}, {}
    try:
        for label, argv in commands.items():
            logs[label] = open(os.path.join(a.work, label + ".log"), "w")
            procs[label] = subprocess.Popen(argv, stdout=logs[label], stderr=subprocess.STDOUT)
            time.sleep(0.5)
        start = time.monotonic()
        rows = []
        minute = 0
        while True:
            server_log = open(os.path.join(a.work, "world_server.log")).read()
            tours = len(re.findall(r"\] scene 'start_menu':", server_log)) - 1
            shm = len(os.listdir("/dev/shm"))
            for label, p in procs.items():
                s = proc_sample(p.pid)
                if s is None:
                    raise RuntimeError(f"{label} ended during the soak (minute {minute}):\n"
                                       + open(os.path.join(a.work, label + ".log")).read()[-3000:])
                rows.append({"minute": minute, "node": label, "rss_kb": s[0], "fds": s[1], "threads": s[2],
                             "shm_entries": shm, "tours": tours})
            print(f"minute {minute}: tours {tours}, rss MB " + ", ".join(
                f"{r['node']} {r['rss_kb'] / 1024:.1f}" for r in rows if r["minute"] == minute), flush=True)
            if minute >= a.minutes:
                break
            minute += 1
            time.sleep(max(0.0, start + 60.0 * minute - time.monotonic()))
        wall_min = (time.monotonic() - start) / 60.0
    finally:
        for p in procs.values():
            if p.poll() is None:
                p.send_signal(signal.SIGTERM)
        for label, p in procs.items():
            try:
                p.wait(timeout=60)
            except subprocess.TimeoutExpired:
                p.kill()
            logs[label].close()
    time.sleep(2.0)
    subprocess.run(["fastdds", "shm", "clean"], capture_output=True)
    shm_after = set(os.listdir("/dev/shm"))

    text = {label: open(os.path.join(a.work, label + ".log")).read() for label in procs}
    stats = loop_statistics(recording)
    # The loop statistics sample nearest each minute mark.
    t0 = min((s[0] for v in stats.values() for s in v), default=0.0)
    for r in rows:
        if r["node"] in stats:
            near = min(stats[r["node"]], key=lambda s: abs(s[0] - (t0 + 60.0 * r["minute"])))
            r["rate_Hz"], r["jitter_p99_us"], r["overruns"] = near[1], near[2], near[5]
    cols = ["minute", "node", "rss_kb", "fds", "threads", "shm_entries", "tours", "rate_Hz", "overruns", "jitter_p99_us"]
    with open(a.csv, "w") as f:
        f.write(",".join(cols) + "\n")
        for r in rows:
            f.write(",".join(str(r.get(c, "")) for c in cols) + "\n")

    summary = [f"soak: {wall_min:.1f} min, session {session} on domain {a.domain}, load {open('/proc/loadavg').read().strip()}"]
    for label in procs:
        pts = [(r["minute"], r["rss_kb"] / 1024.0) for r in rows if r["node"] == label and r["minute"] >= 5]
        fds = [r["fds"] for r in rows if r["node"] == label]
        first = [r["rss_kb"] for r in rows if r["node"] == label][0] / 1024.0
        last = [r["rss_kb"] for r in rows if r["node"] == label][-1] / 1024.0
        summary.append(f"{label}: RSS {first:.1f} -> {last:.1f} MB, slope after minute 5 {slope_per_hour(pts):+.2f} MB/h; "
                       f"open files {min(fds)}-{max(fds)}")
    def worlds(pattern, log):
        """The sequence of worlds a log names, a new revision of the same world not counted."""
        names = re.findall(pattern, log)
        return [n for i, n in enumerate(names) if i == 0 or names[i - 1] != n]
    made = worlds(r"\] scene '([a-z_]+)':", text["world_server"])
    summary.append(f"world changes made by the server: {len(made)}; tours completed: {made.count('start_menu') - 1}")
    seen = {"alice": worlds(r"\] scene '([a-z_]+)' revision", text["alice"]),
            "bob": worlds(r"\] scene '([a-z_]+)' revision", text["bob"]),
            "spectator": worlds(r"scene '([a-z_]+)' revision \d+ received", text["spectator"])}
    summary.append("world changes seen: " + ", ".join(
        f"{k} {len(v)}" + ("" if v == made else " (NOT the server's sequence)") for k, v in seen.items())
                   + f"; boards: server {text['world_server'].count('message board #')}, audio guide spoke "
                   + str(len(re.findall(r"message #\d+ \(", text["audio_guide"]))))
    for user, v in sorted(stats.items()):
        worst = max(s[3] for s in v)
        summary.append(f"{user}'s loop: {len(v)} statistics samples, rate {v[-1][1]:.1f} Hz at the end, "
                       f"overruns {v[-1][5]} of {v[-1][4]} steps, jitter p99 {v[-1][2]:.0f} us, max {worst:.0f} us")
    for label in ("alice", "bob"):
        m = re.search(r"loop statistics: (.*)", text[label])
        if m:
            summary.append(f"{label} at exit: {m.group(1)[:200]}")
    summary.append(f"/dev/shm: {len(shm_before)} entries before, {len(shm_after)} after; new: "
                   f"{sorted(shm_after - shm_before) or 'none'}")
    summary.append(f"recording: {os.path.getsize(recording) / 1e6:.1f} MB for {wall_min:.1f} min")
    print("\n".join(summary))
    with open(os.path.join(a.work, "summary.txt"), "w") as f:
        f.write("\n".join(summary) + "\n")

    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    fig, (ax1, ax2) = plt.subplots(1, 2, figsize=(11, 4.5))
    for label in procs:
        pts = [(r["minute"], r["rss_kb"] / 1024.0) for r in rows if r["node"] == label]
        ax1.plot([p[0] for p in pts], [p[1] for p in pts], marker=".", label=label)
        fpts = [(r["minute"], r["fds"]) for r in rows if r["node"] == label]
        ax2.plot([p[0] for p in fpts], [p[1] for p in fpts], marker=".", label=label)
    ax1.set_xlabel("minute")
    ax1.set_ylabel("resident memory (MB)")
    ax1.set_title("resident memory, sampled each minute")
    ax2.set_xlabel("minute")
    ax2.set_ylabel("open files")
    ax2.set_title("open files")
    ax1.legend(fontsize=8)
    fig.tight_layout()
    fig.savefig(a.png, dpi=100)
    return 0


if __name__ == "__main__":
    sys.exit(main())
