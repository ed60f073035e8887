#!/usr/bin/python3
"""Motion to photon at the desk (issue "A person at the controls", point 3; docs/devices.md):
from a real X input event (a pointer move sent with xdotool to the user's own view) to the first
frame that shows the hand moved, measured on one machine's steady clock (CLOCK_MONOTONIC: this
script's time.monotonic_ns() and the view's --frame-log stamps are the same clock).

The session: a virtual display (Xvfb), a world server in WORLD, `haptic_node --device desk`
for alice and her own view (`graphics_node --view user:alice --input desk`) in a WIDTH x HEIGHT
window at FPS, with Mesa's software GL. The path measured is the whole of it: X server ->
the view's input -> DeskInput over DDS -> the haptic node's 1 kHz loop (the desk's filter moves
the hand) -> DeviceState over DDS -> the view's next frame, swapped.

A frame shows the hand moved when the world's origin, projected through that frame's camera
(a user's view follows the hand base), lands at least THRESHOLD_PX pixels from where it was in
the last frame before the event. Each move jumps the pointer MOVE_PX pixels left or right of
the window's centre (alternately), at a random 0.3-0.6 s after the hand came to rest, so that
the event falls anywhere in the frame period. The event is sent as xdotool sends its own, through
the X server's XTEST extension (libXtst, which xdotool uses), but from this process (ctypes), so
that the time taken just before it is the event's and not a program's start-up (xdotool's own
start took 40 ms on a loaded machine); send_ms is how long sending it took.

usage: motion_to_photon.py --bin-dir BUILD [--moves 200] [--width 1280] [--height 720] [--fps 60]
                           [--world solar_system] [--move-px 40] [--threshold-px 1]
                           [--domain 216] [--work DIR] [--csv FILE] [--png FILE]
Writes one CSV row per move (move, direction, send_ms, latency_ms, frames_after_event,
first_change_ms: the first frame whose hand base differs at all, before the desk's filter has
moved it a pixel; loop_moved_ms: the haptic loop's step that made that frame's state, after
the event; state_to_photon_ms: from the step of the state in the first visible frame to that
frame on the screen) and
prints p50 / p99 / max and the load. A bench: it asserts nothing.
"""
import argparse
import ctypes
import csv
import os
import random
import shutil
import subprocess
import sys
import time

from bench_session import BenchSession  # noqa: E402


def xdotool(*args):
    r = subprocess.run(["xdotool", *map(str, args)], capture_output=True, text=True, timeout=60)
    if r.returncode != 0:
        sys.exit(f"xdotool {' '.join(map(str, args))} failed: {r.stderr}")
    return r.stdout.strip()


class XTest:
    """Pointer motion through the X server's XTEST extension, as xdotool sends it."""

    def __init__(self, display):
        self.x11 = ctypes.CDLL("libX11.so.6")
        self.xtst = ctypes.CDLL("libXtst.so.6")
        self.x11.XOpenDisplay.restype = ctypes.c_void_p
        self.x11.XOpenDisplay.argtypes = [ctypes.c_char_p]
        self.x11.XSync.argtypes = [ctypes.c_void_p, ctypes.c_int]
        self.x11.XCloseDisplay.argtypes = [ctypes.c_void_p]
        self.xtst.XTestFakeMotionEvent.argtypes = [ctypes.c_void_p, ctypes.c_int, ctypes.c_int, ctypes.c_int,
                                                   ctypes.c_ulong]
        self.dpy = self.x11.XOpenDisplay(display.encode())
        if not self.dpy:
            sys.exit(f"cannot open the X display {display}")

    def move(self, x, y):
        """The pointer to screen pixel (x, y), delivered to the server (XSync) on return."""
        if not self.xtst.XTestFakeMotionEvent(self.dpy, -1, x, y, 0):
            sys.exit("XTestFakeMotionEvent failed (no XTEST extension?)")
        self.x11.XSync(self.dpy, 0)

    def close(self):
        self.x11.XCloseDisplay(self.dpy)


class FrameLog:
    """The view's --frame-log, read as it grows: rows of (t_ns, anchor_x_px, anchor_y_px, hand)."""

    def __init__(self, path):
        self.path, self.offset, self.rows, self.partial = path, 0, [], ""

    def poll(self):
        if not os.path.exists(self.path):
            return
        with open(self.path) as f:
            f.seek(self.offset)
            text = f.read()
            self.offset = f.tell()
        lines = (self.partial + text).split("\n")
        self.partial = lines.pop()
        for line in lines:
            cells = line.split(",")
            if not line or cells[0] == "frame" or cells[2] == "":
                continue  # the header, or a frame without alice's hand
            self.rows.append((int(cells[1]), float(cells[5]), float(cells[6]),
                              (float(cells[2]), float(cells[3]), float(cells[4])), int(cells[7])))


def percentile(values, p):
    s = sorted(values)
    return s[min(len(s) - 1, int(round(p / 100.0 * (len(s) - 1))))]


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--bin-dir", required=True)
    ap.add_argument("--moves", type=int, default=200)
    ap.add_argument("--width", type=int, default=1280)
    ap.add_argument("--height", type=int, default=720)
    ap.add_argument("--fps", type=float, default=60.0)
    ap.add_argument("--world", default="solar_system")
    ap.add_argument("--move-px", type=int, default=40)
    ap.add_argument("--threshold-px", type=float, default=1.0)
    ap.add_argument("--domain", default="216")
    ap.add_argument("--work", default="/tmp/motion_to_photon")
    ap.add_argument("--csv", default="")
    ap.add_argument("--png", default="")
    a = ap.parse_args()
    for tool in ("Xvfb", "xdotool"):
        if shutil.which(tool) is None:
            sys.exit(f"{tool} is not installed (deploy/install_deps.sh installs xvfb and xdotool)")
    os.makedirs(a.work, exist_ok=True)
    frame_log = os.path.join(a.work, "frames.csv")
    if os.path.exists(frame_log):
        os.remove(frame_log)
    run = BenchSession(a.bin_dir, a.work)
    display = run.start_display(a.width, a.height)
    session = f"mtp-{os.getpid()}"
    common = ["--domain", a.domain, "--session", session]
    try:
        run.start("world_server", "world_server/world_server", *common, "--scene", a.world)
        run.start("alice", "haptic_node/haptic_node", *common, "--user", "alice", "--device", "desk")
        run.start("view", "graphics_node/graphics_node", *common, "--name", "mtp-view", "--view", "user:alice",
                  "--input", "desk", "--width", a.width, "--height", a.height, "--fps", a.fps, "--frame-log", frame_log)
        run.wait_log("alice", f"scene '{a.world}' revision", 120)
        window = xdotool("search", "--sync", "--onlyvisible", "--name", "alice at the desk").split()[0]
        xdotool("windowfocus", "--sync", window)
        centre_x, centre_y = a.width // 2, a.height // 2
        xdotool("mousemove", "--window", window, centre_x, centre_y)
        run.wait_log("alice", "desk: the hand is live", 60)
        frames = FrameLog(frame_log)
        geometry = dict(line.split("=", 1) for line in xdotool("getwindowgeometry", "--shell", window).splitlines())
        origin_x, origin_y = int(geometry["X"]), int(geometry["Y"])
        xtest = XTest(display)

        def rest_anchor(hold_s):
            """Waits until the hand has stayed put (its drawn base within 0.1 mm) for hold_s; the
            newest frame's anchor."""
            deadline = time.monotonic() + 30
            while time.monotonic() < deadline:
                frames.poll()
                if frames.rows:
                    t_last, hand = frames.rows[-1][0], frames.rows[-1][3]
                    still = [r for r in frames.rows if r[0] >= t_last - hold_s * 1e9]
                    if (still and still[0][0] <= t_last - 0.9 * hold_s * 1e9 and
                            all(max(abs(p - q) for p, q in zip(r[3], hand)) < 1e-4 for r in still)):
                        return frames.rows[-1]
                time.sleep(0.01)
            sys.exit("the hand did not come to rest within 30 s")

        rest_anchor(0.5)
        results = []
        rng = random.Random(1)
        for move in range(a.moves):
            rest = rest_anchor(0.2)
            time.sleep(rng.uniform(0.3, 0.6))
            frames.poll()
            rest = frames.rows[-1]
            direction = 1 if move % 2 == 0 else -1
            t0 = time.monotonic_ns()
            xtest.move(origin_x + centre_x + direction * a.move_px, origin_y + centre_y)
            send_ms = (time.monotonic_ns() - t0) * 1e-6
            seen = None
            deadline = time.monotonic() + 3.0
            while seen is None and time.monotonic() < deadline:
                frames.poll()
                after = [r for r in frames.rows if r[0] > t0]
                for i, r in enumerate(after):
                    if ((r[1] - rest[1]) ** 2 + (r[2] - rest[2]) ** 2) ** 0.5 >= a.threshold_px:
                        seen = (r, i)
                        break
                if seen is None:
                    time.sleep(0.002)
            if seen is None:
                print(f"move {move}: no frame showed the hand moved within 3 s", flush=True)
                results.append((move, direction, send_ms, float("nan"), -1, float("nan"), float("nan"), float("nan")))
                continue
            latency_ms = (seen[0][0] - t0) * 1e-6
            # The first frame whose hand base differs at all from the rest's: the path without the
            # desk filter's ramp up to a visible pixel.
            first = next(r for r in frames.rows if r[0] > t0 and r[3] != rest[3])
            # Its stamp: the haptic loop's step that first moved the hand, on the same clock.
            results.append((move, direction, send_ms, latency_ms, seen[1], (first[0] - t0) * 1e-6,
                            (first[4] - t0) * 1e-6, (seen[0][0] - seen[0][4]) * 1e-6))
        load = os.getloadavg()
        xtest.close()
    finally:
        run.stop()
    latencies = [r[3] for r in results if r[3] == r[3]]
    missing = len(results) - len(latencies)
    if not latencies:
        sys.exit("no move was seen in a frame")
    p50, p99, worst = percentile(latencies, 50), percentile(latencies, 99), max(latencies)
    x50 = percentile([r[2] for r in results], 50)
    firsts = [r[5] for r in results if r[5] == r[5]]
    loops = [r[6] for r in results if r[6] == r[6]]
    shown = [r[7] for r in results if r[7] == r[7]]
    print(f"motion to photon at {a.width} x {a.height}, {a.fps:g} fps, world {a.world}: {len(latencies)} moves "
          f"({missing} unseen): p50 {p50:.1f} ms, p99 {p99:.1f} ms, max {worst:.1f} ms (sending the event: "
          f"p50 {x50:.2f} ms, inside the figures); the first frame with the hand moved at all: p50 {percentile(firsts, 50):.1f} ms, "
          f"p99 {percentile(firsts, 99):.1f} ms; the haptic loop's step that first moved it: p50 "
          f"{percentile(loops, 50):.1f} ms, p99 {percentile(loops, 99):.1f} ms after the event; from the step "
          f"of the state in the first visible frame to that frame: p50 {percentile(shown, 50):.1f} ms, p99 "
          f"{percentile(shown, 99):.1f} ms; load average {load[0]:.2f} {load[1]:.2f} {load[2]:.2f}")
    if a.csv:
        with open(a.csv, "w", newline="") as f:
            w = csv.writer(f)
            w.writerow(["move", "direction", "send_ms", "latency_ms", "frames_after_event", "first_change_ms",
                        "loop_moved_ms", "state_to_photon_ms"])
            for r in results:
                w.writerow([r[0], r[1], f"{r[2]:.3f}", f"{r[3]:.3f}", r[4], f"{r[5]:.3f}", f"{r[6]:.3f}", f"{r[7]:.3f}"])
    if a.png:
        import matplotlib
        matplotlib.use("Agg")
        import matplotlib.pyplot as plt
        fig, (left, right) = plt.subplots(1, 2, figsize=(10, 4))
        left.hist(latencies, bins=30, color="tab:blue")
        for v, label, style in ((p50, "p50", "-"), (p99, "p99", "--"), (50.0, "target p99", ":")):
            left.axvline(v, color="k" if label != "target p99" else "tab:red", linestyle=style,
                         label=f"{label} {v:.1f} ms")
        left.set_xlabel("input event to first frame showing the hand moved [ms]")
        left.set_ylabel("moves")
        left.legend()
        right.plot(range(len(latencies)), latencies, ".", markersize=3)
        right.axhline(50.0, color="tab:red", linestyle=":")
        right.set_xlabel("move")
        right.set_ylabel("latency [ms]")
        fig.suptitle(f"Motion to photon at the desk: {a.width} x {a.height}, {a.fps:g} fps, Mesa software GL, "
                     f"load {load[0]:.1f}")
        fig.tight_layout()
        fig.savefig(a.png, dpi=100)
    return 0


if __name__ == "__main__":
    sys.exit(main())
