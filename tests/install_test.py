#!/usr/bin/env python3
"""An installed handshare tree runs a session without the source tree.

Installs the build into a temporary prefix (`cmake --install BUILD --prefix TMP`), checks the
layout, then, in a private mount namespace (`unshare -m`) where an empty tmpfs hides the source
tree (and the build tree), runs a short session from the installed tree: the installed
world_server and one installed haptic_node (sim device, a tour script from share/handshare),
then a headless graphics_node for two frames. It waits on log lines with timeouts and asserts
that the haptic node built the scene from the installed assets, the QoS profiles were found,
and every node ended cleanly.

Needs root (or CAP_SYS_ADMIN) for unshare -m and mount: without them it prints why and exits
77, which ctest reports as skipped.

usage: install_test.py --cmake CMAKE --build-dir BUILD --source-dir SRC --domain D --work DIR
"""
import argparse
import os
import shutil
import signal
import subprocess
import sys
import tempfile
import time

SKIP = 77
INSTALLED_EXES = ["world_server", "session_report", "haptic_node", "graphics_node", "audio_guide",
                  "web_console", "world_prepare", "fem_solve", "fem_precompute", "handshare-demo"]
INSTALLED_DATA = ["assets/scenes/start_menu.json", "assets/meshes/button.obj", "assets/images/solar_system.png",
                  "assets/devices/hiro2.json",
                  "qos/handshare_qos.xml", "scripts/tour_alice.hand", "scripts/tour_bob.hand",
                  "examples/scripted_stylus.c", "www/operator.html", "www/operator.js", "www/live.js", "www/view.js"]
# The device plug-in ABI (docs/devices.md): its one header and the example plug-in.
INSTALLED_PLUGIN = ["include/handshare/device_plugin.h", "lib/handshare/devices/libhandshare_scripted_stylus.so"]


class Failure(Exception):
    pass


def check(cond, what):
    if not cond:
        raise Failure(what)


def inside(path, folder):
    path, folder = os.path.realpath(path), os.path.realpath(folder)
    return path == folder or path.startswith(folder + os.sep)


# --- the session, run inside the mount namespace ------------------------------------------

class Nodes:
    """Starts installed executables with their output in log files; always cleans up."""

    def __init__(self, prefix, logs, env):
        self.prefix, self.logs, self.env = prefix, logs, env
        self.procs = {}

    def start(self, label, exe, *args):
        log = open(os.path.join(self.logs, label + ".log"), "w")
        proc = subprocess.Popen([os.path.join(self.prefix, "bin", exe), *map(str, args)],
                                stdout=log, stderr=subprocess.STDOUT, env=self.env, cwd=self.logs)
        self.procs[label] = (proc, log)
        return proc

    def log(self, label):
        self.procs[label][1].flush()
        with open(os.path.join(self.logs, label + ".log")) as f:
            return f.read()

    def wait_for_line(self, label, text, timeout):
        end = time.monotonic() + timeout
        while time.monotonic() < end:
            if text in self.log(label):
                return
            proc = self.procs[label][0]
            if proc.poll() is not None and text not in self.log(label):
                raise Failure(f"{label} ended (exit {proc.returncode}) before printing '{text}':\n{self.log(label)}")
            time.sleep(0.05)
        raise Failure(f"'{text}' not in {label}'s output within {timeout} s:\n{self.log(label)}")

    def stop(self, label, sig, timeout):
        proc = self.procs[label][0]
        proc.send_signal(sig)
        try:
            return proc.wait(timeout=timeout)
        except subprocess.TimeoutExpired:
            raise Failure(f"{label} did not end within {timeout} s of signal {sig}")

    def wait(self, label, timeout):
        try:
            return self.procs[label][0].wait(timeout=timeout)
        except subprocess.TimeoutExpired:
            raise Failure(f"{label} did not end within {timeout} s")

    def cleanup(self):
        for proc, log in self.procs.values():
            if proc.poll() is None:
                proc.kill()
                proc.wait()
            log.close()


def hide(folder):
    """Mounts an empty, read-only tmpfs over folder (in this mount namespace only)."""
    r = subprocess.run(["mount", "-t", "tmpfs", "-o", "size=64k,mode=0555,ro", "handshare-hidden", folder],
                       capture_output=True, text=True)
    if r.returncode != 0:
        return f"mount -t tmpfs over {folder} failed: {r.stderr.strip()}"
    if os.listdir(folder):
        return f"{folder} is still visible after the mount"
    return None


def inner(args):
    tmp = args.tmp
    prefix = os.path.join(tmp, "prefix")
    logs = os.path.join(tmp, "logs")
    with open(os.path.join(tmp, "namespace-entered"), "w"):
        pass
    os.chdir(tmp)
    for folder in dict.fromkeys([args.source_dir, args.build_dir]):
        if folder != args.source_dir and inside(folder, args.source_dir):
            continue
        why = hide(folder)
        if why:
            print(f"install test: SKIPPED: {why}")
            return SKIP
    check(not os.path.exists(os.path.join(args.source_dir, "assets")), "the source tree is still visible")
    print(f"install test: {args.source_dir} and {args.build_dir} hidden by empty tmpfs mounts")

    env = {k: v for k, v in os.environ.items()
           if k not in ("HANDSHARE_QOS_FILE", "HANDSHARE_ASSETS", "HANDSHARE_CACHE")}
    env["HANDSHARE_CACHE"] = os.path.join(tmp, "cache")
    share = os.path.realpath(os.path.join(prefix, "share", "handshare"))

    # The defaults printed by --help point into the installed tree.
    r = subprocess.run([os.path.join(prefix, "bin", "haptic_node"), "--help"], capture_output=True,
                       text=True, env=env, timeout=30)
    check(r.returncode == 0, f"haptic_node --help: exit {r.returncode}\n{r.stdout}{r.stderr}")
    check(os.path.join(share, "assets", "devices", "hiro2.json") in r.stdout,
          f"haptic_node --help does not name the installed device geometry:\n{r.stdout}")

    nodes = Nodes(prefix, logs, env)
    domain, session = args.domain, f"install-{os.getpid()}"
    try:
        nodes.start("world_server", "world_server", "--domain", domain, "--session", session,
                    "--scene", "start_menu", "--duration", 120)
        nodes.start("alice", "haptic_node", "--domain", domain, "--session", session, "--user", "alice",
                    "--device", "sim", "--script", os.path.join(share, "scripts", "tour_alice.hand"),
                    "--duration", 120)
        nodes.wait_for_line("world_server", "member joined: user=alice", 30)
        # The scene came over DDS by name; the haptic node loaded it and its meshes from share/.
        nodes.wait_for_line("alice", "scene 'start_menu' revision", 60)
        nodes.wait_for_line("alice", "hand script starts at loop time", 10)
        print("install test: the installed haptic node got the scene: " +
              next(l for l in nodes.log("alice").splitlines() if "scene 'start_menu' revision" in l))

        # A spectator draws two frames with the meshes of the installed assets.
        nodes.start("graphics", "graphics_node", "--domain", domain, "--session", session, "--headless",
                    "--frames", 2, "--fps", 5, "--out", os.path.join(logs, "frames"))
        check(nodes.wait("graphics", 60) == 0, f"graphics_node failed:\n{nodes.log('graphics')}")
        frames = sorted(f for f in os.listdir(os.path.join(logs, "frames")) if f.endswith(".png"))
        check(len(frames) == 2, f"graphics_node wrote {frames}, expected 2 frames")
        check("mesh errors: 0" in nodes.log("graphics"),
              f"graphics_node could not read the installed meshes:\n{nodes.log('graphics')}")

        check(nodes.stop("alice", signal.SIGINT, 20) == 0, f"haptic_node did not exit 0:\n{nodes.log('alice')}")
        check("loop statistics: rate" in nodes.log("alice"), "haptic_node printed no loop statistics")
        nodes.wait_for_line("world_server", "member left: user=alice", 10)
        check(nodes.stop("world_server", signal.SIGTERM, 20) == 0,
              f"world_server did not exit 0:\n{nodes.log('world_server')}")
        check("shutting down" in nodes.log("world_server"), "world_server did not shut down cleanly")
    except Failure:
        for label in nodes.procs:
            sys.stderr.write(f"----- {label} -----\n{nodes.log(label)}\n")
        raise
    finally:
        nodes.cleanup()
    print("install test: the installed world server, haptic node and spectator ran without the source tree")
    return 0


# --- install, then the session in a mount namespace -----------------------------------------

def outer(args):
    source, build = os.path.realpath(args.source_dir), os.path.realpath(args.build_dir)
    tmp = os.path.realpath(tempfile.mkdtemp(prefix="handshare-install-"))
    try:
        check(not inside(tmp, source) and not inside(tmp, build),
              f"the temporary prefix {tmp} is inside the source or build tree (set TMPDIR elsewhere)")
        prefix = os.path.join(tmp, "prefix")
        os.makedirs(os.path.join(tmp, "logs"))
        r = subprocess.run([args.cmake, "--install", build, "--prefix", prefix], capture_output=True, text=True)
        check(r.returncode == 0, f"cmake --install failed (exit {r.returncode}):\n{r.stdout}{r.stderr}")
        for exe in INSTALLED_EXES:
            check(os.access(os.path.join(prefix, "bin", exe), os.X_OK), f"not installed: bin/{exe}")
        for data in INSTALLED_DATA:
            check(os.path.isfile(os.path.join(prefix, "share", "handshare", data)),
                  f"not installed: share/handshare/{data}")
        for path in INSTALLED_PLUGIN:
            check(os.path.isfile(os.path.join(prefix, path)), f"not installed: {path}")
        print(f"install test: installed into {prefix}: bin/ ({len(INSTALLED_EXES)} programs), share/handshare/, "
              "the device plug-in header and example")

        unshare = shutil.which("unshare")
        if os.geteuid() != 0:
            print("install test: SKIPPED: hiding the source tree needs root (unshare -m, mount)")
            return SKIP
        if unshare is None:
            print("install test: SKIPPED: no unshare program (util-linux)")
            return SKIP
        cmd = [unshare, "--mount", "--propagation", "private", "--", sys.executable, os.path.abspath(__file__),
               "--inner", "--tmp", tmp, "--source-dir", source, "--build-dir", build, "--domain", str(args.domain)]
        try:
            r = subprocess.run(cmd, stdout=sys.stdout, stderr=subprocess.PIPE, text=True, timeout=args.timeout)
        except subprocess.TimeoutExpired:
            raise Failure(f"the session in the mount namespace did not end within {args.timeout} s")
        sys.stderr.write(r.stderr)
        if r.returncode != 0 and not os.path.exists(os.path.join(tmp, "namespace-entered")):
            print(f"install test: SKIPPED: unshare -m is not permitted here (exit {r.returncode})")
            return SKIP
        return r.returncode
    finally:
        # Keep the logs in the build tree; remove the prefix.
        if args.work and os.path.isdir(os.path.join(tmp, "logs")):
            shutil.rmtree(args.work, ignore_errors=True)
            shutil.copytree(os.path.join(tmp, "logs"), args.work)
        shutil.rmtree(tmp, ignore_errors=True)
        subprocess.run(["fastdds", "shm", "clean"], stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)


def main():
    p = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    p.add_argument("--cmake", default="cmake")
    p.add_argument("--build-dir", required=True)
    p.add_argument("--source-dir", required=True)
    p.add_argument("--domain", type=int, default=90)
    p.add_argument("--work", help="where the nodes' logs are kept after the test")
    p.add_argument("--timeout", type=float, default=240, help="for the session in the namespace [s]")
    p.add_argument("--inner", action="store_true", help=argparse.SUPPRESS)
    p.add_argument("--tmp", help=argparse.SUPPRESS)
    args = p.parse_args()
    try:
        return inner(args) if args.inner else outer(args)
    except Failure as e:
        print(f"install test: FAILED: {e}")
        return 1


if __name__ == "__main__":
    sys.exit(main())
