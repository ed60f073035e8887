#!/usr/bin/env python3
"""A lab's device through a plug-in (docs/devices.md), in real processes over real DDS.

stylus: the example plug-in (a scripted one-point stylus, C) drives a haptic node that joins a
  session at the start menu. The world server hears the member with its device's capabilities
  (one point, the index finger); the stylus presses the solar-system button and the server opens
  the solar system; the node publishes device states without the four fingers it lacks; the
  button's force reached the plug-in (it prints the largest force it took at close).
bad_plugins: a plug-in that cannot be loaded, has another ABI version, exports no entry, or fails
  to open stops the node before it joins, exit status 1 and a message naming the plug-in and why;
  one that gives NaN positions for 300 reads runs on with its faults counted by kind, with zero
  force meanwhile.

usage: plugin_device_test.py CASE --bin-dir DIR --domain D --work DIR
"""
import os
import re
import subprocess
import sys

HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, HERE)
from session_test import check, run_cases, wait_until  # noqa: E402


def plugin(h, name):
    path = os.path.join(h.bin_dir, "core", "device", "plugin", f"lib{name}.so")
    check(os.path.exists(path), f"plug-in not built: {path}")
    return path


def case_stylus(h, domain):
    session = f"it-plugin-{os.getpid()}"
    common = ["--domain", domain, "--session", session]
    h.start("world_server", "world_server", *common, "--scene", "start_menu")
    # The device frame's origin over the solar-system button (start_menu.json: (-0.15, -0.08,
    # 0.012)); the stylus presses 8 mm below it, again every 3 s.
    h.start("carol", "haptic_node", *common, "--user", "carol",
            "--device", f"plugin:{plugin(h, 'handshare_scripted_stylus')}:press=0,0,0 period=3 depth=0.008",
            "--device-origin", "-0.15,-0.08,0.02", "--trace", os.path.join(h.work, "carol.csv"))
    h.wait_for_line("carol", "device plugin:scripted_stylus (scripted stylus (example)): 1 contact point (index)", 30)
    h.wait_for_line("world_server", "member joined: user=carol kind=haptic device=plugin:scripted_stylus", 60)
    server_log = h.log("world_server")
    heard = re.search(r"member joined: user=carol .*\(device: (.*)\)", server_log)
    check(heard is not None and heard.group(1).startswith("1 point (index), 3.3 N, workspace 0.08 m, 1000 Hz"),
          f"the server heard carol's device as {heard.group(1) if heard else None!r}")
    h.wait_for_line("world_server", "control button_solar_system by carol: scene 'solar_system'", 60)
    check(h.stop("carol", 30) == 0, "carol's haptic node failed")
    log = h.log("carol")
    m = re.search(r"scripted_stylus: (\d+) forces taken, largest ([\d.]+) N", log)
    check(m is not None, "the plug-in did not report at close (was it closed?)")
    forces, largest = int(m.group(1)), float(m.group(2))
    check(forces > 500 and largest > 0.1, f"the plug-in took {forces} forces, the largest {largest} N: "
          "the button's force did not reach the device")
    faults = re.search(r"device faults: (\d+)", log)
    check(faults is not None, "carol's node did not report its device faults")
    # The published device states carry the hand the user has: only the index fingertip moves.
    with open(os.path.join(h.work, "carol.csv")) as f:
        header = f.readline().strip().split(",")
        rows = [line.strip().split(",") for line in f if line.strip()]
    check(len(rows) > 30, f"only {len(rows)} device states traced")
    col = {name: i for i, name in enumerate(header)}
    z_index = [float(r[col["z1"]]) for r in rows if r[col["fault"]] == "0"]
    check(len(z_index) > 30, f"only {len(z_index)} device states without a fault")
    check(min(z_index) < 0.016 and max(z_index) > 0.06,
          f"the index fingertip went from {max(z_index):.3f} down to {min(z_index):.3f} m, not onto the button")
    check(h.stop("world_server", 30) == 0, "world_server failed")
    print(f"stylus: the server heard '{heard.group(1)}'; the stylus pressed the button; the plug-in took {forces} forces, "
          f"the largest {largest:.2f} N; device faults {faults.group(1)}")


def run_node(h, label, domain, device, timeout=60):
    """Runs a haptic node that should stop before joining: (exit status, output)."""
    p = subprocess.run([h.exe("haptic_node"), "--domain", str(domain), "--session", f"it-bad-{os.getpid()}",
                        "--user", label, "--device", device, "--duration", "5"],
                       capture_output=True, text=True, timeout=timeout)
    return p.returncode, p.stdout + p.stderr


def case_bad_plugins(h, domain):
    bad = plugin(h, "misbehaving_plugin")
    refusals = {
        "missing": (os.path.join(h.work, "libnothing.so"), "cannot load"),
        "v99": (plugin(h, "misbehaving_plugin_v99"), "built for device ABI version 99, this handshare reads version 1"),
        "no_entry": (plugin(h, "misbehaving_plugin_no_entry"), "exports no function handshare_device_plugin"),
        "fail_open": (f"{bad}:fail-open", "failed: no device on /dev/test0 (asked to fail)"),
        "bad_caps": (f"{bad}:bad-caps", "impossible capabilities: caps.points is 0"),
    }
    for label, (spec, why) in refusals.items():
        status, out = run_node(h, label, domain, f"plugin:{spec}")
        check(status == 1, f"{label}: the node exited {status}, expected 1:\n{out}")
        path = spec.split(".so")[0] + ".so"
        check(f"device plug-in {path}: " in out and why in out, f"{label}: the message does not say {why!r}:\n{out}")
        check("joined session" not in out, f"{label}: the node joined a session with a device it refused")
    # NaN for 300 reads (from the 500th on): counted by kind, the loop's faults too; the node
    # runs on and exits cleanly.
    session = f"it-nan-{os.getpid()}"
    h.start("nan", "haptic_node", "--domain", domain, "--session", session, "--user", "nan",
            "--device", f"plugin:{bad}:nan after=500 count=300 points=2", "--duration", "3")
    status = h.wait("nan", 60)
    check(status == 0, f"the node with a NaN device exited {status}")
    log = h.log("nan")
    check("device faults: 300 (calls failed 0, not finite 300, jumps 0" in log,
          f"the NaN reads were not counted as 300 non-finite faults:\n{log}")
    loop = re.search(r"faults (\d+), rate-limited", log)
    check(loop is not None and int(loop.group(1)) >= 300, f"the loop counted {loop.group(1) if loop else None} faults")
    print(f"bad plug-ins: {len(refusals)} refused with their reasons; NaN reads: 300 faults counted, node ran on")


if __name__ == "__main__":
    sys.exit(run_cases({"stylus": case_stylus, "bad_plugins": case_bad_plugins}))
