#!/usr/bin/python3
"""What a screen shows of a hand (issue "Hand to hand as fast as the wire", point 3;
docs/network.md): from a haptic step to the first spectator frame that shows it, on one machine's
steady clock (a device state's stamp is the haptic loop's step that made it, CLOCK_MONOTONIC; the
spectator's --frame-log stamps each frame once it is swapped, on the same clock).

The session: a virtual display (Xvfb), a world server in WORLD, a scripted hand (`haptic_node
--device sim --script bench/graphics/spectator_sweep.hand`: sweeps to and fro with short rests)
and a spectator window (`graphics_node`, no --view: the large screen) at WIDTH x HEIGHT and FPS
with Mesa's software GL. Each device state the spectator received is a haptic step; its latency
is from that step to the first frame that draws it or a newer state of the hand (the frame log's
hand_stamp_ns). States the spectator never drew (a newer one came before its frame) count at
the frame that drew the newer one.

usage: spectator_to_photon.py --bin-dir BUILD [--seconds 30] [--width 1280] [--height 720]
                              [--fps 60] [--frame-pacing states|clock] [--domain 217] [--work DIR] [--csv FILE] [--png FILE]
Writes one CSV row per frame that drew a new state (frame, state_stamp_ns, frame_ns,
latency_ms, states_skipped) and prints p50 / p99 / max, the target (one frame period + 5 ms)
and the load. A bench: it asserts nothing.
"""
import argparse
import csv
import os
import shutil
import sys
import time

HERE = os.path.dirname(os.path.abspath(__file__))
from bench_session import BenchSession  # noqa: E402
from motion_to_photon import percentile  # noqa: E402


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--bin-dir", required=True)
    ap.add_argument("--seconds", type=float, default=30.0)
    ap.add_argument("--width", type=int, default=1280)
    ap.add_argument("--height", type=int, default=720)
    ap.add_argument("--fps", type=float, default=60.0)
    ap.add_argument("--world", default="solar_system")
    ap.add_argument("--frame-pacing", default="states", choices=["states", "clock"],
                    help="the spectator's --frame-pacing (states: frames follow the hands' states)")
    ap.add_argument("--domain", default="217")
    ap.add_argument("--work", default="/tmp/spectator_to_photon")
    ap.add_argument("--csv", default="")
    ap.add_argument("--png", default="")
    a = ap.parse_args()
    if shutil.which("Xvfb") is None:
        sys.exit("Xvfb is not installed (deploy/install_deps.sh installs xvfb)")
    os.makedirs(a.work, exist_ok=True)
    frame_log = os.path.join(a.work, "frames.csv")
    if os.path.exists(frame_log):
        os.remove(frame_log)
    run = BenchSession(a.bin_dir, a.work)
    run.start_display(a.width, a.height)
    session = f"stp-{os.getpid()}"
    common = ["--domain", a.domain, "--session", session]
    try:
        run.start("world_server", "world_server/world_server", *common, "--scene", a.world)
        run.start("screen", "graphics_node/graphics_node", *common, "--name", "stp-screen", "--width", a.width,
                  "--height", a.height, "--fps", a.fps, "--frame-log", frame_log, "--frame-pacing", a.frame_pacing)
        run.start("alice", "haptic_node/haptic_node", *common, "--user", "alice", "--device", "sim", "--script",
                  os.path.join(HERE, "spectator_sweep.hand"))
        run.wait_log("alice", f"scene '{a.world}' revision", 120)
        time.sleep(2.0)  # the spectator's window opens and the sweeps begin
        t_start = time.monotonic_ns()
        time.sleep(a.seconds)  # the measurement window: the frames logged meanwhile
        t_end = time.monotonic_ns()
        load = os.getloadavg()
    finally:
        run.stop()
    rows = []
    last_stamp = 0
    frames = 0
    with open(frame_log) as f:
        for r in csv.DictReader(f):
            if r.get("draw_ms") is None:
                continue  # the last row, cut off when the spectator was stopped
            t_ns, stamp = int(r["t_ns"]), int(r["hand_stamp_ns"] or 0)
            if not (t_start <= t_ns <= t_end) or stamp == 0:
                last_stamp = max(last_stamp, stamp)
                continue
            frames += 1
            if stamp > last_stamp:
                rows.append((int(r["frame"]), stamp, t_ns, (t_ns - stamp) * 1e-6))
                last_stamp = stamp
    if not rows:
        sys.exit(f"the spectator drew no state of the hand in {a.seconds:g} s (see {a.work})")
    latencies = [r[3] for r in rows]
    p50, p99, worst = percentile(latencies, 50), percentile(latencies, 99), max(latencies)
    target = 1e3 / a.fps + 5.0
    seconds = (t_end - t_start) * 1e-9
    print(f"haptic step to spectator photon at {a.width} x {a.height}, {a.fps:g} fps, frames paced by "
          f"{a.frame_pacing}, world {a.world}: "
          f"{len(rows)} states drawn in {frames} frames ({frames / seconds:.1f} fps) over {seconds:.0f} s: "
          f"p50 {p50:.1f} ms, p99 {p99:.1f} ms, max {worst:.1f} ms (target p99 <= {target:.1f} ms); "
          f"load average {load[0]:.2f} {load[1]:.2f} {load[2]:.2f}")
    if a.csv:
        with open(a.csv, "w", newline="") as f:
            w = csv.writer(f)
            w.writerow(["frame", "state_stamp_ns", "frame_ns", "latency_ms"])
            for r in rows:
                w.writerow([r[0], r[1], r[2], f"{r[3]:.3f}"])
    if a.png:
        import matplotlib
        matplotlib.use("Agg")
        import matplotlib.pyplot as plt
        fig, ax = plt.subplots(figsize=(6, 4))
        ax.hist(latencies, bins=40, color="tab:blue")
        for v, label, colour, style in ((p50, "p50", "k", "-"), (p99, "p99", "k", "--"),
                                        (target, "target", "tab:red", ":")):
            ax.axvline(v, color=colour, linestyle=style, label=f"{label} {v:.1f} ms")
        ax.set_xlabel("haptic step to the spectator frame that shows it [ms]")
        ax.set_ylabel("states")
        ax.legend()
        ax.set_title(f"{a.width} x {a.height} at {a.fps:g} fps, Mesa software GL, load {load[0]:.1f}")
        fig.tight_layout()
        fig.savefig(a.png, dpi=100)
    return 0


if __name__ == "__main__":
    sys.exit(main())
