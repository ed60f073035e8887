#!/usr/bin/env python3
"""A person at a desk, tested as one: real X input events (xdotool) to the window of a user's own
view (graphics_node --view user:alice --input desk) under a virtual display (Xvfb), and with
those events alone alice's hand (haptic_node --device desk) moves: the haptic node's trace shows
the hand base where the pointer put it; the hand presses the start menu's solar-system button
and the world server opens the solar system; it grasps the ball on the Moon and lifts it (held
weight m g within 5 %, a frame of the window grabbed meanwhile) and pushes the lever to Mars;
presses the arrow to the dinosaur world and there, with a closed hand, the triceratops' tail
beside bob's scripted hand (the deformation the world server publishes equals an independent
FEM solve, fem_solve, of both users' contacts, and a spectator receives it, as in the tour);
the window losing focus releases the hand, and so does the view going quiet (killed).

Needs Xvfb and xdotool (Debian: xvfb, xdotool; deploy/install_deps.sh); without them the test is
skipped (77).

usage: desk_test.py --bin-dir DIR --domain D --work DIR
"""
import ctypes
import math
import os
import select
import shutil
import signal
import subprocess
import sys
import time

HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, HERE)
from session_test import (DATA, PressWatch, check, check_shared_deformation, fem_cache, net_jz, read_trace,  # noqa: E402
                          run_cases, scene_object, wait_until)

# The desk's mapping (graphics_node/include/handshare/graphics/desk_control.hpp, DeskControlConfig).
HOME = (0.0, -0.20, 0.15)
HALF_WIDTH_M, HALF_HEIGHT_M, DEPTH_STEP_M = 0.30, 0.15, 0.01
WIDTH, HEIGHT = 640, 480  # the window
# The desk's hand (haptic_node/src/desk_device.hpp, DeskFingertip_H): fingertips on a ring about
# a grasp centre in the hand base's frame, thumb first at azimuth -90 deg, 72 deg apart, 15 deg
# below it; radius 75 mm open, 10 mm closed.
GRASP_CENTRE_H = (0.0, 0.07, -0.03)
RING_OPEN_M, RING_CLOSED_M = 0.075, 0.010
BALL_KG, MOON_G = 0.2, 1.62  # the solar system's ball (assets/scenes/solar_system.json)


def fingertip_h(finger, closure):
    a = math.radians(-90 + 72 * finger)
    e = math.radians(-15)
    r = RING_OPEN_M + closure * (RING_CLOSED_M - RING_OPEN_M)
    n = (math.cos(e) * math.cos(a), math.cos(e) * math.sin(a), math.sin(e))
    return tuple(c + r * k for c, k in zip(GRASP_CENTRE_H, n))


def pointer_for(x_m, z_m):
    """The window pixel whose pointer puts the hand base at x_m, z_m."""
    col = round((1.0 + (x_m - HOME[0]) / HALF_WIDTH_M) / 2.0 * WIDTH)
    row = round((1.0 - (z_m - HOME[2]) / HALF_HEIGHT_M) / 2.0 * HEIGHT)
    return min(max(col, 0), WIDTH - 1), min(max(row, 0), HEIGHT - 1)


def launch_xvfb(screen, log):
    """A virtual display of its own (Xvfb picks a free number and writes it to a pipe), its
    screen WxHxD: (the Xvfb process, ':N')."""
    read_end, write_end = os.pipe()
    # -noreset: by default the server resets when its last client goes, and refuses connections
    # meanwhile (a view starting just as the readiness check below or xdotool disconnects got
    # "Failed to open display").
    proc = subprocess.Popen(["Xvfb", "-displayfd", str(write_end), "-screen", "0", screen, "-nolisten", "tcp",
                             "-noreset"],
                            pass_fds=(write_end,), stdout=log, stderr=subprocess.STDOUT)
    os.close(write_end)
    number = b""
    deadline = time.monotonic() + 30
    while not number.endswith(b"\n"):
        ready, _, _ = select.select([read_end], [], [], max(0.0, deadline - time.monotonic()))
        check(ready, "Xvfb did not say its display number within 30 s")
        chunk = os.read(read_end, 16)
        check(chunk, "Xvfb ended without a display")
        number += chunk
    os.close(read_end)
    display = ":" + number.decode().strip()
    # The number is written once the server listens; a client is only sure of it once it
    # connects: wait until a connection is taken (or say why not).
    x11 = ctypes.CDLL("libX11.so.6")
    x11.XOpenDisplay.restype = ctypes.c_void_p
    x11.XOpenDisplay.argtypes = [ctypes.c_char_p]
    x11.XCloseDisplay.argtypes = [ctypes.c_void_p]
    while True:
        check(proc.poll() is None, f"Xvfb on {display} exited ({proc.returncode}) right after it started")
        connection = x11.XOpenDisplay(display.encode())
        if connection:
            x11.XCloseDisplay(connection)
            return proc, display
        check(time.monotonic() < deadline, f"Xvfb said {display} but took no connection within 30 s")
        time.sleep(0.05)


def start_xvfb(h):
    """The test's virtual display; it ends with the test's other processes."""
    log = open(os.path.join(h.work, "xvfb.log"), "w")
    proc, display = launch_xvfb("1024x768x24", log)
    h.procs["xvfb"] = (proc, log)
    return display


def xdotool(*args, timeout=30):
    """One xdotool command on the test's display; its output."""
    r = subprocess.run(["xdotool", *map(str, args)], capture_output=True, text=True, timeout=timeout)
    check(r.returncode == 0, f"xdotool {' '.join(map(str, args))} failed ({r.returncode}): {r.stderr}")
    return r.stdout.strip()


def grab_window(window, path):
    """The window's pixels as the X server has them, to a PNG (a frame of what the person sees);
    a note instead where this Pillow cannot read the X display."""
    geometry = dict(line.split("=", 1) for line in xdotool("getwindowgeometry", "--shell", window).splitlines())
    x, y, width, height = (int(geometry[k]) for k in ("X", "Y", "WIDTH", "HEIGHT"))
    try:
        from PIL import ImageGrab
        ImageGrab.grab(bbox=(x, y, x + width, y + height), xdisplay=os.environ["DISPLAY"]).save(path)
        print(f"frame: {path}")
    except (ImportError, OSError) as e:
        print(f"no frame of the window ({e})")


def live_rows(trace):
    return [r for r in read_trace(trace) if r["fault"] == 0.0]


def hand_near(trace, x=None, y=None, z=None, tol=0.005):
    """The newest valid row has the hand base within tol of the given coordinates."""
    rows = live_rows(trace)
    if not rows:
        return False
    r = rows[-1]
    return all(want is None or abs(r[c] - want) <= tol for c, want in (("hx", x), ("hy", y), ("hz", z)))


def newest(trace):
    rows = read_trace(trace)
    return rows[-1] if rows else None


def case_desk(h, domain):
    for tool in ("Xvfb", "xdotool"):
        if shutil.which(tool) is None:
            print(f"SKIP: {tool} is not installed (deploy/install_deps.sh installs xvfb and xdotool)")
            sys.exit(77)
    session = f"it-desk-{os.getpid()}"
    w = h.work
    trace = os.path.join(w, "alice.csv")
    common = ["--domain", domain, "--session", session]
    # The dinosaur world's models, prepared before the session (as the README advises), in the
    # build's shared model cache.
    cache = fem_cache(w)
    os.environ["HANDSHARE_CACHE"] = cache
    prep = subprocess.run([os.path.join(h.bin_dir, "core", "world", "world_prepare"), "--cache", cache,
                           "--scenes", "dinosaur"], capture_output=True, text=True, timeout=600)
    check(prep.returncode == 0, f"world_prepare failed: {prep.stdout}{prep.stderr}")
    os.environ["DISPLAY"] = start_xvfb(h)
    dump = os.path.join(w, "deformation")
    received_file = os.path.join(w, "received_deformation.json")
    h.start("world_server", "world_server", *common, "--scene", "start_menu",
            "--dump-deformation", dump, "--deformation-threshold", "5e-5")
    # A spectator, for what every screen receives of the tail alice and bob press.
    h.start("spectator", "graphics_node", *common, "--headless", "--frames", 100000, "--fps", 2,
            "--out", os.path.join(w, "frames"), "--deformation-out", received_file)
    h.start("alice", "haptic_node", *common, "--user", "alice", "--device", "desk", "--trace", trace)
    # bob is a scripted hand: he waits high above the table until the dinosaur world is here,
    # then presses the tail and holds (tests/data/desk_bob.hand).
    h.start("bob", "haptic_node", *common, "--user", "bob", "--script", os.path.join(DATA, "desk_bob.hand"))
    h.start("view", "graphics_node", *common, "--name", "desk-alice", "--view", "user:alice", "--input", "desk",
            "--width", WIDTH, "--height", HEIGHT, "--fps", 30)
    h.wait_for_line("alice", "scene 'start_menu' revision 1", 60)
    window = xdotool("search", "--sync", "--onlyvisible", "--name", "alice at the desk", timeout=90).split()[0]
    # No window manager: the test gives the window the keyboard focus, as a click would.
    xdotool("windowfocus", "--sync", window)
    xdotool("mousemove", "--window", window, WIDTH // 2, HEIGHT // 2)
    h.wait_for_line("view", "desk: the window has focus", 30)
    h.wait_for_line("alice", "desk: the hand is live", 30)
    wait_until("alice's hand at home, as the pointer at the window's centre puts it", 30,
               lambda: hand_near(trace, *HOME), lambda: f"newest trace row: {newest(trace)}")

    # The pointer to the right and up: the hand follows, smoothly, in the same directions.
    col, row = pointer_for(0.20, 0.20)
    xdotool("mousemove", "--window", window, col, row)
    wait_until("alice's hand 0.2 m right and 5 cm up", 30, lambda: hand_near(trace, 0.20, HOME[1], 0.20),
               lambda: f"newest trace row: {newest(trace)}")
    rows = live_rows(trace)
    steps = [abs(b["hx"] - a["hx"]) / max(b["t_s"] - a["t_s"], 1e-6) for a, b in zip(rows, rows[1:])
             if b["t_s"] > a["t_s"]]
    check(max(steps) <= 0.26, f"the hand base moved at up to {max(steps):.3f} m/s (the desk's bound: 0.25 m/s)")
    print(f"pointer right and up: hand at x {rows[-1]['hx']:.3f} m, z {rows[-1]['hz']:.3f} m, "
          f"base speed at most {max(steps):.3f} m/s")

    # The start menu's solar-system button (-0.15, -0.08, 0.012): the middle fingertip above
    # it (the pointer, and S once: a centimetre towards you), then down onto it.
    middle = fingertip_h(2, 0.0)
    x_base = -0.15 - middle[0]
    y_base = HOME[1] - DEPTH_STEP_M
    check(abs(y_base + middle[1] + 0.08) < 0.005, "the middle fingertip must come over the button")
    z_above = 0.012 + 0.05 - middle[2]
    xdotool("mousemove", "--window", window, *pointer_for(x_base, z_above))
    xdotool("key", "s")
    wait_until("alice's middle finger above the solar-system button", 30,
               lambda: hand_near(trace, x_base, y_base, z_above, tol=0.006),
               lambda: f"newest trace row: {newest(trace)}")
    xdotool("mousemove", "--window", window, *pointer_for(x_base, 0.0 - middle[2]))
    h.wait_for_line("world_server", "control button_solar_system by alice: scene 'solar_system'", 60)
    h.wait_for_line("alice", "scene 'solar_system'", 60)
    print("the pointer pressed the solar-system button: the solar system is open")
    xdotool("mousemove", "--window", window, *pointer_for(0.0, 0.15))

    # The ball on the Moon (0, 0.05, 0.04), radius 0.04: the grasp centre over it (the wheel,
    # 18 notches away from you, with S's centimetre back), down around it, C five times (the
    # ring 42.5 mm: 5.5 mm inside the fingertips' contact distance), then lifted 5 cm.
    ball = (0.0, 0.05, 0.04)
    x_base, y_base = ball[0] - GRASP_CENTRE_H[0], ball[1] - GRASP_CENTRE_H[1]
    notches = round((y_base - HOME[1]) / DEPTH_STEP_M) + 1  # + the centimetre of S
    for _ in range(notches):
        xdotool("click", 4)  # the wheel, away from you
    z_grasp = ball[2] - GRASP_CENTRE_H[2]
    wait_until("alice's open hand over the ball", 30, lambda: hand_near(trace, x_base, y_base, 0.15, tol=0.006),
               lambda: f"newest trace row: {newest(trace)}")
    xdotool("mousemove", "--window", window, *pointer_for(x_base, z_grasp))
    wait_until("alice's open hand around the ball", 30, lambda: hand_near(trace, x_base, y_base, z_grasp, tol=0.004),
               lambda: f"newest trace row: {newest(trace)}")
    xdotool("key", "c", "c", "c", "c", "c")
    closed = [fingertip_h(i, 0.5) for i in range(5)]
    wait_until("alice's hand closed around the ball", 30,
               lambda: live_rows(trace) and all(abs(live_rows(trace)[-1][f"y{i}"] - (y_base + closed[i][1])) < 0.003
                                                for i in range(5)),
               lambda: f"newest trace row: {newest(trace)}")
    z_lift = z_grasp + 0.05
    xdotool("mousemove", "--window", window, *pointer_for(x_base, z_lift))
    wait_until("alice's hand up 5 cm", 30, lambda: hand_near(trace, x_base, y_base, z_lift, tol=0.004),
               lambda: f"newest trace row: {newest(trace)}")
    start_rows = len(read_trace(trace))
    # As the tour's check: the last 2 s of a 3 s hold (the ball settles in the hand first).
    wait_until("3 s of trace with the hand still", 60, lambda: len(read_trace(trace)) >= start_rows + 300)
    rows = read_trace(trace)[start_rows + 100:start_rows + 300]
    held = [-sum(r[f"fz{i}"] for i in range(5)) for r in rows]
    # The mean force from the loop's impulse (every 1 ms step's force over the time it was
    # held), not the mean of the rows: the grip's force swings by +-2 N between steps, and the
    # rows sample it at the bridge's ticks (a busy machine shifts them: 0.304 N of 0.324 once).
    weight = -(net_jz(rows[-1]) - net_jz(rows[0])) / (rows[-1]["t_s"] - rows[0]["t_s"])
    print(f"held weight on the Moon {weight:.3f} N (m g = {BALL_KG * MOON_G:.3f} N), "
          f"from {min(held):.3f} to {max(held):.3f} N over {len(held)} rows")
    check(abs(weight - BALL_KG * MOON_G) <= 0.05 * BALL_KG * MOON_G,
          f"the held weight {weight:.3f} N is not the ball's {BALL_KG * MOON_G:.3f} N within 5 %")
    h.wait_for_line("world_server", "object 'ball': owner '' -> 'alice' (granted)", 10)
    grab_window(window, os.path.join(w, "desk_holding_ball.png"))
    xdotool("key", "o")

    # The lever (0.25, 0.1, 0): the middle fingertip behind its handle, then away from you into
    # Mars' detent, as the tour's hand pushes it (0.25, 0.07, 0.075) -> (0.25, 0.17, 0.06): the
    # pointer places it, the wheel pushes.
    middle = fingertip_h(2, 0.0)
    x_lever = 0.25 - middle[0]
    y_behind, y_pushed = 0.07 - middle[1], 0.17 - middle[1]
    z_behind, z_pushed = 0.075 - middle[2], 0.06 - middle[2]
    xdotool("mousemove", "--window", window, *pointer_for(x_lever, 0.20))
    notches = round((y_behind - y_base) / DEPTH_STEP_M)
    for _ in range(abs(notches)):
        xdotool("click", 4 if notches > 0 else 5)  # the wheel: 4 away from you, 5 towards you
    y_behind = y_base + notches * DEPTH_STEP_M
    wait_until("alice's hand over the lever", 30, lambda: hand_near(trace, x_lever, y_behind, 0.20, tol=0.006),
               lambda: f"newest trace row: {newest(trace)}")
    xdotool("mousemove", "--window", window, *pointer_for(x_lever, z_behind))
    wait_until("alice's middle finger behind the lever's handle", 30,
               lambda: hand_near(trace, x_lever, y_behind, z_behind, tol=0.006),
               lambda: f"newest trace row: {newest(trace)}")
    xdotool("mousemove", "--window", window, *pointer_for(x_lever, z_pushed))
    for _ in range(round((y_pushed - y_behind) / DEPTH_STEP_M)):
        xdotool("click", 4)
    h.wait_for_line("world_server", "gravity -3.71 m/s^2", 60)
    print("the wheel pushed the lever to Mars")
    xdotool("mousemove", "--window", window, *pointer_for(x_lever, 0.25))
    y_base = y_pushed
    wait_until("alice's hand up from the lever", 30, lambda: hand_near(trace, x_lever, y_base, 0.25, tol=0.006),
               lambda: f"newest trace row: {newest(trace)}")

    # The arrow to the dinosaur world (0.25, -0.18, 0.01): the middle fingertip over it (the
    # wheel towards you), then down onto it, as onto the start menu's button.
    arrow = (0.25, -0.18, 0.01)
    x_base = arrow[0] - middle[0]
    notches = round((arrow[1] - middle[1] - y_base) / DEPTH_STEP_M)
    for _ in range(abs(notches)):
        xdotool("click", 4 if notches > 0 else 5)
    y_base += notches * DEPTH_STEP_M
    z_above = arrow[2] + 0.05 - middle[2]
    xdotool("mousemove", "--window", window, *pointer_for(x_base, z_above))
    wait_until("alice's middle finger above the arrow", 30, lambda: hand_near(trace, x_base, y_base, z_above, tol=0.006),
               lambda: f"newest trace row: {newest(trace)}")
    xdotool("mousemove", "--window", window, *pointer_for(x_base, 0.0 - middle[2]))
    h.wait_for_line("world_server", "control arrow_next by alice: scene 'dinosaur'", 60)
    xdotool("mousemove", "--window", window, *pointer_for(x_base, 0.25))
    for user in ("alice", "bob"):
        h.wait_for_line(user, "scene 'dinosaur' revision", 120)
    print("the pointer pressed the arrow: the dinosaur world is open")

    # The tail (at (0.32, 0.08, 0.045), its base attached to the body), beside bob: alice's hand
    # closed (C ten times: the five fingertips on a 10 mm ring, a five-finger patch) over
    # (0.225, 0.08), where the tour's alice presses, then down until the fingertips' centres are
    # where the tour's fingertip presses the tail 3 mm (z 0.0649: the surface 8 mm lower, less 3).
    xdotool("key", *["c"] * 10)
    tail = scene_object("dinosaur", "triceratops_tail")
    patch = (0.225, 0.08)
    closed = fingertip_h(0, 1.0)
    x_base = patch[0] - GRASP_CENTRE_H[0]
    notches = round((patch[1] - GRASP_CENTRE_H[1] - y_base) / DEPTH_STEP_M)
    for _ in range(abs(notches)):
        xdotool("click", 4 if notches > 0 else 5)
    y_base += notches * DEPTH_STEP_M
    xdotool("mousemove", "--window", window, *pointer_for(x_base, 0.25))
    wait_until("alice's closed hand over the tail", 30, lambda: hand_near(trace, x_base, y_base, 0.25, tol=0.006),
               lambda: f"newest trace row: {newest(trace)}")
    z_press = 0.0649 - closed[2]
    xdotool("mousemove", "--window", window, *pointer_for(x_base, z_press))
    held_file = os.path.join(dump, "triceratops_tail.json")
    pressed = PressWatch(held_file, tail["position_m"], {"alice": patch, "bob": (0.27, 0.08)})
    held = wait_until("the tail pressed by alice (at the desk) and bob, held still for 2.5 s", 90,
                      lambda: pressed.still_for(2.5), pressed.explain)
    grab_window(window, os.path.join(w, "desk_pressing_tail.png"))
    check(h.stop("spectator", 20) == 0, "the spectator did not end cleanly")
    check_shared_deformation(h, held, received_file, patch, (0.27, 0.08), tail["position_m"])
    xdotool("mousemove", "--window", window, *pointer_for(x_base, 0.25))
    xdotool("key", "o")

    # The window loses the keyboard focus (unmapped): the hand is released, and comes back.
    xdotool("windowunmap", "--sync", window)
    h.wait_for_line("alice", "desk: the view lost focus: the hand is released", 30)
    wait_until("a released hand in alice's trace", 10, lambda: newest(trace)["fault"] == 1.0)
    xdotool("windowmap", "--sync", window)
    xdotool("windowfocus", "--sync", window)
    wait_until("alice's hand live again", 30, lambda: h.log("alice").count("desk: the hand is live") >= 2,
               lambda: h.log("alice"))
    wait_until("a live hand in alice's trace", 10, lambda: newest(trace)["fault"] == 0.0)

    # The view dies: its input stops, and the haptic node releases the hand after 1 s.
    h.procs["view"][0].send_signal(signal.SIGKILL)
    h.wait("view", 10)
    h.wait_for_line("alice", "desk: no input for 1.0 s: the hand is released", 30)
    wait_until("a released hand in alice's trace", 10, lambda: newest(trace)["fault"] == 1.0)
    rc = h.stop("alice", 30)
    check(rc == 0, f"alice's haptic node ended with {rc}")
    check(h.stop("bob", 30) == 0, "bob's haptic node failed")
    # (The rate bound is not asserted here: a world change under a pressing finger steps the
    # force whatever the device; DeskDevice.StepsOfTheTargetNeverTripTheForceRateBound holds
    # the desk's part.)
    loop = [line for line in h.log("alice").splitlines() if "loop statistics" in line]
    print("released on focus loss and on a quiet desk; " + (loop[-1].split("] ")[-1][:200] if loop else ""))


if __name__ == "__main__":
    sys.exit(run_cases({"desk": case_desk}))
