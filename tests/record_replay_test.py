#!/usr/bin/env python3
"""Record a session and play it back to a spectator on another domain (session_record,
session_play): a short session (world_server in the dinosaur world, one scripted haptic node
that presses the tail, a deformation, then the arrow to the microscopic world, a world change)
is recorded while a live spectator renders it; the recording is played to a second spectator on
another domain; frames that show the same thing by the senders' own stamps (the scene state's
revision and each hand's device-state stamp_ns, frame_times.csv) are compared pixel by pixel.

Also: session_report reads the recording; the recording's bytes per second are printed.

usage: record_replay_test.py --bin-dir DIR --domain D --work DIR   (uses domains D and D+1)
"""
import argparse
import csv
import os
import shutil
import signal
import subprocess
import sys

from PIL import Image, ImageChops, ImageFilter

from session_test import DATA, Failure, Harness, check, fem_cache

# Pixel tolerance: frames of the same device states differ only where the other streams
# (deformation, object poses, 60 Hz) arrived a tick earlier or later in one of the runs, and
# by a pixel at the outlines of what moves with the frame's own time (the Daphnia's periodic
# motion, a hand drawn where its device state puts it at the frame's instant): two loaded runs
# had 1.19 % of pixels differ there, outlines only. A pixel differs when no pixel within one
# of it in the other frame is within 32 of it (that run: 0.06 %).
MAX_MEAN_ABS = 2.0          # mean |difference| over all pixels and channels, of 255
MAX_DIFFERING_SHARE = 0.01  # share of pixels off by more than 32 from the other's 3x3 neighbourhood
MAX_MB_PER_HOUR_PER_USER = 400  # the recording's size bound stated in docs/network.md
LIVE_FPS, REPLAY_FPS = 20, 27   # incommensurate: see where the replay spectator starts


class RecordHarness(Harness):
    """The recorder and the player live in the world server's folder of the build tree."""

    def exe(self, name):
        if name in ("session_record", "session_play"):
            path = os.path.join(self.bin_dir, "world_server", name)
            check(os.access(path, os.X_OK), f"executable not built: {path}")
            return path
        return super().exe(name)


def frame_times(folder):
    """{(scene, revision, hands): (frame file, moving objects' pose stamps)} of a spectator's
    frames that show hands."""
    rows = {}
    with open(os.path.join(folder, "frame_times.csv")) as f:
        for row in csv.DictReader(f):  # by column name: the file gains columns (deformations)
            if row["hands"]:
                rows[(row["scene"], int(row["revision"]), row["hands"])] = (os.path.join(folder, row["file"]),
                                                                           row["objects"])
    return rows


def beyond_neighbourhood(a, b):
    """Per pixel of a: how far (largest channel) it lies outside b's 3x3 neighbourhood range."""
    low, high = b.filter(ImageFilter.MinFilter(3)), b.filter(ImageFilter.MaxFilter(3))
    off = ImageChops.lighter(ImageChops.subtract(low, a), ImageChops.subtract(a, high))
    r, g, bl = off.split()
    return ImageChops.lighter(ImageChops.lighter(r, g), bl)


def compare(a, b):
    ia, ib = Image.open(a).convert("RGB"), Image.open(b).convert("RGB")
    check(ia.size == ib.size, f"{a} and {b} differ in size")
    diff = ImageChops.difference(ia, ib)
    hist = diff.histogram()  # 3 x 256 bins
    n = ia.size[0] * ia.size[1]
    mean = sum(i * c for k in range(3) for i, c in enumerate(hist[256 * k:256 * (k + 1)])) / (3 * n)
    # Either frame's pixel off from the other's neighbourhood: a missing or shifted object
    # shows in one direction at least.
    off = ImageChops.lighter(beyond_neighbourhood(ia, ib), beyond_neighbourhood(ib, ia))
    big = sum(off.histogram()[33:])
    return mean, big / n


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--bin-dir", required=True)
    ap.add_argument("--domain", type=int, required=True)
    ap.add_argument("--work", required=True)
    args = ap.parse_args()
    shutil.rmtree(args.work, ignore_errors=True)
    os.makedirs(args.work)
    h = RecordHarness(args.bin_dir, args.work)
    live_domain, replay_domain = args.domain, args.domain + 1
    session = f"it-record-{os.getpid()}"
    cache = fem_cache(args.work)
    os.environ["HANDSHARE_CACHE"] = cache
    recording = os.path.join(args.work, "session.rec")
    exe = lambda folder, name: os.path.join(args.bin_dir, folder, name)
    try:
        prep = subprocess.run([exe("core/world", "world_prepare"), "--cache", cache, "--scenes", "dinosaur,microscopic"],
                              capture_output=True, text=True, timeout=600)
        check(prep.returncode == 0, f"world_prepare failed: {prep.stdout}{prep.stderr}")
        h.start("record", "session_record", "--domain", live_domain, "--session", session, "--out", recording)
        h.wait_for_line("record", "recording session", 15)
        h.start("live", "graphics_node", "--domain", live_domain, "--session", session, "--headless",
                "--frames", 100000, "--fps", LIVE_FPS, "--out", os.path.join(args.work, "live"))
        h.start("world_server", "world_server", "--domain", live_domain, "--session", session, "--scene", "dinosaur")
        h.wait_for_line("world_server", "message board #1", 30)
        h.start("alice", "haptic_node", "--domain", live_domain, "--session", session, "--user", "alice",
                "--script", os.path.join(DATA, "record_alice.hand"), "--duration", 14)
        check(h.wait("alice", 60) == 0, "alice's haptic node failed")
        ws = h.log("world_server")
        check("scene 'microscopic'" in ws, f"the world did not change to the microscopic world:\n{ws}")
        for label in ("world_server", "live", "record"):
            h.procs[label][0].send_signal(signal.SIGTERM)
            check(h.wait(label, 30) == 0, f"{label} did not end cleanly")
        rec_log = h.log("record")
        check("recorded" in rec_log, f"the recorder said nothing of what it recorded:\n{rec_log}")

        checked = subprocess.run([exe("world_server", "session_play"), recording, "--check"],
                                 capture_output=True, text=True, timeout=60)
        check(checked.returncode == 0, f"session_play --check failed: {checked.stderr}")
        print(checked.stdout.strip())

        # The replay spectator draws at another, incommensurate rate (27 fps against 20 fps live).
        # At the same rate both would sample the 100 Hz device states in a phase fixed for the
        # whole run: at an offset near 25 ms no live frame has a replayed one within 10 ms (the
        # runs that paired 2-4 frames instead of ~100). At 27 fps the offset sweeps through the
        # 50 ms period, so about half of the live frames have a replayed one within 10 ms.
        h.start("replay", "graphics_node", "--domain", replay_domain, "--session", session + "-replay", "--headless",
                "--frames", 100000, "--fps", REPLAY_FPS, "--out", os.path.join(args.work, "replay"))
        h.start("play", "session_play", "--domain", replay_domain, "--session", session + "-replay",
                "--wait-for-readers", 1, "--hold", 1, recording)
        check(h.wait("play", 120) == 0, f"session_play failed:\n{h.log('play')}")
        h.procs["replay"][0].send_signal(signal.SIGTERM)
        check(h.wait("replay", 30) == 0, "the replay spectator did not end cleanly")

        live, replay = frame_times(os.path.join(args.work, "live")), frame_times(os.path.join(args.work, "replay"))
        # Pairs: the same world and revision, hands' device states at most one device-state
        # period (10 ms at 100 Hz) apart, and the same poses of moving objects (the Daphnia
        # bobs: its object states come about every 40 ms, and a pose 40 ms older is a pixel or
        # two off all round its outline, which failed 1 run in about 20 under load). The two
        # spectators draw in their own phase, so showing the very same states is luck (2 of ~270
        # frames on a loaded machine); a hand moves at most a few mm in 10 ms, which the pixel
        # tolerance covers.
        def stamps(text):
            return {u: int(t) for u, t in (h.split("@") for h in text.split(";") if h)}
        replay_by_world = {}
        for (scene, rev, hands), (path, objects) in replay.items():
            replay_by_world.setdefault((scene, rev), []).append((stamps(hands), stamps(objects), path))
        pairs = []
        for (scene, rev, hands), (path, objects) in live.items():
            want = stamps(hands)
            want_objects = stamps(objects)
            best = None
            for got, got_objects, rpath in replay_by_world.get((scene, rev), []):
                if got.keys() != want.keys() or got_objects != want_objects:
                    continue
                gap = max(abs(got[u] - want[u]) for u in want)
                if gap <= 10_000_000 and (best is None or gap < best[0]):
                    best = (gap, rpath)
            if best:
                pairs.append(((scene, rev, hands), path, best[1], best[0]))
        scenes = {k[0] for k, _, _, _ in pairs}
        exact = sum(1 for *_, gap in pairs if gap == 0)
        print(f"{len(live)} live and {len(replay)} replayed frames with hands; {len(pairs)} pairs within 10 ms "
              f"({exact} with the very same device states; scenes {sorted(scenes)})")
        check(len(pairs) >= 10, f"only {len(pairs)} frames of the live session and the replay pair up")
        check({"dinosaur", "microscopic"} <= scenes, f"paired frames cover only {sorted(scenes)}")
        worst_mean, worst_share = 0.0, 0.0
        for key, live_path, replay_path, gap in pairs:
            mean, share = compare(live_path, replay_path)
            worst_mean, worst_share = max(worst_mean, mean), max(worst_share, share)
            check(mean <= MAX_MEAN_ABS and share <= MAX_DIFFERING_SHARE,
                  f"{live_path} vs {replay_path} ({key}, hands {gap / 1e6:.1f} ms apart): mean |diff| {mean:.3f}, "
                  f"{100 * share:.3f}% of pixels differ by more than 32 from the other's 3x3 neighbourhood "
                  f"(tolerance {MAX_MEAN_ABS}, {100 * MAX_DIFFERING_SHARE}%)")
        print(f"frames match: worst mean |diff| {worst_mean:.3f} of 255 (tolerance {MAX_MEAN_ABS}), worst share of "
              f"pixels off by more than 32 from the other's neighbourhood: {100 * worst_share:.3f}% (tolerance "
              f"{100 * MAX_DIFFERING_SHARE}%)")

        report = subprocess.run([exe("world_server", "session_report"), recording], capture_output=True, text=True,
                                timeout=30)
        check(report.returncode == 0, f"session_report on the recording failed: {report.stderr}")
        for needle in ("dinosaur", "microscopic", "arrow_next", "alice"):
            check(needle in report.stdout, f"session report of the recording lacks '{needle}':\n{report.stdout}")

        # The recording's size per second of session, for docs/network.md.
        import sqlite3
        db = sqlite3.connect(f"file:{recording}?mode=ro", uri=True)
        first, last, n = db.execute("SELECT min(steady_ns), max(steady_ns), count(*) FROM samples").fetchone()
        per_topic = db.execute("SELECT i.topic, count(*), sum(length(s.cdr)) FROM samples s JOIN instances i "
                               "ON i.id = s.instance GROUP BY i.topic ORDER BY 3 DESC").fetchall()
        db.close()
        seconds = (last - first) * 1e-9
        size = os.path.getsize(recording)
        print(f"recording: {size} bytes, {n} samples over {seconds:.1f} s: {size / seconds:.0f} bytes/s, "
              f"{size / seconds * 3600 / 1e6:.0f} MB per hour")
        for topic, count, payload in per_topic:
            print(f"  {topic}: {count} samples, {payload} payload bytes ({count / seconds:.1f}/s)")
        # docs/network.md: an hour with one haptic user stays below 400 MB (measured 333 MB).
        check(size / seconds * 3600 < MAX_MB_PER_HOUR_PER_USER * 1e6,
              f"{size / seconds * 3600 / 1e6:.0f} MB per hour exceeds {MAX_MB_PER_HOUR_PER_USER} MB for one user")
        print("PASS")
        return 0
    except Failure as e:
        h.dump_logs()
        print(f"FAIL: {e}", file=sys.stderr)
        return 1
    finally:
        h.cleanup()


if __name__ == "__main__":
    sys.exit(main())
