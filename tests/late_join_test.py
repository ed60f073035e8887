#!/usr/bin/env python3
"""Late joiners get the whole current state: a spectator (graphics_node --headless) and an audio
guide that join a session after three world changes show the current world, the current board
text, the server's object poses and every deformable's current field.

The session: a world server and a scripted haptic user (tests/data/late_join_alice.hand): start
menu -> microscopic -> solar system -> dinosaur, the triceratops tail pressed and held. The
dinosaur world of this test (a copy of the assets with its scene changed) also holds the solar
system's ball, placed 8 cm above the ground: it falls when the world appears and rests, so its
pose is no longer the scene state's, and only an ObjectState can tell a late joiner where it is.

usage: late_join_test.py --bin-dir DIR --domain D --work DIR
"""
import json
import math
import os
import re
import sqlite3
import subprocess
import sys
import time

HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, HERE)
from session_test import (DATA, PressWatch, check, check_speech, edited_assets,  # noqa: E402
                          read_json, run_cases, fem_cache, scene_object, wait_until)

BALL_DROP_M = 0.08  # the ball starts this far above its resting place
REST_TOL_M = 1e-5  # the world server's rest tolerance: a body at rest moves less per tick


def make_assets(work):
    """The project's assets, with a dinosaur world that also holds a ball, in the air."""
    ball = dict(scene_object("solar_system", "ball"))
    # Clear of the triceratops, the controls and the hand's path; resting at z = radius.
    ball["position_m"] = [-0.05, -0.10, ball["radius_m"] + BALL_DROP_M]

    def add_ball(scene):
        if scene["name"] == "dinosaur":
            scene["objects"].append(ball)
    return edited_assets(work, add_ball), ball


def newest_pose(db_path, object_id):
    """The world server's newest logged pose of a body: (unix_ns, [px, py, pz], [qw, qx, qy, qz]), or None."""
    if not os.path.exists(db_path):
        return None
    db = sqlite3.connect(f"file:{db_path}?mode=ro", uri=True, timeout=5)
    try:
        row = db.execute("SELECT unix_ns, px, py, pz, qw, qx, qy, qz FROM object_poses WHERE object_id = ? "
                         "ORDER BY session_id DESC LIMIT 1", (object_id,)).fetchone()
    except sqlite3.OperationalError:
        row = None
    finally:
        db.close()
    return None if row is None else (row[0], list(row[1:4]), list(row[4:8]))


def arrival(log, pattern):
    """Seconds after joining that a node's log line matching pattern reports, else None."""
    m = re.search(pattern + r".* received ([\d.]+) s after joining", log)
    return float(m.group(1)) if m else None


def case_late_joiners(h, domain):
    session = f"it-late-{os.getpid()}"
    w = h.work
    assets, ball = make_assets(w)
    os.environ["HANDSHARE_ASSETS"] = assets
    cache = fem_cache(w)
    os.environ["HANDSHARE_CACHE"] = cache
    prep = subprocess.run([os.path.join(h.bin_dir, "core", "world", "world_prepare"), "--cache", cache,
                           "--scenes", "dinosaur,microscopic"], capture_output=True, text=True, timeout=600)
    check(prep.returncode == 0, f"world_prepare failed: {prep.stdout}{prep.stderr}")
    dump, log_db = os.path.join(w, "deformation"), os.path.join(w, "session.db")
    common = ["--domain", domain, "--session", session]
    h.start("world_server", "world_server", *common, "--scene", "start_menu", "--log", log_db,
            "--dump-deformation", dump)
    h.start("alice", "haptic_node", *common, "--user", "alice", "--device", "sim",
            "--script", os.path.join(DATA, "late_join_alice.hand"), "--trace", os.path.join(w, "alice.csv"))
    # Three world changes, each a new board message.
    for step in ("control button_microscopic by alice: scene 'microscopic'",
                 "control arrow_next by alice: scene 'solar_system'",
                 "control arrow_next by alice: scene 'dinosaur'"):
        h.wait_for_line("world_server", step, 120)
    h.wait_for_line("world_server", "models of 'dinosaur' ready", 120)
    # The tail pressed and held: the dump (every published field) unchanged for 2.5 s, so the
    # periodic keyframe after the last change has gone out too.
    with open(os.path.join(assets, "scenes", "dinosaur.json")) as f:
        scene = json.load(f)
    objects = {o["id"]: o for o in scene["objects"]}
    tail = PressWatch(os.path.join(dump, "triceratops_tail.json"), objects["triceratops_tail"]["position_m"],
                      {"alice": (0.225, 0.08)})
    held = wait_until("the tail pressed by alice, held still for 2.5 s", 90, lambda: tail.still_for(2.5), tail.explain)
    # The ball fell and rests: on the ground in the server's log, its logged position unchanged
    # (within the server's rest tolerance) for 2 s, over which its pose was logged again.
    rest = {"p": None, "since": None}
    def ball_at_rest():
        pose = newest_pose(log_db, "ball")
        if not pose or abs(pose[1][2] - ball["radius_m"]) > 0.005:
            return None
        if rest["p"] is None or max(abs(a - b) for a, b in zip(pose[1], rest["p"][1])) > REST_TOL_M:
            rest["p"], rest["since"] = pose, time.monotonic()
        return pose if time.monotonic() - rest["since"] >= 2.0 and pose[0] > rest["p"][0] else None
    wait_until("the ball resting on the ground in the server's log", 30, ball_at_rest,
               lambda: f"newest logged pose: {newest_pose(log_db, 'ball')}")
    server_log = h.log("world_server")
    revision = int(re.findall(r"scene 'dinosaur' \(revision (\d+)\)", server_log)[-1])
    boards = re.findall(r"message board #(\d+): (.*)", server_log)
    board_id, board_text = int(boards[-1][0]), boards[-1][1].strip()
    check(board_id == 4 and board_text == scene["messages"][0]["text"],
          f"the server's board is #{board_id} {board_text!r}, expected #4, the dinosaur's")

    # The late joiners. The spectator renders until it has everything, then writes what it shows.
    received_file, state_file = os.path.join(w, "received.json"), os.path.join(w, "state.json")
    t_join = time.monotonic()
    h.start("spectator", "graphics_node", *common, "--headless", "--frames", 100000, "--fps", 10,
            "--out", os.path.join(w, "frames"), "--deformation-out", received_file, "--state-out", state_file)
    h.start("audio_guide", "audio_guide", *common, "--out", os.path.join(w, "speech"))
    for line in ("scene 'dinosaur' revision", f"message board #{board_id}", "first deformation of 'triceratops_tail'",
                 "first pose of 'ball'"):
        h.wait_for_line("spectator", line, 30)
    h.wait_for_line("audio_guide", f"message #{board_id} (", 60)  # spoken into its WAV
    # A frame drawn with all of it (frame N+1 begun: frame N is written).
    wait_until("two frames drawn by the late spectator", 30,
               lambda: os.path.exists(os.path.join(w, "frames", "frame_00002.png")), lambda: h.log("spectator"))
    t_all = time.monotonic()
    check(h.stop("spectator", 30) == 0, "the late spectator failed")
    check(h.stop("audio_guide", 30) == 0, "the late audio guide failed")
    final_dump = read_json(os.path.join(dump, "triceratops_tail.json"))
    final_pose = newest_pose(log_db, "ball")
    check(h.stop("alice", 30) == 0, "alice's haptic node failed")
    check(h.stop("world_server", 30) == 0, "world_server failed")
    # The server's current field, as of after the joins (a spectator's join makes it send keyframes,
    # which count as revisions): still the one that was held (the hand did not move).
    held_max = max(math.sqrt(sum(c * c for c in u)) for u in held["sent_u_W_m"].values())
    drift = max(math.sqrt(sum((x - y) ** 2 for x, y in zip(u, held["sent_u_W_m"].get(v, [0.0, 0.0, 0.0]))))
                for v, u in final_dump["sent_u_W_m"].items())
    check(drift <= held["threshold_m"] + 1e-6 * held_max, f"the tail's field moved by {drift:.3g} m while they joined")

    # The scene and the board the spectator shows are the current ones.
    state = read_json(state_file)
    check(state is not None, f"the spectator wrote no {state_file}")
    check(state["scene"] == "dinosaur" and state["revision"] == revision,
          f"the spectator shows scene {state['scene']!r} revision {state['revision']}, the server dinosaur {revision}")
    check(state["board"]["message_id"] == board_id and state["board"]["text"] == board_text
          and state["board"]["language"] == "en",
          f"the spectator's board {state['board']}, the server's #{board_id} {board_text!r}")
    with open(os.path.join(w, "frames", "frame_times.csv")) as f:
        last_frame = f.read().strip().split("\n")[-1].split(",")
    check(last_frame[2:4] == ["dinosaur", str(revision)], f"the last frame shows {last_frame[2:4]}")
    # The object poses: the ball where the server has it (its ObjectState), the others as placed.
    shown = state["objects"]
    controls = {c["id"] for c in scene["controls"]}
    check(sorted(shown) == sorted(set(objects) | controls),
          f"the spectator's objects {sorted(shown)}, the scene's {sorted(set(objects) | controls)}")
    check(all(shown[c]["from"] == "scene_state" for c in controls), "a control was moved by an object state")
    check(shown["ball"]["from"] == "object_state", "the spectator draws the ball at the scene state's pose")
    # The server's pose from its log (written when it publishes one, at most every 0.1 s) after
    # the joins; a body at rest may creep by less than the rest tolerance between two of them.
    ball_err = max(abs(a - b) for a, b in zip(shown["ball"]["p_WO_m"], final_pose[1]))
    ball_rot = max(abs(a - b) for a, b in zip(shown["ball"]["q_WO_wxyz"], final_pose[2]))
    check(ball_err <= REST_TOL_M and ball_rot <= 1e-3,
          f"the spectator's ball {shown['ball']} differs from the server's {final_pose} by {ball_err:.3g} m")
    fell = ball["position_m"][2] - shown["ball"]["p_WO_m"][2]
    check(abs(fell - BALL_DROP_M) < 0.005, f"the ball is drawn {fell * 1e3:.1f} mm below its start, not resting")
    for oid, o in objects.items():  # the rest stay where the scene puts them
        if oid == "ball":
            continue
        err = max(abs(a - b) for a, b in zip(shown[oid]["p_WO_m"], o["position_m"]))
        check(err < 1e-9, f"{oid} is drawn at {shown[oid]['p_WO_m']}, placed at {o['position_m']}")
    # Every deformable's field: the tail's equals the server's current one (float32 on the wire);
    # the head and the leg, never touched, have none.
    with open(received_file) as f:
        received = json.load(f)
    check(set(received) <= {"triceratops_tail", "triceratops_head", "triceratops_leg"}, f"fields of {set(received)}")
    tail_rx = received.get("triceratops_tail")
    check(tail_rx is not None, "the late spectator received no field of the tail")
    sent = final_dump["sent_u_W_m"]
    u_max = max(math.sqrt(sum(c * c for c in u)) for u in sent.values())
    check(u_max >= 1e-3, f"the tail's dent is {u_max * 1e3:.2f} mm: not a field worth checking")
    worst = 0.0
    for v in range(int(tail_rx["vertex_count"])):
        a, b = sent.get(str(v), [0.0, 0.0, 0.0]), tail_rx["u_W_m"].get(str(v), [0.0, 0.0, 0.0])
        worst = max(worst, math.sqrt(sum((x - y) ** 2 for x, y in zip(a, b))))
    tol = 1e-6 * u_max  # float32 on the wire (2^-24 relative), with margin
    check(worst <= tol, f"the late spectator's tail field differs from the server's by {worst:.3g} m (> {tol:.3g})")
    # At least the revision of the field held still (a later one is the same field re-sent as a
    # keyframe for this spectator, which may still be on its way when it stops).
    check(held["revision"] <= tail_rx["revision"] <= final_dump["revision"],
          f"the spectator's tail is revision {tail_rx['revision']}, the server's held one {held['revision']}, "
          f"its last {final_dump['revision']}")
    for oid in ("triceratops_head", "triceratops_leg"):
        check(not received.get(oid, {}).get("u_W_m"), f"{oid} was never touched but the spectator shows it dented")
    # The audio guide spoke the current message, and only that one.
    speech = os.path.join(w, "speech")
    wavs = sorted(os.listdir(speech))
    check(wavs == [f"message_{board_id}.txt", f"message_{board_id}.wav"], f"the late audio guide wrote {wavs}")
    with open(os.path.join(speech, f"message_{board_id}.txt")) as f:
        spoken = f.read()
    check(spoken.startswith(board_text), f"the audio guide spoke {spoken!r}, the board says {board_text!r}")
    duration, rms = check_speech(os.path.join(speech, f"message_{board_id}.wav"))

    g, a = h.log("spectator"), h.log("audio_guide")
    figures = {"scene": arrival(g, r"scene 'dinosaur' revision \d+"), "board": arrival(g, rf"message board #{board_id}"),
               "tail field": arrival(g, r"first deformation of 'triceratops_tail'"),
               "ball pose": arrival(g, r"first pose of 'ball'"),
               "audio guide board": arrival(a, rf"message board #{board_id}")}
    print(f"late joiners after 3 world changes (dinosaur revision {revision}, board #{board_id}):")
    print("  arrived after joining: " + ", ".join(f"{k} {v:.3f} s" for k, v in figures.items()))
    print(f"  tail field: revision {tail_rx['revision']}, dent {u_max * 1e3:.2f} mm, {len(tail_rx['u_W_m'])} vertices "
          f"moved, largest difference to the server's {worst:.2e} m")
    print(f"  ball: fell {fell * 1e3:.1f} mm, drawn at the server's pose (difference {ball_err:.1e} m); speech "
          f"{duration:.1f} s, RMS {rms:.0f}; everything within {t_all - t_join:.2f} s of starting both")
    h.print_traffic()


if __name__ == "__main__":
    sys.exit(run_cases({"late_joiners": case_late_joiners}))
