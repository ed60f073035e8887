#!/usr/bin/env python3
"""Smoke tests of handshare over a real (impaired) network: the executables in separate network
namespaces, so Fast DDS talks UDP over veth and a bridge, not shared memory.

usage: net_dds_test.py two_hosts|partitioned_user|tour|unicast_peers|late_joiners_unicast|delayed_tail|handover
                      --bin-dir DIR --nfq-delay PATH --domain D --work DIR
"""
import math
import os
import re
import shutil
import subprocess
import sys
import time

HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, HERE)
from netharness import Network, Failure, check, main  # noqa: E402

sys.path.insert(0, os.path.join(HERE, ".."))
import session_test  # noqa: E402  (trace and deformation-dump readers shared with the loopback tests)

DATA = os.path.join(HERE, "..", "data")


def exe(bin_dir, name):
    path = os.path.join(bin_dir, name, name)
    check(os.access(path, os.X_OK), f"executable not built: {path}")
    return path


def shm_files():
    try:
        return {f for f in os.listdir("/dev/shm") if "fastrtps" in f or "fastdds" in f}
    except FileNotFoundError:
        return set()


def case_two_hosts(args):
    """world_server on one host, a simulated haptic node on another; 20 ms +- 5 ms and 2 % loss
    on what arrives at each host (so each direction of each link)."""
    os.makedirs(args.work, exist_ok=True)
    server_exe, node_exe = exe(args.bin_dir, "world_server"), exe(args.bin_dir, "haptic_node")
    session = f"net-two-hosts-{os.getpid()}"
    common = ["--domain", args.domain, "--session", session]
    with Network(2, nfq_delay=args.nfq_delay) as net:
        a, b = net.hosts
        for seed, h in enumerate((a, b), start=1):
            h.loss(2)
            h.delay(20, jitter_ms=5, seed=seed)
        shm_before = shm_files()
        t0 = time.monotonic()
        server = a.start("world_server", [server_exe, *common, "--duration", 60], args.work)
        node = b.start("alice", [node_exe, *common, "--user", "alice", "--device", "sim", "--script",
                                 os.path.join(DATA, "alice.hand"), "--duration", 45], args.work)
        try:
            t_join = server.wait_for("member joined: user=alice", 30)
            t_scene = node.wait_for(re.compile(r"scene '[^']+' revision \d+"), 30)
            c0 = a.counters()
            time.sleep(1.0)  # a measurement window of the traffic, not a wait for an event
            c1 = a.counters()
            unicast = (c1["udp_in"] - c1["udp_in_mcast"]) - (c0["udp_in"] - c0["udp_in_mcast"])
            mcast = c1["udp_in_mcast"] - c0["udp_in_mcast"]
            # It is really UDP: cut the node's host off (nft drops UDP only); over shared memory
            # nothing would change. Over UDP the server loses alice (1 s participant lease) and
            # finds her again when the link heals.
            t_cut = time.monotonic()
            net.isolate(b)
            t_lost = server.wait_for("member lost: user=alice", 15)
            # The cut lasts 3 s (the issue's partition): long enough for both sides' participant
            # leases (1 s) to end. (A heal between the member's liveliness loss and the lease's end
            # left the writer unmatched for good in one run: noted in docs/network.md.)
            time.sleep(max(0.0, t_cut + 3.0 - time.monotonic()))  # the partition's length, not a wait
            t_heal = time.monotonic()
            net.heal_all()
            # Back when the link heals: Fast DDS 2.9 does not deliver her member sample again, so
            # the server restores the member when her writer matches again (MemberRegistry).
            joins = server.log().count("member joined: user=alice")
            t_back = server.wait_for("member joined: user=alice", 10, count=joins + 1)
            t_stop_sent = time.monotonic()
            node.stop()
            # Her clean leave after the partition: not asserted. With Fast DDS 2.9.1 the server has
            # not received her dispose once her writer was re-matched (3 runs of 3): it reports her
            # lost when her writer goes, ~40 ms later (docs/network.md).
            try:
                t_left = server.wait_for("member left: user=alice", 5)
            except Failure:
                t_left = None
            t_stop = node.popen.returncode
        except Failure:
            for p in (server, node):
                sys.stderr.write(f"----- {p.label} -----\n{p.log()}\n")
            raise
        server.stop()
        stats = {h.ns: h.clear_delay() for h in (a, b)}
    scene_line = re.search(r"scene '[^']+' revision \d+[^\n]*", node.log()).group(0)
    print(f"two hosts ({a.addr} server, {b.addr} haptic node), 20 ms +- 5 ms and 2% loss on arrival at each:")
    print(f"  member joined {t_join - t0:.2f} s after start; scene at the node {t_scene - t0:.2f} s ({scene_line})")
    print(f"  UDP datagrams arriving at the server's host in 1 s: {unicast} unicast, {mcast} multicast")
    print("  samples per topic (out: written, in: taken, lost: reported lost by the middleware):")
    print("\n".join("  " + t for t in traffic_lines({p.label: p.log() for p in (server, node)})))
    back = f"joined again after {t_back - t_heal:.2f} s"
    print(f"  node's host isolated: member lost after {t_lost - t_cut:.2f} s; healed: {back}")
    if t_left:
        print(f"  member left {t_left - t_stop_sent:.2f} s after SIGTERM to the node (rc {t_stop})")
    else:
        print(f"  node stopped with SIGTERM (rc {t_stop}); the server reported no clean leave (known, not asserted)")
    for ns, st in stats.items():
        print(f"  delayer {ns}: {st and st.get('raw')}")
    new_shm = sorted(shm_files() - shm_before)
    print(f"  /dev/shm Fast DDS files left after the run: {new_shm or 'none'}")
    check(unicast > 0, "no unicast UDP reached the server")
    check(all(st and st["accepted"] > 0 for st in stats.values()), "a delayer saw no traffic")


def traffic_lines(logs):
    """Each process's exit line of samples written, taken and lost per topic ("traffic: ...")."""
    return [f"  {label} {session_test.traffic_line(log) or 'printed no traffic line'}" for label, log in logs.items()]


def loop_summary(log, user):
    """The figures of a haptic node's exit summary (rate, jitter, overruns, faults, rate-limited steps)."""
    m = re.search(rf"\[haptic_node {user}\] loop statistics: rate ([\d.]+) Hz, steps (\d+), jitter p50 (\d+) us "
                  r"p99 (\d+) us max (\d+) us, step p50 [\d.]+ us p99 [\d.]+ us, overruns (\d+), resyncs (\d+), "
                  r"faults (\d+), rate-limited steps (\d+)", log)
    check(m is not None, f"{user}'s haptic node printed no loop summary:\n{log[-3000:]}")
    keys = ("rate_Hz", "steps", "jitter_p50_us", "jitter_p99_us", "jitter_max_us", "overruns", "resyncs", "faults",
            "rate_limited")
    return {k: float(v) for k, v in zip(keys, m.groups())}


def loop_rate(rows, t_a, t_b):
    """The haptic loop's rate [Hz] between two times of the host's steady clock, from a trace's rows
    (seq counts the loop's steps; stamp_ns is the step's time)."""
    w = [r for r in rows if t_a <= r["stamp_ns"] * 1e-9 <= t_b]
    check(len(w) > 20, f"only {len(w)} trace rows in [{t_a:.2f}, {t_b:.2f}] s")
    return (w[-1]["seq"] - w[0]["seq"]) / ((w[-1]["stamp_ns"] - w[0]["stamp_ns"]) * 1e-9)


def smoothness(rows, t_ref, t_a, t_b, change, fade_s=0.25):
    """The worst step of a trace's net vertical force in [t_a, t_b) s of t_ref beyond what a fade
    of the whole `change` over fade_s could do between those rows: (excess, step, gap)."""
    fz = [(r["stamp_ns"] * 1e-9 - t_ref, session_test.net_fz(r)) for r in rows]
    window = [(t, f) for t, f in fz if t_a <= t < t_b]
    check(len(window) > 20, f"only {len(window)} trace rows in [{t_a}, {t_b}) s")
    return max((abs(f1 - f0) - change * (t1 - t0) / fade_s, abs(f1 - f0), t1 - t0)
               for (t0, f0), (t1, f1) in zip(window, window[1:]))


def dinosaur_ready(args):
    """The work folder, and the dinosaur world's compliances prepared in its cache (shared by the
    nodes through HANDSHARE_CACHE): the tail cases' set-up. Returns the server's and the haptic
    node's executables."""
    os.makedirs(args.work, exist_ok=True)
    server_exe, node_exe = exe(args.bin_dir, "world_server"), exe(args.bin_dir, "haptic_node")
    cache = session_test.fem_cache(args.work)
    os.environ["HANDSHARE_CACHE"] = cache
    prep = subprocess.run([os.path.join(args.bin_dir, "core", "world", "world_prepare"), "--cache", cache,
                           "--scenes", "dinosaur"], capture_output=True, text=True, timeout=600)
    check(prep.returncode == 0, f"world_prepare failed: {prep.stdout}{prep.stderr}")
    return server_exe, node_exe


def script_starts(nodes):
    """Each haptic node's loop time [s] when its hand script started (it logs it once the first
    world is here)."""
    starts = {}
    for user, p in nodes.items():
        p.wait_for("hand script starts at loop time", 60)
        starts[user] = float(re.search(r"hand script starts at loop time ([\d.]+) s", p.log()).group(1))
    return starts


def stop_session(server, nodes, when=""):
    """Stops the haptic nodes (each must exit 0), then the world server."""
    for user, p in nodes.items():
        check(p.stop(timeout=30) == 0, f"{user}'s haptic node failed{when}:\n{p.log()[-3000:]}")
    server.stop()


def print_logs(procs):
    """The end of each process's log, for a failed case."""
    for p in procs:
        sys.stderr.write(f"----- {p.label} -----\n{p.log()[-6000:]}\n")


STEP_FLOOR = 0.02  # of a force: a step below it is not felt (Weber fraction about 0.1)


def case_partitioned_user(args):
    """Three hosts (world server; alice; bob), 20 ms +- 5 ms and 2 % loss on what arrives at each.
    alice and bob press the triceratops tail together; alice's host is cut off for 3 s, then
    healed. Asserted: the server marks alice lost within 1.5 s; bob's force moves to its
    alone-value without a step (alice's contacts fade at his node); alice's haptic loop keeps its
    rate through the cut and its safety never has to cut a force step (rate-limited steps 0);
    after the heal alice is back within 1 s, once (present=2, no duplicate), with her contacts:
    the tail's solve holds her fingertip again and bob's force returns to its shared value; a
    control event she sends afterwards (a reliable sample of her re-matched writer) is applied."""
    server_exe, node_exe = dinosaur_ready(args)
    session = f"net-partition-{os.getpid()}"
    common = ["--domain", args.domain, "--session", session]
    dump = os.path.join(args.work, "deformation")
    traces = {u: os.path.join(args.work, f"{u}.csv") for u in ("alice", "bob")}
    for f in traces.values():
        if os.path.exists(f):
            os.remove(f)
    tail = session_test.scene_object("dinosaur", "triceratops_tail")
    p_tail = tail["position_m"]
    mu_s, mu_k = tail["material"].get("mu_static", 0.0), tail["material"].get("mu_kinetic", 0.0)
    with Network(3, nfq_delay=args.nfq_delay) as net:
        a, b, c = net.hosts
        for seed, h in enumerate((a, b, c), start=1):
            h.loss(2)
            h.delay(20, jitter_ms=5, seed=seed)
        server = a.start("world_server", [server_exe, *common, "--scene", "dinosaur", "--dump-deformation", dump,
                                          "--deformation-threshold", "1e-6", "--duration", 120], args.work)
        server.wait_for("models of 'dinosaur' ready", 60)
        nodes = {}
        for host, user in ((b, "alice"), (c, "bob")):
            nodes[user] = host.start(user, [node_exe, *common, "--user", user, "--device", "sim", "--script",
                                            os.path.join(DATA, "partition_alice.hand" if user == "alice"
                                                         else "vanish_bob.hand"),
                                            "--trace", traces[user], "--duration", 90], args.work)
        alice, bob = nodes["alice"], nodes["bob"]
        tail = session_test.PressWatch(os.path.join(dump, "triceratops_tail.json"), p_tail,
                                       {"alice": (0.225, 0.08), "bob": (0.27, 0.08)})
        try:
            server.wait_for("member joined: user=alice", 30)
            server.wait_for("member joined: user=bob", 30)
            session_test.wait_until("the tail pressed by alice and bob, held still for 3 s", 90,
                                    lambda: tail.still_for(3.0), tail.explain)
            joins = server.log().count("member joined: user=alice")
            t_cut = time.monotonic()  # the host's steady clock, which stamps both traces
            net.isolate(b)
            t_lost = server.wait_for("member lost: user=alice", 10)

            def bob_alone():
                held = tail.poll()
                return held is not None and not tail.loaded_near(held, "alice") and tail.loaded_near(held, "bob")
            session_test.wait_until("the tail loaded by bob alone", 5, bob_alone, tail.explain)
            t_alone = time.monotonic()
            time.sleep(max(0.0, t_cut + 3.0 - time.monotonic()))  # the partition's length, not a wait
            t_heal = time.monotonic()
            net.heal_all()
            t_back = server.wait_for("member joined: user=alice", 10, count=joins + 1)
            rejoin = re.findall(r"member joined: user=alice[^\n]*present=(\d+)", server.log())[-1]
            session_test.wait_until("the tail pressed by both again", 10,
                                    lambda: (held := tail.poll()) is not None and tail.loaded_near(held, "alice")
                                    and tail.loaded_near(held, "bob"), tail.explain)
            t_shared = time.monotonic()
            # Both traces 2.5 s past the heal (the shared press settles), flushed row by row.
            for user in ("alice", "bob"):
                session_test.wait_until(f"{user}'s trace 2.5 s past the heal", 30,
                                        lambda u=user: (rows := session_test.read_trace(traces[u]))
                                        and rows[-1]["stamp_ns"] * 1e-9 >= t_heal + 2.6)
            # A reliable sample from alice's writer after the partition: her script presses the
            # arrow to the microscopic world 30 s after her press began.
            t_sent = alice.wait_for("control arrow_next: PRESSED", 60)
            t_applied = server.wait_for("control arrow_next by alice: scene 'microscopic'", 30)
            for user in ("alice", "bob"):
                check(nodes[user].stop(timeout=30) == 0, f"{user}'s haptic node failed:\n{nodes[user].log()[-3000:]}")
        except Failure:
            print_logs((server, alice, bob))
            raise
        server.stop()
        summaries = {u: loop_summary(nodes[u].log(), u) for u in ("alice", "bob")}
        ws_log = server.log()
        traffic = traffic_lines({p.label: p.log() for p in (server, alice, bob)})
    rows = {u: session_test.read_trace(traces[u]) for u in ("alice", "bob")}

    def mean_fz(user, t_a, t_b):
        v = [session_test.net_fz(r) for r in rows[user] if t_a <= r["stamp_ns"] * 1e-9 - t_cut < t_b]
        check(len(v) > 20, f"{user}'s trace has {len(v)} rows in [{t_a}, {t_b}) s of the cut")
        return sum(v) / len(v)
    heal = t_heal - t_cut
    bob_before, bob_cut, bob_after = mean_fz("bob", -2.0, -0.2), mean_fz("bob", 2.0, 3.0), mean_fz("bob", heal + 1.5, heal + 2.5)
    alice_before, alice_cut = mean_fz("alice", -2.0, -0.2), mean_fz("alice", 2.0, 3.0)
    change = abs(bob_cut - bob_before)
    worst, step, gap = smoothness(rows["bob"], t_cut, -0.5, 3.0, change)
    a_change = abs(alice_cut - alice_before)
    a_worst, a_step, a_gap = smoothness(rows["alice"], t_cut, -0.5, 3.0, a_change)
    rate_cut = loop_rate(rows["alice"], t_cut + 0.2, t_heal - 0.2)
    rate_before = loop_rate(rows["alice"], t_cut - 2.5, t_cut - 0.2)
    print("partitioned user: server | alice | bob on three hosts, 20 ms +- 5 ms and 2 % loss on arrival at each; "
          "alice's host cut off for 3 s while both press the tail")
    print(f"  server: alice lost {t_lost - t_cut:.2f} s after the cut; tail loaded by bob alone "
          f"{t_alone - t_cut:.2f} s after it; alice back {t_back - t_heal:.2f} s after the heal (present={rejoin}), "
          f"her contacts in the tail's solve again {t_shared - t_heal:.2f} s after it")
    print(f"  alice's control event {t_sent - t_heal:.1f} s after the heal (a reliable sample of her re-matched "
          f"writer): applied by the server {1e3 * (t_applied - t_sent):.0f} ms after her node sent it")
    print(f"  bob's force {bob_before:.4f} -> {bob_cut:.4f} N during the cut -> {bob_after:.4f} N after; steepest "
          f"step {step:.5f} N (rows {1e3 * gap:.0f} ms apart)")
    print(f"  alice's force {alice_before:.4f} -> {alice_cut:.4f} N during the cut; steepest step {a_step:.5f} N "
          f"(rows {1e3 * a_gap:.0f} ms apart); loop {rate_before:.1f} Hz before, {rate_cut:.1f} Hz during the cut")
    print("  samples per topic (out: written, in: taken, lost: reported lost by the middleware):")
    print("\n".join("  " + t for t in traffic))
    for u, s in summaries.items():
        print(f"  {u}'s loop: {s['rate_Hz']:.1f} Hz, jitter p99 {s['jitter_p99_us']:.0f} us max "
              f"{s['jitter_max_us']:.0f} us, overruns {s['overruns']:.0f}, faults {s['faults']:.0f}, "
              f"rate-limited steps {s['rate_limited']:.0f}")
    check(t_lost - t_cut <= 1.5, f"the server marked alice lost {t_lost - t_cut:.2f} s after the cut (> 1.5 s)")
    check(t_back - t_heal <= 1.0, f"alice was back {t_back - t_heal:.2f} s after the heal (> 1 s)")
    check(rejoin == "2", f"after the heal the server counts {rejoin} members present (alice and bob: 2)")
    check(ws_log.count("member joined: user=alice") == joins + 1, "alice joined more than once after the heal")
    check(change >= 0.01, f"alice's press did not matter to bob's fingertip ({bob_before:.4f} -> {bob_cut:.4f} N)")
    # A step is a fault when it is a good part of the change alice's press made to bob's force,
    # and large enough to feel: with friction on the tail, where each patch stuck decides how
    # much alice's press matters to bob (0.024-0.10 N seen), and a change that small leaves
    # steps under STEP_FLOOR of his force (a fifth of the 10 % a fingertip tells apart) that
    # nobody feels (a 0.019 N step once, with a 0.024 N change).
    allowed = max(0.3 * change, STEP_FLOOR * abs(bob_before))
    check(worst <= allowed, f"bob's force jumped by {step:.4f} N between rows {1e3 * gap:.0f} ms apart when "
                            f"alice was cut off (whole change {change:.4f} N; allowed {allowed:.4f} N)")
    # With friction on the tail, alice's fingertip, held still while the tail rises under it as
    # bob's contacts fade, may break away (stick to slip): Coulomb's force then changes at once,
    # from the static to the kinetic cone, by up to (mu_s - mu_k) times the force she presses
    # with. Seen once in 8 runs of 86d003d: one step of 0.070 N as bob's fade ended (the fade
    # allows 0.050 N), her force constant after it. That her patch slipped there is likely, not
    # shown (the trace has no patch state). Such a step is allowed; a larger one is not.
    breakaway = (mu_s - mu_k) * max(alice_before, alice_cut)
    check(a_change < 0.01 or a_worst <= 0.3 * a_change + breakaway,
          f"alice's force jumped by {a_step:.4f} N between rows {1e3 * a_gap:.0f} ms apart when she was cut off "
          f"(a friction breakaway allows {breakaway:.4f} N)")
    check(abs(bob_after - bob_before) <= 0.1 * change + 2e-3,
          f"bob's force after the heal {bob_after:.4f} N is not the shared press's {bob_before:.4f} N")
    check(rate_cut >= 0.98 * rate_before, f"alice's loop ran at {rate_cut:.1f} Hz during the cut ({rate_before:.1f} before)")
    for u, s in summaries.items():
        check(s["faults"] == 0, f"{u}'s haptic loop had {s['faults']:.0f} faulted steps")
        check(s["rate_limited"] == 0, f"{u}'s force safety had to cut {s['rate_limited']:.0f} force steps")


class NetHarness(session_test.Harness):
    """session_test's Harness with each process in the network namespace of its host: a
    loopback case runs unchanged across hosts (labels not in `hosts_by_label` run in the first)."""

    def __init__(self, bin_dir, work, hosts_by_label, default_host):
        super().__init__(bin_dir, work)
        self.hosts_by_label, self.default_host = hosts_by_label, default_host

    def start(self, label, name, *args):
        host = self.hosts_by_label.get(label, self.default_host)
        log = open(os.path.join(self.work, label + ".log"), "w")
        if "--duration" not in args:
            args = (*args, "--duration", session_test.BACKSTOP_S)
        proc = subprocess.Popen(["ip", "netns", "exec", host.ns, self.exe(name), *map(str, args)], stdout=log,
                                stderr=subprocess.STDOUT)
        self.procs[label] = (proc, log)
        return proc


def case_tour(args):
    """The encyclopedia tour (session_test.py's case, with the same assertions: Moon and Mars
    weights, the jointly pressed tail against fem_solve, both hands in the spectator's frames,
    every board message spoken) with the world server, alice, bob, the spectator and the audio
    guide on five hosts, 20 ms +- 5 ms one-way delay and 2 % loss on what arrives at each."""
    session_test.clean_work(args.work)
    labels = ("world_server", "alice", "bob", "spectator", "audio_guide")
    with Network(5, nfq_delay=args.nfq_delay) as net:
        for seed, host in enumerate(net.hosts, start=1):
            host.loss(2)
            host.delay(20, jitter_ms=5, seed=seed)
        h = NetHarness(args.bin_dir, args.work, dict(zip(labels, net.hosts)), net.hosts[0])
        t0 = time.monotonic()
        try:
            session_test.case_encyclopedia(h, args.domain)
        except Failure:
            h.dump_logs()
            raise
        except session_test.Failure as e:
            h.dump_logs()
            raise Failure(str(e))
        finally:
            h.cleanup()
        took = time.monotonic() - t0
        counters = {label: host.counters() for label, host in zip(labels, net.hosts)}
        delays = {label: host.clear_delay() for label, host in zip(labels, net.hosts)}
    print(f"tour across five hosts ({', '.join(labels)}), 20 ms +- 5 ms and 2 % loss on arrival at each: "
          f"completed in {took:.1f} s")
    for label in labels:
        raw = delays[label] and delays[label].get("raw")
        print(f"  {label}: UDP datagrams arrived {counters[label]['udp_in']} "
              f"({counters[label]['udp_in_mcast']} multicast); delayer {raw}")


def case_unicast_peers(args):
    """A network without multicast (nft drops every multicast datagram arriving at either host):
    the world server and a haptic node on two hosts match with --peers (unicast discovery to the
    listed hosts), and do not without it (the negative control)."""
    os.makedirs(args.work, exist_ok=True)
    server_exe, node_exe = exe(args.bin_dir, "world_server"), exe(args.bin_dir, "haptic_node")
    # A bad peer is an option error naming the value (exit 2), before any DDS entity exists.
    bad = subprocess.run([node_exe, "--session", "x", "--user", "x", "--peers", "10.0.0.1:99999"], capture_output=True, text=True,
                         timeout=30)
    check(bad.returncode == 2 and "'10.0.0.1:99999': port 99999 is not in 1..65535" in bad.stderr,
          f"bad --peers: rc {bad.returncode}, stderr {bad.stderr!r}")
    node_script = os.path.join(DATA, "alice.hand")
    with Network(2, nfq_delay=args.nfq_delay) as net:
        a, b = net.hosts
        for h in (a, b):
            h.drop_multicast()

        def session_of(label, peers_of_server, peers_of_node):
            session = f"net-peers-{label}-{os.getpid()}"
            common = ["--domain", args.domain, "--session", session]
            c0 = {h: h.counters() for h in (a, b)}
            t0 = time.monotonic()
            server = a.start(f"world_server_{label}", [server_exe, *common, *peers_of_server, "--duration", 60],
                             args.work)
            node = b.start(f"alice_{label}", [node_exe, *common, *peers_of_node, "--user", "alice", "--device", "sim",
                                              "--script", node_script, "--duration", 45], args.work)
            return server, node, t0, c0

        # Negative control: simple discovery without --peers. Its announcements are multicast
        # only; nothing of it arrives, so the two never match. 8 s is 10x the time they take
        # to match with multicast across these hosts (0.6-0.8 s, net.two_hosts, with 20 ms
        # delay and loss), and 40 announcements.
        server, node, t0, c0 = session_of("without_peers", [], [])
        try:
            server.wait_for("member joined: user=alice", 8)
            joined = True
        except Failure:
            joined = False
        check(not joined, "without --peers and without multicast the server still saw alice join")
        check("scene '" not in node.log(), "without --peers the node still received a scene")
        mcast_dropped = {h.ns: h.counters()["udp_in_mcast"] - c0[h]["udp_in_mcast"] for h in (a, b)}
        check(all(n > 0 for n in mcast_dropped.values()),
              f"no multicast announcement reached a host (so none was dropped): {mcast_dropped}")
        check(server.popen.poll() is None and node.popen.poll() is None, "a node of the negative control ended")
        server.stop()
        node.stop()
        t_neg = time.monotonic() - t0

        # With --peers on both: each announces to the other's host (and its own loopback).
        server, node, t0, c0 = session_of("with_peers", ["--peers", b.addr], ["--peers", a.addr])
        try:
            t_join = server.wait_for("member joined: user=alice", 30)
            t_scene = node.wait_for(re.compile(r"scene 'start_menu' revision \d+"), 30)
            t_stop = time.monotonic()
            node.stop()
            t_left = server.wait_for("member left: user=alice", 10)
        except Failure:
            for p in (server, node):
                sys.stderr.write(f"----- {p.label} -----\n{p.log()}\n")
            raise
        server.stop()
        c1 = {h: h.counters() for h in (a, b)}
        unicast = {h.ns: (c1[h]["udp_in"] - c1[h]["udp_in_mcast"]) - (c0[h]["udp_in"] - c0[h]["udp_in_mcast"])
                   for h in (a, b)}
        mcast = {h.ns: c1[h]["udp_in_mcast"] - c0[h]["udp_in_mcast"] for h in (a, b)}
    print(f"no multicast ({a.addr} server, {b.addr} haptic node; nft drops 224.0.0.0/4 arriving at both):")
    print(f"  without --peers: no match in {t_neg:.1f} s; multicast datagrams dropped on arrival: {mcast_dropped}")
    print(f"  with --peers: member joined {t_join - t0:.2f} s after start, scene at the node {t_scene - t0:.2f} s, "
          f"member left {t_left - t_stop:.2f} s after SIGTERM to the node (clean leave over unicast)")
    print(f"  UDP datagrams that arrived in the --peers run: unicast {unicast}, multicast (dropped) {mcast}")
    print("  samples per topic in the --peers run (out: written, in: taken, lost: reported lost):")
    print("\n".join("  " + t for t in traffic_lines({p.label: p.log() for p in (server, node)})))
    check(all(n > 0 for n in unicast.values()), f"no unicast UDP arrived at a host: {unicast}")


class HostsHarness:
    """session_test.Harness's interface over netharness hosts: each label runs on the host
    `placement` gives it, with --peers listing every other host (multicast is dropped)."""

    def __init__(self, net, bin_dir, work, placement):
        self.net, self.bin_dir, self.work, self.placement = net, bin_dir, work, placement
        self.procs = {}

    def start(self, label, name, *args):
        host = self.placement[label]
        peers = ",".join(h.addr for h in self.net.hosts if h is not host)
        if "--duration" not in args:
            args = (*args, "--duration", 900)  # a backstop; the test ends each node
        self.procs[label] = host.start(label, [exe(self.bin_dir, name), *args, "--peers", peers], self.work)
        return self.procs[label]

    def wait_for_line(self, label, text, timeout):
        return self.procs[label].wait_for(text, timeout)

    def log(self, label):
        return self.procs[label].log()

    def stop(self, label, timeout):
        return self.procs[label].stop(timeout=timeout)

    def print_traffic(self):
        print("samples per topic (out: written, in: taken, lost: reported lost by the middleware):")
        print("\n".join(traffic_lines({label: p.log() for label, p in self.procs.items()})))


def case_late_joiners_unicast(args):
    """tests/late_join_test.py's late joiners across a network without multicast: the world
    server on one host, the scripted hand on another, the late spectator and audio guide on a
    third; every node with --peers, multicast dropped on arrival at every host, 10 ms +- 2 ms
    and 1 % loss on what arrives at each host."""
    sys.path.insert(0, os.path.join(HERE, ".."))
    import late_join_test  # noqa: E402
    session_test.clean_work(args.work)
    with Network(3, nfq_delay=args.nfq_delay) as net:
        a, b, c = net.hosts
        for seed, h in enumerate(net.hosts, start=1):
            h.drop_multicast()
            h.loss(1)
            h.delay(10, jitter_ms=2, seed=seed)
        h = HostsHarness(net, args.bin_dir, args.work,
                         {"world_server": a, "alice": b, "spectator": c, "audio_guide": c})
        try:
            late_join_test.case_late_joiners(h, args.domain)
        except (Failure, late_join_test.Failure) as e:  # the harness's, or session_test's checks'
            for label in h.procs:
                sys.stderr.write(f"----- {label} -----\n{h.log(label)}\n")
            raise Failure(str(e))
        c_in = c.counters()
        stats = {x.ns: x.clear_delay() for x in net.hosts}
    print(f"  (hosts: server {a.addr}, hand {b.addr}, late joiners {c.addr}; UDP arriving at the late joiners' host: "
          f"{c_in['udp_in']} datagrams, {c_in['udp_in_mcast']} multicast, dropped)")
    for ns, st in stats.items():
        print(f"  delayer {ns}: {st and st.get('raw')}")


DELAYS_MS = (0, 10, 25, 50, 100)
# The holds of tests/data/delay_{alice,bob}.hand, in script time [s]: each user's press at 3 mm
# and 1 mm deeper while the other holds still, and both holding still at the end.
# (alice: 3 mm from 3 s, 4 mm 6.5-9.5 s; bob: 4 mm 12.5-15.5 s; both at 3 mm from 16 s; the
# first 1.5-2 s of each hold are the HIRO II arm settling.)
STIFFNESS_WINDOWS = {"alice": ((5.0, 6.0), (8.0, 9.5)), "bob": ((10.5, 12.0), (14.0, 15.5))}
STILL_WINDOW = (17.5, 20.5)
HF_LIMIT_N = 0.02           # force RMS above 5 Hz while both hold still
STIFFNESS_TOLERANCE = 0.05  # at 25 ms, of the no-delay stiffness
OBSERVER_BOUND_J = -1e-4    # the coupling observer's lowest value (one step's prediction error)
# One body, one shape: each node's field of the tail against the world server's, the largest
# difference at a vertex. At rest within FIELD_BOUND_M (about 1 % of the 4.3 mm the tail moves
# where pressed); within it one round trip after the inputs stop, give or take the sampling
# (the nodes dump every 0.1 s, the test compares every 0.1 s, a still hand's set comes every
# 0.1 s). The inputs stop when neither fingertip moves more than INPUT_STILL_M in 0.1 s.
FIELD_BOUND_M = 50e-6
FIELD_SAMPLING_S = 0.3
INPUT_STILL_M = 20e-6


def last_move(rows, t0, window):
    """The last script time in `window` at which the fingertip (z1) moved more than
    INPUT_STILL_M over the 0.1 s before (the window's start if it never did)."""
    ts = [r["t_s"] - t0 for r in rows]
    last, j = window[0], 0
    for i, t in enumerate(ts):
        while ts[j] < t - 0.1:
            j += 1
        if window[0] <= t <= window[1] and abs(rows[i]["z1"] - rows[j]["z1"]) > INPUT_STILL_M:
            last = t
    return last


def hf_rms(values, dt_s, cut_Hz=5.0):
    """RMS [N] of the part of a uniformly sampled series above cut_Hz (a straight line through it
    taken out first): from its discrete Fourier transform."""
    n = len(values)
    t = [i * dt_s for i in range(n)]
    tm, vm = sum(t) / n, sum(values) / n
    slope = sum((a - tm) * (b - vm) for a, b in zip(t, values)) / max(sum((a - tm) ** 2 for a in t), 1e-30)
    r = [b - vm - slope * (a - tm) for a, b in zip(t, values)]
    power = 0.0
    for k in range(1, n // 2 + 1):
        if k / (n * dt_s) <= cut_Hz:
            continue
        re_, im_ = 0.0, 0.0
        for i, x in enumerate(r):
            a = 2.0 * math.pi * k * i / n
            re_ += x * math.cos(a)
            im_ -= x * math.sin(a)
        w = 1.0 if 2 * k == n else 2.0  # the other half of the spectrum
        power += w * (re_ * re_ + im_ * im_) / (n * n)
    return math.sqrt(power)


def coupling_summary(log, user):
    """The figures of a haptic node's coupling-passivity exit line (None if it had no coupling)."""
    m = re.search(rf"\[haptic_node {user}\] coupling passivity: (on|off), channels (\d+), steps (\d+), held back (\d+), "
                  r"energy sent ([-\d.e+]+) J, received ([-\d.e+]+) J, observer min ([-\d.e+]+) J, "
                  r"drift max ([-\d.e+]+) mm, granted at rest ([-\d.e+]+) J in (\d+) steps", log)
    if m is None:
        return None
    keys = ("channels", "steps", "held_back", "sent_J", "received_J", "observer_min_J", "drift_max_mm",
            "granted_J", "granted_steps")
    out = {k: float(v) for k, v in zip(keys, m.groups()[1:])}
    out["on"] = m.group(1) == "on"
    return out


# The tail's published vertices: the scene mesh's, which its tetrahedral mesh keeps first.
TAIL_VERTICES = session_test.obj_vertices(os.path.join(HERE, "..", "..", "assets", "meshes", "triceratops_tail.obj"))


class FieldWatch:
    """Compares each haptic node's own field of one deformable (haptic_node --dump-deformation)
    with the world server's published field of it (world_server --dump-deformation; its
    `sent_u_W_m`, within the re-send threshold of the server's solve) while the session runs:
    the largest difference of a vertex's displacement, on this host's clock."""

    EVERY_S = 0.1  # the nodes replace their dumps at most this often

    def __init__(self, dumps, object_id, vertices):
        self.files = {who: os.path.join(d, object_id + ".json") for who, d in dumps.items()}
        self.vertices = vertices
        self.rows = []  # (monotonic s, user, divergence m, the node's largest displacement m)
        self.next = 0.0

    def poll(self):
        if time.monotonic() < self.next:
            return None
        self.next = time.monotonic() + self.EVERY_S
        server = session_test.read_json(self.files["server"])
        if server is None:
            return None
        sent = {int(k): v for k, v in server["sent_u_W_m"].items()}
        now = time.monotonic()
        for user in ("alice", "bob"):
            local = session_test.read_json(self.files[user])
            if local is None:
                continue
            mine = {int(k): v for k, v in local["u_W_m"].items() if int(k) < self.vertices}
            worst = 0.0
            for k in set(sent) | set(mine):
                a, b = sent.get(k, (0.0, 0.0, 0.0)), mine.get(k, (0.0, 0.0, 0.0))
                worst = max(worst, math.sqrt(sum((x - y) ** 2 for x, y in zip(a, b))))
            largest = max((math.sqrt(sum(x * x for x in v)) for v in mine.values()), default=0.0)
            self.rows.append((now, user, worst, largest))
        return None


def frictionless_tail(scene):
    """A scene edit (session_test.edited_assets): the triceratops tail without friction."""
    for o in scene.get("objects", []):
        if o.get("id") == "triceratops_tail":
            o["material"].pop("mu_static", None)
            o["material"].pop("mu_kinetic", None)


def measure_delayed_tail(args, net, delays_ms=DELAYS_MS, coupling="woken", one_host=False):
    """The delayed two-user press of case_delayed_tail, measured (nothing asserted but that each
    run happened): one session per one-way delay in delays_ms, the haptic nodes' coupling as
    `haptic_node --coupling` says, on net's three hosts: the world server on the first, alice and
    bob on the second (one_host) or alice there and bob on the third. Returns
    (results: a dict of figures per delay and user, forces, fields, fault causes)."""
    os.makedirs(args.work, exist_ok=True)
    os.environ["HANDSHARE_ASSETS"] = session_test.edited_assets(args.work, frictionless_tail)
    server_exe, node_exe = dinosaur_ready(args)
    results, forces, fields = [], [], []
    fault_causes = {}  # (delay, user): the node's "faulted steps by cause" line, if it had faults
    a, b, c = net.hosts
    for delay_ms in delays_ms:
        for seed, h in enumerate((a, b, c), start=1):
            h.clear_delay()
            if delay_ms > 0:
                h.delay(delay_ms, jitter_ms=0, seed=seed)
        session = f"net-delay-{delay_ms}-{os.getpid()}-{coupling}"
        common = ["--domain", args.domain, "--session", session]
        traces = {u: os.path.join(args.work, f"{u}_{delay_ms}ms.csv") for u in ("alice", "bob")}
        for f in traces.values():
            if os.path.exists(f):
                os.remove(f)
        dumps = {who: os.path.join(args.work, f"field_{delay_ms}ms", who) for who in ("server", "alice", "bob")}
        for d in dumps.values():
            shutil.rmtree(d, ignore_errors=True)
        server = a.start(f"world_server_{delay_ms}ms", [server_exe, *common, "--scene", "dinosaur",
                                                       "--dump-deformation", dumps["server"],
                                                       "--deformation-threshold", "1e-6", "--duration", 120],
                         args.work)
        watch = FieldWatch(dumps, "triceratops_tail", TAIL_VERTICES)
        nodes = {}
        try:
            server.wait_for("models of 'dinosaur' ready", 60)
            for host, user in ((b, "alice"), (b if one_host else c, "bob")):
                nodes[user] = host.start(f"{user}_{delay_ms}ms",
                                         [node_exe, *common, "--user", user, "--device", "hiro", "--script",
                                          os.path.join(DATA, f"delay_{user}.hand"), "--trace", traces[user],
                                          "--dump-deformation", dumps[user], "--coupling", coupling,
                                          "--duration", 90], args.work)
            starts = script_starts(nodes)
            for user in nodes:
                # The fields are compared while the session runs (each dump is replaced).
                session_test.wait_until(f"{user}'s trace past the still window ({delay_ms} ms)", 90,
                                        lambda u=user: watch.poll() or ((rows := session_test.read_trace(traces[u]))
                                        and rows[-1]["t_s"] - starts[u] >= STILL_WINDOW[1] + 0.2))
            stop_session(server, nodes, f" at {delay_ms} ms")
        except Failure:
            print_logs((server, *nodes.values()))
            raise
        # When the inputs stopped changing: the last moment either fingertip (the arm settling
        # after bob's last move) moved more than INPUT_STILL_M in 0.1 s, in script time.
        inputs_stop = max(last_move(session_test.read_trace(traces[u]), starts[u], (15.0, STILL_WINDOW[1]))
                          for u in ("alice", "bob"))
        for user in ("alice", "bob"):
            rows = session_test.read_trace(traces[user])
            t0 = starts[user]

            def window(w, rows=rows, t0=t0):
                sel = [r for r in rows if w[0] <= r["t_s"] - t0 < w[1]]
                check(len(sel) > 50, f"{user}'s trace has {len(sel)} rows in script time {w} at {delay_ms} ms")
                return sel

            def mean(sel, f):
                return sum(f(r) for r in sel) / len(sel)
            w3, w4 = (window(w) for w in STIFFNESS_WINDOWS[user])
            f3, f4 = mean(w3, session_test.net_fz), mean(w4, session_test.net_fz)
            z3, z4 = mean(w3, lambda r: r["z1"]), mean(w4, lambda r: r["z1"])
            check(z3 - z4 > 2e-4, f"{user}'s fingertip went {1e3 * (z3 - z4):.3f} mm deeper at {delay_ms} ms")
            still = window(STILL_WINDOW)
            dt = (still[-1]["t_s"] - still[0]["t_s"]) / (len(still) - 1)
            fz = [session_test.net_fz(r) for r in still]
            # The field comparisons on this user's script time (the trace stamps both clocks).
            offset = rows[-1]["stamp_ns"] * 1e-9 - rows[-1]["t_s"] + t0
            diffs = [(t - offset, d, big) for t, u, d, big in watch.rows if u == user]
            fields += [(delay_ms, user, t, d, big) for t, d, big in diffs]
            at_rest = [d for t, d, _ in diffs if STILL_WINDOW[0] <= t < STILL_WINDOW[1]]
            check(len(at_rest) >= 10, f"{len(at_rest)} comparisons of {user}'s field with the server's while "
                                      f"both held still at {delay_ms} ms")
            # Converged: from when on every comparison is within FIELD_BOUND_M.
            after = [(t, d) for t, d, _ in diffs if inputs_stop <= t < STILL_WINDOW[1]]
            converged = max([t for t, d in after if d > FIELD_BOUND_M], default=inputs_stop) - inputs_stop
            summary = loop_summary(nodes[user].log(), user)
            causes = re.search(rf"\[haptic_node {user}\] faulted steps by cause: (.*)", nodes[user].log())
            fault_causes[(delay_ms, user)] = causes.group(1) if causes else "no causes printed"
            passivity = coupling_summary(nodes[user].log(), user)
            check(passivity is not None, f"{user}'s node printed no coupling-passivity line at {delay_ms} ms")
            check(passivity["on"], f"{user}'s coupling-passivity controller is not on by default")
            results.append({"delay_ms": delay_ms, "user": user, "k_N_per_m": (f4 - f3) / (z3 - z4),
                            "force_N": mean(still, session_test.net_fz), "hf_rms_N": hf_rms(fz, dt),
                            "swing_N": max(fz) - min(fz), "observer_min_J": passivity["observer_min_J"],
                            "held_back": int(passivity["held_back"]), "drift_max_mm": passivity["drift_max_mm"],
                            "granted_J": passivity["granted_J"], "field_diff_rest_m": max(at_rest),
                            "field_converged_s": converged, "inputs_stop_s": inputs_stop,
                            "field_max_m": max(big for _, _, big in diffs),
                            "energy_sent_J": passivity["sent_J"], "energy_received_J": passivity["received_J"],
                            "faults": int(summary["faults"]), "rate_limited": int(summary["rate_limited"]),
                            "loop_Hz": summary["rate_Hz"], "coupling_steps": int(passivity["steps"]),
                            "channels": int(passivity["channels"])})
            forces += [(delay_ms, user, r["t_s"] - t0, session_test.net_fz(r)) for r in rows
                       if 0.0 <= r["t_s"] - t0 <= STILL_WINDOW[1]]
    return results, forces, fields, fault_causes


def case_delayed_tail(args):
    """Two users at HIRO II devices (the simulated plant: each user's fingertip a mass held at the
    scripted hand by a spring-damper, so the force each feels moves their fingertip) press the
    triceratops tail together, on three hosts with 0, 10, 25, 50 and 100 ms one-way delay on what
    arrives at each. Each presses 1 mm deeper in turn while the other holds still, then both hold.
    Asserted at every delay: each haptic loop stays stable (force RMS above 5 Hz under HF_LIMIT_N
    while both hold, no safety faults) and the coupling's passivity observer never falls below
    its bound; at 25 ms the stiffness each user feels (force change over fingertip depth change)
    is within STIFFNESS_TOLERANCE of the no-delay value. One body, one shape: each node's own
    field of the tail (haptic_node --dump-deformation) is within FIELD_BOUND_M of the world
    server's while both hold still, and came within it one round trip (plus the sampling) after
    the inputs stopped. Writes delayed_tail.csv (the figures), delayed_tail_forces.csv (each
    user's force through the run) and delayed_tail_field.csv (each comparison) to --work.
    The tail is frictionless here whatever the scene file says: with friction on it (tried,
    docs/scenes.md) the stiffness a user feels depends on where each patch stuck and whether it
    slipped as the other hand pressed, which changed from session to session at any delay
    (alice 92-167 N/m in one run's five sessions, at 0 ms too), so it would not isolate what the
    delay does. Friction across a delay is TailFriction's, in one process."""
    with Network(3, nfq_delay=args.nfq_delay) as net:
        results, forces, fields, fault_causes = measure_delayed_tail(args, net)
    columns = list(results[0].keys())
    with open(os.path.join(args.work, "delayed_tail.csv"), "w") as f:
        f.write(",".join(columns) + "\n")
        for r in results:
            f.write(",".join(f"{r[c]:.6g}" if isinstance(r[c], float) else str(r[c]) for c in columns) + "\n")
    with open(os.path.join(args.work, "delayed_tail_forces.csv"), "w") as f:
        f.write("delay_ms,user,t_s,fz_N\n")
        for d, u, t, v in forces:
            f.write(f"{d},{u},{t:.4f},{v:.6f}\n")
    with open(os.path.join(args.work, "delayed_tail_field.csv"), "w") as f:
        f.write("delay_ms,user,t_s,divergence_m,largest_m\n")
        for d, u, t, div, big in fields:
            f.write(f"{d},{u},{t:.3f},{div:.4e},{big:.4e}\n")
    k0 = {r["user"]: r["k_N_per_m"] for r in results if r["delay_ms"] == 0}
    print("delayed tail: alice and bob at simulated HIRO IIs press the tail on three hosts; one-way delay on arrival at each")
    print("  delay user   stiffness [N/m] (vs 0 ms)  force [N]  RMS > 5 Hz [N]  observer min [J]  held back  drift [mm]  "
          "granted [J]  field vs server at rest [um]                      faults")
    for r in results:
        print(f"  {r['delay_ms']:4d}  {r['user']:6s} {r['k_N_per_m']:9.1f} ({100 * (r['k_N_per_m'] / k0[r['user']] - 1):+5.1f} %)"
              f"      {r['force_N']:7.3f}   {r['hf_rms_N']:.5f}         {r['observer_min_J']:+.2e}        "
              f"{r['held_back']:6d}   {r['drift_max_mm']:.3f}       {r['granted_J']:.2e}    "
              f"{1e6 * r['field_diff_rest_m']:6.1f} of {1e6 * r['field_max_m']:6.0f}, converged "
              f"{r['field_converged_s']:.2f} s after {r['inputs_stop_s']:.2f} s     {r['faults']}")
    for r in results:
        what = f"{r['user']} at {r['delay_ms']} ms"
        check(r["hf_rms_N"] < HF_LIMIT_N, f"{what}: force RMS above 5 Hz {r['hf_rms_N']:.4f} N (>= {HF_LIMIT_N} N)")
        check(r["faults"] == 0, f"{what}: {r['faults']} safety faults ({fault_causes[(r['delay_ms'], r['user'])]})")
        check(r["observer_min_J"] >= OBSERVER_BOUND_J,
              f"{what}: the coupling observer fell to {r['observer_min_J']:.3e} J (< {OBSERVER_BOUND_J} J)")
        check(r["k_N_per_m"] > 0.0, f"{what}: stiffness {r['k_N_per_m']:.1f} N/m")
        check(r["field_diff_rest_m"] <= FIELD_BOUND_M,
              f"{what}: the node's field of the tail is {1e6 * r['field_diff_rest_m']:.1f} um off the server's at rest "
              f"(> {1e6 * FIELD_BOUND_M:.0f} um)")
        rule = 2e-3 * r["delay_ms"] + FIELD_SAMPLING_S
        check(r["field_converged_s"] <= rule,
              f"{what}: the node's field came within {1e6 * FIELD_BOUND_M:.0f} um of the server's "
              f"{r['field_converged_s']:.2f} s after the inputs stopped (> one round trip + {FIELD_SAMPLING_S} s)")
        if r["delay_ms"] == 25:
            change = r["k_N_per_m"] / k0[r["user"]] - 1.0
            check(abs(change) <= STIFFNESS_TOLERANCE,
                  f"{what}: stiffness {r['k_N_per_m']:.1f} N/m is {100 * change:+.1f} % of the no-delay "
                  f"{k0[r['user']]:.1f} N/m (> {100 * STIFFNESS_TOLERANCE:.0f} %)")


HANDOVER_DELAY_MS = 50
HANDOVER_HOLD_M = 2e-3    # the ball's largest distance from where alice held it until bob's node has it
HANDOVER_BOUND_M = 5e-3   # ... and until bob lifts it (his grip settles it by its own sag)
WEIGHT_TOLERANCE = 0.05   # bob's held weight, of m g


def read_poses(path, object_id):
    """The world server's --pose-trace rows of one body: (steady s, owner, position, speed)."""
    rows = []
    try:
        with open(path) as f:
            lines = f.read().split("\n")
    except FileNotFoundError:
        return rows
    for line in lines[1:-1]:
        c = line.split(",")
        if len(c) == 9 and c[1] == object_id:
            v = [float(x) for x in c[6:9]]
            rows.append((int(c[0]) * 1e-9, c[2], [float(x) for x in c[3:6]], math.sqrt(sum(x * x for x in v))))
    return rows


def measure_handover(args, net, delay_ms=HANDOVER_DELAY_MS, coupling="woken"):
    """case_handover's session on net's three hosts with delay_ms one-way on arrival at each and
    the haptic nodes' coupling as `haptic_node --coupling` says; returns its figures (times from
    the moment alice's hand began to open, distances from where she held the ball). Asserts only
    that the session ran."""
    os.makedirs(args.work, exist_ok=True)
    server_exe, node_exe = exe(args.bin_dir, "world_server"), exe(args.bin_dir, "haptic_node")
    ball = session_test.scene_object("solar_system", "ball")
    session = f"net-handover-{os.getpid()}-{delay_ms}-{coupling}"
    common = ["--domain", args.domain, "--session", session]
    poses_csv = os.path.join(args.work, "handover_poses.csv")
    traces = {u: os.path.join(args.work, f"handover_{u}.csv") for u in ("alice", "bob")}
    for f in (poses_csv, *traces.values()):
        if os.path.exists(f):
            os.remove(f)
    a, b, c = net.hosts
    for seed, h in enumerate((a, b, c), start=1):
        h.clear_delay()
        if delay_ms > 0:
            h.delay(delay_ms, jitter_ms=0, seed=seed)
    server = a.start("world_server", [server_exe, *common, "--scene", "solar_system", "--pose-trace", poses_csv,
                                      "--duration", 120], args.work)
    nodes = {}
    try:
        server.wait_for("models of 'solar_system' ready", 60)
        for host, user in ((b, "alice"), (c, "bob")):
            nodes[user] = host.start(user, [node_exe, *common, "--user", user, "--device", "sim", "--script",
                                            os.path.join(DATA, f"handover_{user}.hand"), "--trace", traces[user],
                                            "--coupling", coupling, "--duration", 90], args.work)
        starts = script_starts(nodes)
        server.wait_for("object 'ball': owner '' -> 'alice' (granted)", 30)
        t_handed = server.wait_for("object 'ball': owner 'alice' -> 'bob'", 60)
        session_test.wait_until("bob's trace past his lift", 60,
                                lambda: (rows := session_test.read_trace(traces["bob"]))
                                and rows[-1]["t_s"] - starts["bob"] >= 17.6)
        hold_line = re.search(r"let go of 'ball' while 'bob' grasps it", nodes["alice"].log())
        stop_session(server, nodes)
    except Failure:
        print_logs((server, *nodes.values()))
        raise
    ws_log = server.log()
    reason = re.search(r"object 'ball': owner 'alice' -> 'bob' \((\w+)\)", ws_log).group(1)
    rows = {u: session_test.read_trace(traces[u]) for u in ("alice", "bob")}

    def steady(user, script_s):
        """A moment of a user's script on the hosts' steady clock (the trace stamps both)."""
        last = rows[user][-1]
        return last["stamp_ns"] * 1e-9 - last["t_s"] + starts[user] + script_s
    poses = read_poses(poses_csv, "ball")
    t_release, t_lift, t_lifted = steady("alice", 9.5), steady("bob", 14.0), steady("bob", 16.0)
    held = [p for t, o, p, _ in poses if steady("alice", 8.5) <= t < t_release and o == "alice"]
    check(len(held) >= 3, f"{len(held)} poses of the ball held by alice in the second before she let go")
    p_held = [sum(p[k] for p in held) / len(held) for k in range(3)]
    check(p_held[2] > ball["position_m"][2] + 0.04, f"alice held the ball at z = {p_held[2]:.4f} m: not lifted 5 cm")
    through = [(t, o, p, v) for t, o, p, v in poses if t_release <= t < t_lift]
    check(through and through[-1][1] == "bob", "the ball was not bob's before he lifted it")
    far = max(through, key=lambda r: math.dist(r[2], p_held))
    # Until bob's node can have it (the hand-over plus a round trip), the ball is alice's node's
    # or the server's to keep where her hand left it.
    t_bob = t_handed + 2e-3 * delay_ms
    hold_far = max(math.dist(p, p_held) for t, _, p, _ in through if t < t_bob)
    # The energy the hand-over carries into bob's node: the state the server first publishes as
    # his (his node cannot have simulated the body before it gets that state, and starts from it).
    handed = [v for _, o, _, v in through if o == "bob"]
    handed_speed = handed[0]
    fastest = max(v for _, _, _, v in through)
    lifted = [p for t, o, p, _ in poses if t >= t_lifted and o == "bob"]
    check(len(lifted) >= 3, f"{len(lifted)} poses of the ball after bob lifted it")
    rise = sum(p[2] for p in lifted) / len(lifted) - p_held[2]
    # bob's weight: his loop's impulse from 0.5 s after the hand-over to his lift.
    w0, w1 = t_handed + 0.5, t_lift - 0.2
    sel = [r for r in rows["bob"] if w0 <= r["stamp_ns"] * 1e-9 < w1]
    check(len(sel) > 50 and sel[-1]["t_s"] - sel[0]["t_s"] >= 1.0,
          f"bob's trace has {len(sel)} rows between the hand-over and his lift")
    weight = -(session_test.net_jz(sel[-1]) - session_test.net_jz(sel[0])) / (sel[-1]["t_s"] - sel[0]["t_s"])
    mg = ball["mass_kg"] * 1.62
    with open(poses_csv + ".tmp", "w") as f:
        f.write("t_s,owner,x_m,y_m,z_m,speed_m_per_s\n")
        for t, o, p, v in poses:
            f.write(f"{t - t_release:.4f},{o},{p[0]:.6f},{p[1]:.6f},{p[2]:.6f},{v:.5f}\n")
    os.replace(poses_csv + ".tmp", poses_csv)
    return {"ball": ball, "p_held": p_held, "hold_line": hold_line, "t_handed_s": t_handed - t_release,
            "t_bob_s": t_bob - t_release, "t_lift_s": t_lift - t_release, "hold_far_m": hold_far, "handed_speed": handed_speed,
            "far_m": math.dist(far[2], p_held), "far_owner": far[1], "far_t_s": far[0] - t_release,
            "fastest": fastest, "weight_N": weight, "mg_N": mg, "rise_m": rise, "reason": reason}


def case_handover(args):
    """A body handed from one owner to another across a 50 ms one-way delay (three hosts: world
    server; alice; bob). On the Moon alice lifts the ball 5 cm and holds it; bob's hand grasps it
    there too; alice lets go. The world server hands it to bob after its release grace, and bob's
    node simulates it from when that reaches it: a round trip and more after alice's hand opened.
    Asserted: the hand-over happened (alice -> bob, handed_over); until bob's node can have the
    ball (the hand-over plus a round trip) every pose the server published stays within
    HANDOVER_HOLD_M of where alice held it (remote hands put no force on a rigid body: unheld, it
    would fall out of bob's fingers meanwhile), and the first state published as bob's is at rest
    (the hand-over carries no kinetic energy into bob's node); until bob lifts, within
    HANDOVER_BOUND_M (his grip settles it); bob's hand then carries its weight (m g within
    WEIGHT_TOLERANCE, from his loop's impulse) and lifts it 3 cm. Writes handover_poses.csv (the
    ball's published poses) to --work."""
    with Network(3, nfq_delay=args.nfq_delay) as net:
        m = measure_handover(args, net)
    ball, p_held, mg, weight, rise = m["ball"], m["p_held"], m["mg_N"], m["weight_N"], m["rise_m"]
    print(f"hand-over: alice -> bob on three hosts, {HANDOVER_DELAY_MS} ms one-way on arrival at each, the Moon's ball")
    print(f"  alice held it at z = {p_held[2]:.4f} m and let go (her node {'held it still for bob' if m['hold_line'] else 'did not hold it'}); "
          f"the server handed it over ({m['reason']}) {m['t_handed_s']:.2f} s after her hand began to open")
    print(f"  until bob's node had it ({m['t_bob_s']:.2f} s): farthest {1e3 * m['hold_far_m']:.2f} mm from where alice held it; "
          f"first published as bob's at {m['handed_speed']:.2e} m/s ({0.5 * ball['mass_kg'] * m['handed_speed'] ** 2:.1e} J of "
          f"kinetic energy handed over)")
    print(f"  until bob lifted it ({m['t_lift_s']:.2f} s): farthest {1e3 * m['far_m']:.2f} mm from where "
          f"alice held it ({m['far_owner']}'s pose at {m['far_t_s']:.2f} s), fastest {m['fastest']:.3f} m/s")
    print(f"  bob's hand held {weight:.4f} N (m g = {mg:.4f} N) and lifted it {1e3 * rise:.1f} mm (his hand: 30 mm)")
    check(m["reason"] == "handed_over", f"the ball went from alice to bob by '{m['reason']}', not a hand-over")
    check(m["hold_far_m"] <= HANDOVER_HOLD_M,
          f"before bob's node had the ball it went {1e3 * m['hold_far_m']:.2f} mm from where alice held it "
          f"(> {1e3 * HANDOVER_HOLD_M:.0f} mm): it fell")
    check(m["handed_speed"] <= 1e-6, f"the ball was handed over moving at {m['handed_speed']:.4f} m/s, not at rest")
    check(m["far_m"] <= HANDOVER_BOUND_M,
          f"through the hand-over the ball went {1e3 * m['far_m']:.1f} mm from where alice held it "
          f"(> {1e3 * HANDOVER_BOUND_M:.0f} mm; {m['far_owner']}'s pose {m['far_t_s']:.2f} s after she let go)")
    check(abs(weight - mg) <= WEIGHT_TOLERANCE * mg, f"bob's hand held {weight:.4f} N, not the ball's {mg:.4f} N")
    check(abs(rise - 0.03) <= HANDOVER_BOUND_M, f"bob's lift moved the ball {1e3 * rise:.1f} mm, not his hand's 30 mm")


if __name__ == "__main__":
    main({"two_hosts": case_two_hosts, "partitioned_user": case_partitioned_user, "tour": case_tour,
          "unicast_peers": case_unicast_peers, "late_joiners_unicast": case_late_joiners_unicast,
          "delayed_tail": case_delayed_tail, "handover": case_handover},
         failures=(session_test.Failure,))
