#!/usr/bin/env python3
"""Eight stations and eight screens on one session (issue "Many stations on one session", point 3):
8 simulated haptic users in pairs on the commons' shared objects (tail, head, leg, ball), 8
headless spectators and the audio guide on one world server for 60 s (bench/scale/scale.py
runs the session and prints the table of every process's cost; docs/network.md, "Scale").

What must hold at that scale, each checked on what the processes report, never on timing:
- every process runs to the end and exits 0; every member joined and none was lost;
- no reliable sample is lost anywhere (member_info, scene_state, message_board,
  control_event, deformation: the middleware's sample-lost status, per reader);
- every pair shares its object: each of the 8 hands sent contact sets at the full rate because
  its partner touched the same object, and the world server took contact sets of all 8;
- device states go no faster than the screens draw: each hand sent at most the 30 Hz floor
  (session/stream_rates.hpp) over the run, with 20 % slack, while each screen took device
  states, the tail's or another part's deformation and the board;
- the audio guide spoke the board; no shared-memory segment is left behind.
The loops' rates, jitter and overruns and the server's tick are printed, not asserted (a busy
CI machine may be slower; bench/scale measures them).

usage: scale_test.py --bin-dir DIR --domain D --work DIR [--seconds 60]
"""
import argparse
import os
import re
import signal
import sys

HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, HERE)
sys.path.insert(0, os.path.join(HERE, "..", "bench", "scale"))
from session_test import Failure, check, clean_work, fem_cache, remove_orphan_ports, shm_segments  # noqa: E402
import scale  # noqa: E402

USERS = 8
SPECTATORS = 8


def run(bin_dir, domain, work, seconds):
    before = shm_segments()
    result = scale.run_session(bin_dir, work, domain, USERS, SPECTATORS, seconds, fps=5.0, cache=fem_cache(work))
    rows = {r["node"]: r for r in result["rows"]}
    logs = result["logs"]
    window = result["window_s"]
    print(f"{USERS} users + {SPECTATORS} spectators + the audio guide, {window:.1f} s measured, "
          f"load {result['load'][0]} -> {result['load'][1]}")
    for r in result["rows"]:
        print("  " + ", ".join(f"{c} {scale.fmt(r.get(c))}" for c in scale.COLUMNS[2:-1] if r.get(c) is not None))

    for label, r in rows.items():
        check(r["exit"] == 0, f"{label} exited {r['exit']}")
        check(r["reliable_lost"] == 0, f"{label} lost {r['reliable_lost']} reliable samples: {r['traffic']}")
    server = logs["world_server"]
    for k in range(USERS):
        check(re.search(rf"member joined: user=user{k + 1}\b", server), f"user{k + 1} never joined")
    for k in range(SPECTATORS):
        check(re.search(rf"member joined: user=screen{k + 1}\b", server), f"screen{k + 1} never joined")
    check("member lost" not in server, "a member was lost: " + "; ".join(re.findall(r"member lost[^\n]*", server)))
    taken = rows["world_server"]["traffic"].get("contact_set", {}).get("in", 0)
    check(taken > 0, "the world server took no contact set")

    # The paced device states over the bridge's whole run (its ticks at their mean rate): at
    # most the 30 Hz floor the 5 fps screens get.
    for k in range(USERS):
        r = rows[f"user{k + 1}"]
        check("device_states" in r, f"user{k + 1} printed no bridge summary:\n{logs[f'user{k + 1}'][-2000:]}")
        check(r["contact_sets_shared"] > 0,
              f"user{k + 1} never sent a contact set at the full rate: its partner's touch was not seen "
              f"({r['contact_sets']} contact sets)")
        bridge_s = r["bridge_ticks"] / r["bridge_Hz"]
        limit = 1.2 * 30.0 * bridge_s + 5
        check(r["device_states"] <= limit,
              f"user{k + 1} sent {r['device_states']} device states in {bridge_s:.0f} s of ticks: more than "
              f"the 30 Hz the 5 fps screens need ({limit:.0f})")
    for k in range(SPECTATORS):
        t = rows[f"screen{k + 1}"]["traffic"]
        for topic in ("device_state", "deformation", "message_board"):
            check(t.get(topic, {}).get("in", 0) > 0, f"screen{k + 1} took no {topic}: {t}")
    check(re.search(r"message #\d+ \(", logs["audio_guide"]), "the audio guide spoke no board message")
    left = shm_segments() - before
    check(not left, f"shared-memory segments left behind: {sorted(left)}")
    print("scale: every node ran to the end, no reliable sample lost, every pair shared its object, "
          "device states paced to the screens")


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--bin-dir", required=True)
    ap.add_argument("--domain", type=int, required=True)
    ap.add_argument("--work", required=True)
    ap.add_argument("--seconds", type=float, default=60.0)
    a = ap.parse_args()
    clean_work(a.work)
    signal.signal(signal.SIGTERM, lambda *_: sys.exit(143))  # killed by ctest: the nodes end too
    try:
        run(a.bin_dir, a.domain, a.work, a.seconds)
    except (Failure, RuntimeError) as e:
        print(f"FAILED: scale: {e}\n(work folder: {a.work})", file=sys.stderr)
        return 1
    finally:
        remove_orphan_ports([a.domain])
    return 0


if __name__ == "__main__":
    sys.exit(main())
