#!/usr/bin/python3
"""Bytes and samples per second per topic and per node of a real session, from a recording.

Runs the real executables on loopback DDS with `session_record` listening, then reads the
recording (world_server/src/recording.cpp: every sample's CDR with its receive time) and
attributes each sample to the node that wrote it (from the sample: the user of a device state,
contact set or control event, the owner of an object state, the member of a member info, the
node of loop statistics; scene state, message board and deformations are the world server's).

Cases:
  tour   the demo's encyclopedia tour (deploy/handshare-demo: world server, alice and bob on
         haptic_node/scripts/tour_*.hand, a headless spectator at 2 fps; no audio guide, which
         only announces itself), the whole recording
  press  the dinosaur world, alice and bob press the triceratops tail and hold still
         (bench/net/press_*.hand), a headless spectator; the window from 2 s after both hands'
         first contact set to the first hand's last one

Payload bytes are the CDR (4-byte encapsulation included); each sample adds its RTPS submessage,
RTPS, UDP and IP headers on the wire. The recorder is one more reader of every topic, so writers
that skip a topic nobody reads (device state, loop statistics) write it here.

With --deadband W the haptic nodes run with that contact-set deadband (0: every bridge tick, as
before the deadband; default: the node's own default); their account of what it let through goes
into the '#' lines. With --work DIR the recordings stay there (DIR/tour.db, DIR/press.db): a
recording at --deadband 0 is what deadband_bench reads.

usage: net_bandwidth.py --bin-dir BUILD [--domain D] [--work DIR] [--cases tour,press] [--deadband W]
                        [--csv FILE]
Prints case,topic,node,samples_per_s,bytes_per_s,payload_B rows (and '#' lines with the load).
"""
import argparse
import os
import signal
import sqlite3
import struct
import subprocess
import sys
import tempfile
import time
from collections import defaultdict

HERE = os.path.dirname(os.path.abspath(__file__))
ROOT = os.path.join(HERE, "..", "..")
TOUR_SCRIPTS = os.path.join(ROOT, "haptic_node", "scripts")


class Failure(Exception):
    pass


def loadavg():
    with open("/proc/loadavg") as f:
        return " ".join(f.read().split()[:3])


class Procs:
    """Processes with their output in files; all killed on leaving, shm leftovers cleaned."""

    def __init__(self, bin_dir, work, case):
        self.bin_dir, self.work, self.case, self.procs = bin_dir, work, case, {}

    def __enter__(self):
        return self

    def __exit__(self, *exc):
        for proc, log in self.procs.values():
            if proc.poll() is None:
                proc.kill()
                proc.wait()
            log.close()
        subprocess.run(["fastdds", "shm", "clean"], stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
        return False

    def start(self, label, exe, *args):
        path = os.path.join(self.bin_dir, exe)
        if not os.access(path, os.X_OK):
            raise Failure(f"executable not built: {path}")
        log = open(self.log_path(label), "w")
        self.procs[label] = (subprocess.Popen([path, *map(str, args)], stdout=log, stderr=subprocess.STDOUT), log)

    def log_path(self, label):
        return os.path.join(self.work, f"{self.case}_{label}.log")

    def log(self, label):
        self.procs[label][1].flush()
        with open(self.log_path(label)) as f:
            return f.read()

    def wait_for_line(self, label, text, timeout):
        end = time.monotonic() + timeout
        while text not in self.log(label):
            if self.procs[label][0].poll() is not None:
                raise Failure(f"{label} ended without printing '{text}':\n{self.log(label)}")
            if time.monotonic() > end:
                raise Failure(f"'{text}' not in {label}'s output within {timeout} s:\n{self.log(label)}")
            time.sleep(0.1)

    def wait(self, label, timeout):
        try:
            return self.procs[label][0].wait(timeout=timeout)
        except subprocess.TimeoutExpired:
            raise Failure(f"{label} did not end within {timeout} s")

    def stop(self, label, timeout=20):
        proc = self.procs[label][0]
        if proc.poll() is None:
            proc.send_signal(signal.SIGTERM)
        return self.wait(label, timeout)


def prepare(bin_dir, cache, scenes):
    r = subprocess.run([os.path.join(bin_dir, "core", "world", "world_prepare"), "--cache", cache, "--scenes", scenes],
                       capture_output=True, text=True, timeout=900)
    if r.returncode != 0:
        raise Failure(f"world_prepare failed: {r.stdout}{r.stderr}")


def run_tour(p, domain, session, work, hand_options):
    """hand_options: extra haptic_node options (--deadband)."""
    rec = os.path.join(work, "tour.db")
    p.start("record", "world_server/session_record", "--domain", domain, "--session", session, "--out", rec)
    p.wait_for_line("record", "recording session", 15)
    p.start("world_server", "world_server/world_server", "--domain", domain, "--session", session,
            "--scene", "start_menu", "--duration", 80)
    p.wait_for_line("world_server", "message board #1", 30)
    p.start("spectator", "graphics_node/graphics_node", "--domain", domain, "--session", session, "--headless",
            "--frames", 100000, "--fps", 2, "--duration", 80, "--out", os.path.join(work, "tour_frames"))
    for user in ("alice", "bob"):
        p.start(user, "haptic_node/haptic_node", "--domain", domain, "--session", session, "--user", user,
                "--device", "sim", "--script", os.path.join(TOUR_SCRIPTS, f"tour_{user}.hand"), "--duration", 50,
                *hand_options)
    for user in ("alice", "bob"):
        if p.wait(user, 120) != 0:
            raise Failure(f"{user}'s haptic node failed:\n{p.log(user)}")
    if "scene 'microscopic'" not in p.log("world_server"):
        raise Failure(f"the tour did not reach the microscopic world:\n{p.log('world_server')}")
    for label in ("record", "spectator", "world_server"):
        p.stop(label)
    return rec, peer_age_lines(p)


def peer_age_lines(p):
    """The haptic nodes' own account of the contact sets: their own report's age when the bridge
    wrote it, and the peers' sets' age when the bridge took them and when the loop used them."""
    return [line.strip() for user in ("alice", "bob") for line in p.log(user).splitlines()
            if "contact sets:" in line or "contact deadband:" in line]


def run_press(p, domain, session, work, hand_options):
    rec = os.path.join(work, "press.db")
    p.start("world_server", "world_server/world_server", "--domain", domain, "--session", session,
            "--scene", "dinosaur", "--duration", 80)
    p.wait_for_line("world_server", "models of 'dinosaur' ready", 60)
    p.start("record", "world_server/session_record", "--domain", domain, "--session", session, "--out", rec)
    p.wait_for_line("record", "recording session", 15)
    p.start("spectator", "graphics_node/graphics_node", "--domain", domain, "--session", session, "--headless",
            "--frames", 100000, "--fps", 2, "--duration", 80, "--out", os.path.join(work, "press_frames"))
    for user in ("alice", "bob"):
        p.start(user, "haptic_node/haptic_node", "--domain", domain, "--session", session, "--user", user,
                "--device", "sim", "--script", os.path.join(HERE, f"press_{user}.hand"), "--duration", 25,
                *hand_options)
    for user in ("alice", "bob"):
        if p.wait(user, 90) != 0:
            raise Failure(f"{user}'s haptic node failed:\n{p.log(user)}")
    for label in ("record", "spectator", "world_server"):
        p.stop(label)
    return rec, peer_age_lines(p)


def cdr_strings(cdr, count):
    """The first `count` top-level strings of a CDR sample that starts with them (little or big
    endian by its encapsulation), skipping non-string fields is not needed for our types."""
    little = cdr[1] in (1, 3)
    body, off, out = cdr[4:], 0, []
    for _ in range(count):
        off = (off + 3) & ~3
        (n,) = struct.unpack_from("<I" if little else ">I", body, off)
        off += 4
        out.append(body[off:off + n - 1].decode("utf-8", "replace") if n > 0 else "")
        off += n
    return out


def writer_of(topic, cdr):
    """The node that wrote a sample of `topic` (see the module doc)."""
    name = topic.split("/")[-1]
    if name in ("scene_state", "message_board", "deformation"):
        return "world_server"
    if name in ("device_state", "contact_set"):
        return cdr_strings(cdr, 1)[0]
    if name == "object_state":  # object_id, session, owner ("" = the world server simulates it)
        return cdr_strings(cdr, 3)[2] or "world_server"
    if name == "control_event":  # session, user
        return cdr_strings(cdr, 2)[1]
    if name == "member_info":  # "<session>/<user or node>"
        return cdr_strings(cdr, 1)[0].split("/", 1)[-1]
    if name == "loop_statistics":  # "haptic_node/alice"
        return cdr_strings(cdr, 1)[0].split("/")[-1]
    return "?"


def analyse(case, db):
    con = sqlite3.connect(db)
    rows = con.execute("SELECT s.steady_ns, i.topic, s.cdr FROM samples s JOIN instances i ON s.instance = i.id "
                       "WHERE s.state = 0 ORDER BY s.id").fetchall()
    con.close()
    if not rows:
        raise Failure(f"{db}: no samples recorded")
    if case == "press":
        first, last = {}, {}
        for t, topic, cdr in rows:
            if topic.endswith("contact_set"):
                u = writer_of(topic, cdr)
                first.setdefault(u, t)
                last[u] = t
        if sorted(first) != ["alice", "bob"]:
            raise Failure(f"{db}: contact sets from {sorted(first)}, not alice and bob")
        t0, t1 = max(first.values()) + 2e9, min(last.values())
    else:
        t0, t1 = rows[0][0], rows[-1][0]
    if t1 - t0 < 5e9:
        raise Failure(f"{db}: window of {(t1 - t0) / 1e9:.1f} s is too short")
    seconds = (t1 - t0) / 1e9
    count, size = defaultdict(int), defaultdict(int)
    for t, topic, cdr in rows:
        if t0 <= t <= t1:
            key = (topic.split("/")[-1], writer_of(topic, cdr))
            count[key] += 1
            size[key] += len(cdr)
    out = []
    for key in sorted(count, key=lambda k: (-size[k], k)):
        out.append((case, key[0], key[1], count[key] / seconds, size[key] / seconds, size[key] / count[key]))
    return seconds, out


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--bin-dir", required=True, help="the build tree (build/)")
    ap.add_argument("--domain", type=int, default=168)
    ap.add_argument("--work", help="where logs and recordings go (default: a temporary folder, removed)")
    ap.add_argument("--cases", default="tour,press")
    ap.add_argument("--deadband", type=float, help="the haptic nodes' contact-set deadband (Weber fraction)")
    ap.add_argument("--csv", help="also write the rows to this file")
    args = ap.parse_args(argv)
    hand_options = [] if args.deadband is None else ["--deadband", args.deadband]
    cases = args.cases.split(",")
    for c in cases:
        if c not in ("tour", "press"):
            ap.error(f"unknown case '{c}' (tour, press)")
    if not 0 <= args.domain <= 232:
        ap.error("--domain must be in 0..232")
    tmp = None
    work = args.work
    if work is None:
        tmp = tempfile.TemporaryDirectory(prefix="net_bandwidth.")
        work = tmp.name
    os.makedirs(work, exist_ok=True)
    cache = os.environ.setdefault("HANDSHARE_CACHE", os.path.join(os.path.expanduser("~"), ".cache", "handshare"))
    lines = ["case,topic,node,samples_per_s,bytes_per_s,payload_B"]
    try:
        prepare(args.bin_dir, cache, "dinosaur,microscopic")
        for case in cases:
            session = f"net-bandwidth-{case}-{os.getpid()}"
            load_before = loadavg()
            with Procs(args.bin_dir, work, case) as p:
                rec, notes = (run_tour if case == "tour" else run_press)(p, args.domain, session, work, hand_options)
            seconds, rows = analyse(case, rec)
            deadband = "node default" if args.deadband is None else f"{args.deadband:g}"
            lines.append(f"# {case}: {seconds:.1f} s window; deadband {deadband}; load before {load_before}, "
                         f"after {loadavg()}")
            lines.extend(f"# {case}: {n}" for n in notes)
            total = defaultdict(lambda: [0.0, 0.0])
            for r in rows:
                lines.append(f"{r[0]},{r[1]},{r[2]},{r[3]:.1f},{r[4]:.0f},{r[5]:.0f}")
                total[r[2]][0] += r[3]
                total[r[2]][1] += r[4]
            for node, (n, b) in sorted(total.items()):
                lines.append(f"# {case} total {node}: {n:.1f} samples/s, {b / 1000:.1f} kB/s")
    except Failure as e:
        sys.stderr.write(f"net_bandwidth: {e}\n")
        return 1
    finally:
        if tmp is not None:
            tmp.cleanup()
    print("\n".join(lines))
    if args.csv:
        with open(args.csv, "w") as f:
            f.write("\n".join(lines) + "\n")
    return 0


if __name__ == "__main__":
    sys.exit(main())
