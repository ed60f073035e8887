#!/usr/bin/env python3
"""Smoke tests of handshare over a real (impaired) network: the executables in separate network
namespaces, so Fast DDS talks UDP over veth and a bridge, not shared memory.

usage: net_dds_test.py two_hosts|unicast_peers|late_joiners_unicast --bin-dir DIR --nfq-delay PATH --domain D
                      --work DIR
"""
import os
import re
import subprocess
import sys
import time

HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, HERE)
from netharness import Network, Failure, check, main  # noqa: E402

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


def case_late_joiners_unicast(args):
    """tests/late_join_test.py's late joiners across a network without multicast: the world
    server on one host, the scripted hand on another, the late spectator and audio guide on a
    third; every node with --peers, multicast dropped on arrival at every host, 10 ms +- 2 ms
    and 1 % loss on what arrives at each host."""
    sys.path.insert(0, os.path.join(HERE, ".."))
    import late_join_test  # noqa: E402
    os.makedirs(args.work, exist_ok=True)
    for entry in os.listdir(args.work):  # a rerun starts clean (the waits read files); the cache stays
        if entry != "cache":
            path = os.path.join(args.work, entry)
            subprocess.run(["rm", "-rf", path], check=True)
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


if __name__ == "__main__":
    main({"two_hosts": case_two_hosts, "unicast_peers": case_unicast_peers,
          "late_joiners_unicast": case_late_joiners_unicast})
