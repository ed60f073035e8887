#!/usr/bin/env python3
"""A crashed world server: kill -9 mid-session, then a restart with the same command line.

alice goes to the solar system, pulls the lever to Mars and lifts the ball; while she holds
it the server is killed. Her haptic node runs on: she keeps the ball's weight in her hand (no
force jump, the ball is not dropped), and keeps her world. The restarted server resumes the
session from its log within 2 s: the same world and revision (alice's node builds nothing
new), the same board message (the audio guide speaks nothing twice), the ball given back to
alice from her claim, the lever where she left it for a screen that joins only after the
restart; no row the killed server committed is lost.

usage: server_crash_test.py --bin-dir DIR --domain D --work DIR
"""
import csv
import json
import os
import re
import signal
import sqlite3
import sys
import time

from session_test import Failure, check, net_jz, run_cases

MARS = 3.71
BALL_KG = 0.2  # assets/scenes/solar_system.json
SCRIPT = """# alice: the solar system, the lever to Mars, then lift the ball and hold it (server_crash_test.py)
start -0.15 -0.25 0.15
await_world
press 1.5 -0.15 -0.08 0.020 0.006
reach 1.0 0.25 -0.05 0.15
hold 1.0
poke 1.0 0.25 0.07 0.075
poke 1.5 0.25 0.17 0.06
poke 0.8 0.25 0.05 0.10
reach 1.0 0 -0.06 0.16
hold 1.0
grasp 1.5 0 0.05 0.04 0.04 0.002
lift 1.5 0.05
hold 120
"""
HOLD_STARTS_S = 11.8  # script time of the final hold: the sum of the durations above


def trace(path):
    with open(path) as f:
        rows = []
        for row in csv.DictReader(f):
            try:
                rows.append({k: float(v) for k, v in row.items()})
            except (TypeError, ValueError):
                pass  # the line being written
        return rows


def mean_weight(rows):
    """The weight on the hand over rows (first to last): the haptic loop's impulse over that
    time divided by it, every step's force, not the bridge's samples of one step each. A held
    ball jiggles in the grip: single samples spread +-11 % around m g in a passing run, while
    50 ms impulse means stay within 1 %."""
    return -(net_jz(rows[-1]) - net_jz(rows[0])) / (rows[-1]["t_s"] - rows[0]["t_s"])


def window_weights(rows, t0, t1, window_s=0.05):
    """mean_weight over consecutive windows of window_s covering [t0, t1]: a ball dropped or
    thrown for 20 ms moves its window's mean by 40 %."""
    rows = [r for r in rows if t0 <= r["t_s"] <= t1]
    out, i = [], 0
    while i < len(rows) - 1:
        j = i + 1
        while j < len(rows) - 1 and rows[j]["t_s"] - rows[i]["t_s"] < window_s:
            j += 1
        out.append(mean_weight(rows[i:j + 1]))
        i = j
    return out


def wait_for_trace_time(path, t_s, timeout):
    end = time.monotonic() + timeout
    while time.monotonic() < end:
        rows = trace(path) if os.path.exists(path) else []
        if rows and rows[-1]["t_s"] >= t_s:
            return rows
        time.sleep(0.05)
    raise Failure(f"{path} did not reach loop time {t_s:.1f} s within {timeout} s")


def run(h, domain):
    domain = str(domain)
    session = f"it-crash-{os.getpid()}"
    db = os.path.join(h.work, "session.db")
    for f in (db, db + "-wal", db + "-shm"):
        if os.path.exists(f):
            os.remove(f)
    script = os.path.join(h.work, "alice.hand")
    with open(script, "w") as f:
        f.write(SCRIPT)
    alice_csv = os.path.join(h.work, "alice.csv")
    server_args = ["--domain", domain, "--session", session, "--scene", "start_menu", "--log", db]
    h.start("world_server", "world_server", *server_args)
    h.start("alice", "haptic_node", "--domain", domain, "--session", session, "--user", "alice",
            "--device", "sim", "--script", script, "--trace", alice_csv)
    h.start("audio_guide", "audio_guide", "--domain", domain, "--session", session,
            "--out", os.path.join(h.work, "speech"))
    h.wait_for_line("alice", "hand script starts at loop time", 30)
    t0 = float(re.search(r"hand script starts at loop time ([0-9.]+)", h.log("alice")).group(1))
    h.wait_for_line("world_server", "gravity -3.71", 30)
    h.wait_for_line("world_server", "object 'ball': owner '' -> 'alice'", 30)
    # alice holds the ball up: the kill comes 3.5 s into her final hold, once the ball has
    # settled in her hand (the first 2 s after a lift swing by up to 5 N).
    rows = wait_for_trace_time(alice_csv, t0 + HOLD_STARTS_S + 3.5, 40)
    before = mean_weight([r for r in rows if r["t_s"] >= t0 + HOLD_STARTS_S + 2.5])
    check(abs(before - BALL_KG * MARS) < 0.02 * BALL_KG * MARS,
          f"alice holds {before:.3f} N before the crash, not m g(Mars) = {BALL_KG * MARS:.3f} N")
    lines_before = h.log("world_server")

    # kill -9, and the same command line again.
    h.procs["world_server"][0].kill()
    h.procs["world_server"][0].wait()
    t_kill = rows[-1]["t_s"]
    killed_at = time.monotonic()
    h.start("world_server2", "world_server", *server_args)
    resumed_at = h.wait_for_line("world_server2", "resuming session #1", 10)
    owned_at = h.wait_for_line("world_server2", "object 'ball': owner '' -> 'alice'", 10)
    # A screen that joins only now draws the lever where alice left it (Mars' detent): the
    # restarted server publishes where its log says each control settled.
    state_file = os.path.join(h.work, "spectator_state.json")
    h.start("spectator", "graphics_node", "--domain", domain, "--session", session, "--headless",
            "--frames", 100000, "--fps", 2, "--out", os.path.join(h.work, "frames"), "--state-out", state_file)
    h.wait_for_line("spectator", "control 'lever_planet' of 'solar_system' at index 1 (by alice)", 60)
    # The state it writes names the controls of the world it shows: wait for that world too (the
    # control states can come before the scene state).
    h.wait_for_line("spectator", "scene 'solar_system' revision", 60)
    check(h.stop("spectator", 20) == 0, "the spectator did not end cleanly")
    with open(state_file) as f:
        shown = json.load(f)["controls"]
    check(shown.get("lever_planet") == {"index": 1, "engaged": False},
          f"a screen joining after the resume should show the lever in Mars' detent: {shown}")
    rows = wait_for_trace_time(alice_csv, t_kill + 6.0, 30)
    for label in ("alice", "audio_guide", "world_server2"):
        check(h.procs[label][0].poll() is None, f"{label} ended:\n{h.log(label)}")
        h.procs[label][0].send_signal(signal.SIGTERM)
    for label in ("alice", "audio_guide", "world_server2"):
        check(h.wait(label, 30) == 0, f"{label} did not end cleanly")

    resume_s, owner_s = resumed_at - killed_at, owned_at - killed_at
    check(resume_s <= 2.0, f"the restarted server resumed {resume_s:.2f} s after the kill (> 2 s)")
    check(owner_s <= 2.0, f"the ball was alice's again {owner_s:.2f} s after the kill (> 2 s)")
    server2 = h.log("world_server2")
    m = re.search(r"resuming session #1, .*: world '(\w+)' revision (\d+), (\d+) body poses, board message #(\d+)",
                  server2)
    check(m is not None, f"no resume line:\n{server2}")
    check(m.group(1) == "solar_system", f"resumed world '{m.group(1)}', not the solar system")
    # alice kept her models: the restarted server published the revision she has.
    alice = h.log("alice")
    scene_lines = [l for l in alice.splitlines() if re.search(r"scene '\w+' revision", l)]
    check(len(scene_lines) == 3, f"alice built {len(scene_lines)} scenes (start menu, solar system, Mars "
                                 f"expected; a 4th means the restart changed her world):\n" + "\n".join(scene_lines))
    check(f"revision {m.group(2)}:" in scene_lines[-1], f"resumed revision {m.group(2)} is not alice's last")
    # Her hand kept the weight through the crash and the resume: no drop, no jump.
    during = window_weights(rows, t_kill - 1.0, t_kill + 6.0)
    low, high = min(during), max(during)
    check(low > 0.95 * BALL_KG * MARS and high < 1.05 * BALL_KG * MARS,
          f"the held weight went {low:.3f}..{high:.3f} N in 50 ms windows around the crash "
          f"(m g = {BALL_KG * MARS:.3f} N)")
    after_mean = mean_weight([r for r in rows if r["t_s"] >= t_kill + 4.0])
    check(abs(after_mean - before) < 0.02 * before, f"held {before:.3f} N before, {after_mean:.3f} N after")
    faults = sum(1 for r in rows if r["fault"] != 0)
    check(faults == 0, f"{faults} faulted steps in alice's trace")
    # The board: the same message again, not spoken twice.
    wavs = sorted(f for f in os.listdir(os.path.join(h.work, "speech")) if f.startswith("message_") and f.endswith(".wav"))
    spoken = len(re.findall(r"message board #", lines_before))
    check(len(wavs) == spoken, f"{len(wavs)} messages spoken for {spoken} shown before the crash: {wavs}")

    # The log: every control event the killed server printed is a committed row of session 1.
    printed = len(re.findall(r"\] control \S+: \w+ by alice", lines_before))
    con = sqlite3.connect(db)
    rows1 = con.execute("SELECT count(*) FROM control_events WHERE session_id = 1").fetchone()[0]
    ended1, = con.execute("SELECT ended_unix_ns FROM sessions WHERE id = 1").fetchone()
    resumed_from, = con.execute("SELECT resumed_from FROM sessions WHERE id = 2").fetchone()
    con.close()
    check(printed > 0 and rows1 == printed, f"{printed} control events printed, {rows1} in the log")
    check(ended1 is None and resumed_from == 1, f"session 1 ended {ended1}, session 2 resumes {resumed_from}")
    print(f"crashed server: resumed {resume_s:.2f} s after kill -9 (world '{m.group(1)}' revision {m.group(2)}, "
          f"{m.group(3)} poses, message #{m.group(4)}); ball alice's again after {owner_s:.2f} s; held weight "
          f"{before:.3f} N before, {low:.3f}..{high:.3f} N through the crash, {after_mean:.3f} N after; "
          f"{rows1} control events committed of {printed} printed")
    h.print_traffic()


if __name__ == "__main__":
    sys.exit(run_cases({"server_crash": run}))
