"""The processes of a graphics bench's session (bench/graphics/motion_to_photon.py,
spectator_to_photon.py): a virtual display of its own and the programs of a build, each
program's output in WORK/NAME.log, all stopped (SIGINT, then killed after 20 s) in reverse
order of their start."""
import os
import signal
import subprocess
import sys
import time

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "..", "tests"))
from desk_test import launch_xvfb  # noqa: E402


class BenchSession:
    def __init__(self, bin_dir, work):
        self.bin_dir, self.work, self.procs = bin_dir, work, []

    def log(self, name):
        return open(os.path.join(self.work, name + ".log"), "w")

    def start_display(self, width, height):
        """An Xvfb a little larger than a WIDTH x HEIGHT window; DISPLAY is set for what starts next."""
        xvfb, display = launch_xvfb(f"{width + 64}x{height + 64}x24", self.log("xvfb"))
        self.procs.append(xvfb)
        os.environ["DISPLAY"] = display
        return display

    def start(self, name, exe, *args):
        """exe: DIR/PROGRAM under the build folder."""
        p = subprocess.Popen([os.path.join(self.bin_dir, exe.split("/")[0], exe.split("/")[-1]), *map(str, args)],
                             stdout=self.log(name), stderr=subprocess.STDOUT, env=os.environ.copy())
        self.procs.append(p)
        return p

    def wait_log(self, name, text, timeout):
        deadline = time.monotonic() + timeout
        while time.monotonic() < deadline:
            with open(os.path.join(self.work, name + ".log")) as f:
                if text in f.read():
                    return
            time.sleep(0.05)
        sys.exit(f"{name} did not say '{text}' within {timeout} s (see {self.work}/{name}.log)")

    def stop(self):
        for p in reversed(self.procs):
            if p.poll() is None:
                p.send_signal(signal.SIGINT)
        for p in reversed(self.procs):
            try:
                p.wait(timeout=20)
            except subprocess.TimeoutExpired:
                p.kill()
                p.wait()
