#!/usr/bin/env python3
"""QoS before and after, measured on an impaired link between two network namespaces.

usage: qos_measure.py --bin-dir BUILD --nfq-delay PATH [--domain 170] [--work DIR]
                      [--cases event,field_tail,field_max,contact] [--runs 1]
                      [--before tests/net/data/qos_before.xml] [--after deploy/qos/handshare_qos.xml]

Each case runs tests/tools/qos_probe (build/tests/qos_probe) as publisher on host A and
subscriber on host B, once with each QoS file, and prints one table (docs/network.md, "QoS tuned
to the network"). Both hosts get 20 ms +- 5 ms (normal, sd 5 ms, in order) of delay on arrival, and loss
on arrival drawn per IP packet, before the kernel reassembles fragments (a chain at priority
-450 in prerouting), as a real link loses packets: a 65 kB UDP datagram is 45 IP packets, and
losing any one loses the datagram.

  event       ControlEvent, reliable keep-all, 10 Hz, 300 samples, 2 % loss: delivery latency.
  field_tail  Deformation of the triceratops tail's 962 nodes (15.5 kB), 60 Hz, 600, 1 % loss.
  field_max   Deformation of 4096 nodes (65.7 kB, the IDL's largest), 60 Hz, 600, 1 % loss.
  contact     ContactSet at 1 kHz (10000) while 4096-node fields go at 60 Hz from the same
              participant, over a 100 Mbit/s link (tbf on A's egress), 2 % loss.
  contact_link  the same over the 100 Mbit/s link alone: no delay, no loss.

Needs root (namespaces, nft, tc); without it, exits 77 with SKIP. Not a ctest test: it measures,
it asserts nothing but that every run produced its figures.
"""
import argparse
import multiprocessing
import os
import re
import subprocess
import sys

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from netharness import Failure, Network, Skip, SKIP_RETURN_CODE  # noqa: E402

ROOT = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))

# name: (probe case, rate Hz, count, nodes, field rate Hz, loss %, delay ms, link Mbit/s or None,
#        within ms)
CASES = {
    "event": ("event", 10, 300, 962, 0, 2.0, 20, None, 100),
    "field_tail": ("field", 60, 600, 962, 0, 1.0, 20, None, 100),
    "field_max": ("field", 60, 600, 4096, 0, 1.0, 20, None, 100),
    "contact": ("contact", 1000, 10000, 4096, 60, 2.0, 20, 100, 30),
    # The link alone (no delay, no loss): what the fields' bursts do to the contact sets' queue.
    "contact_link": ("contact", 1000, 10000, 4096, 60, 0.0, 0, 100, 5),
}


def packet_loss(host, percent):
    """Drops `percent` % of arriving IPv4 UDP packets, IP fragments one by one (before reassembly)."""
    host.nft(f"""table ip hsqos {{
  counter ip_in {{ }}
  counter ip_dropped {{ }}
  chain pre {{ type filter hook prerouting priority -450;
    ip protocol udp counter name ip_in
    ip protocol udp numgen random mod 10000 < {round(percent * 100)} counter name ip_dropped drop
  }}
}}
""")


def nft_counters(host, table):
    import json
    r = host.run(["nft", "-j", "list", "counters", "table", "ip", table])
    return {i["counter"]["name"]: i["counter"]["packets"] for i in json.loads(r.stdout)["nftables"] if "counter" in i}


def uptime():
    return subprocess.run(["uptime"], capture_output=True, text=True).stdout.strip()


def run_one(args, name, label, qos_file, domain, seed):
    case, rate, count, nodes, field_rate, loss, delay_ms, link, within = CASES[name]
    count = max(10, int(count * args.scale))
    probe = os.path.join(args.bin_dir, "tests", "qos_probe")
    work = os.path.join(args.work, f"{name}_{label}_{domain}")
    os.makedirs(work, exist_ok=True)
    duration = count / rate + 20  # the subscriber gives up 20 s after the last sample was due
    with Network(hosts=2, nfq_delay=args.nfq_delay) as net:
        a, b = net.hosts
        for k, h in enumerate((a, b)):
            packet_loss(h, loss)
            if delay_ms == 0:
                continue
            # FIFO: the delayer's normal jitter (sd 5 ms) reorders a 1 kHz stream's packets, and a
            # best-effort reader drops every sample older than one it has (most of them), which a
            # real link with 5 ms of jitter does not do to packets of one flow.
            h.delay(delay_ms, jitter_ms=5, seed=seed + k, reorder=False)
        if link:
            # The sender's link: a token bucket at `link` Mbit/s on A's egress (the kernel has tbf).
            a.run(["tc", "qdisc", "add", "dev", a.ifname, "root", "tbf", "rate", f"{link}mbit", "burst", "16kb",
                   "latency", "200ms"])
        common = ["--domain", domain, "--session", "qos", "--qos", qos_file, "--case", case, "--count", count]
        sub = b.start("sub", [probe, "--role", "sub", *common, "--duration", duration, "--within-ms", within], work)
        sub.wait_for("ready", timeout=30)
        pub = a.start("pub", [probe, "--role", "pub", *common, "--rate", rate, "--nodes", nodes, "--field-rate",
                              field_rate, "--linger", 10], work)
        pub.wait_for("matched", timeout=60)
        pub.wait_for(re.compile(r"sent \d+"), timeout=count / rate * 3 + 60)
        rc = sub.wait(timeout=duration + 30)
        if rc != 0:
            raise Failure(f"{name}/{label}: subscriber rc {rc}:\n{sub.log()}")
        m = re.search(r"result .*", sub.log())
        if not m:
            raise Failure(f"{name}/{label}: no result line:\n{sub.log()}")
        res = dict(kv.split("=", 1) for kv in m.group(0).split()[1:])
        res["ip_in_B"] = nft_counters(b, "hsqos").get("ip_in", 0)
        res["udp_datagrams_B"] = b.counters().get("udp_in", 0)
        sent = re.search(r"sent (\d+) in ([\d.]+) s", pub.log())
        res["sent"] = sent.group(1) if sent else "?"
        pub.stop()
        d = b.clear_delay() or {}
        a.clear_delay()
        res["delayer_B"] = (f"{d['accepted']}/{d['received']} passed, release late mean {d['late_mean_us']} us "
                            f"max {d['late_max_us']} us" if "accepted" in d else "none")
    return res


def _child(queue, args, name, label, qos_file, domain, seed):
    try:
        queue.put(("ok", run_one(args, name, label, qos_file, domain, seed)))
    except Skip as e:
        queue.put(("skip", str(e)))
    except Exception as e:  # Failure, or a bug: the parent reports it
        queue.put(("fail", f"{type(e).__name__}: {e}"))


def run_isolated(args, name, label, qos_file, domain, seed):
    """run_one in a child process: the harness allows 9 networks per process, and a child also
    leaves nothing of one run's state to the next."""
    ctx = multiprocessing.get_context("fork")
    queue = ctx.Queue()
    p = ctx.Process(target=_child, args=(queue, args, name, label, qos_file, domain, seed))
    p.start()
    kind, value = queue.get()
    p.join()
    if kind == "skip":
        raise Skip(value)
    if kind == "fail":
        raise Failure(f"{name}/{label}: {value}")
    return value


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--bin-dir", required=True)
    ap.add_argument("--nfq-delay", required=True)
    ap.add_argument("--domain", type=int, default=170)
    ap.add_argument("--work", default="/tmp/qos_measure")
    ap.add_argument("--cases", default=",".join(CASES))
    ap.add_argument("--runs", type=int, default=1)
    ap.add_argument("--scale", type=float, default=1.0, help="multiply every case's sample count (quick checks)")
    ap.add_argument("--before", default=os.path.join(ROOT, "tests/net/data/qos_before.xml"))
    ap.add_argument("--after", default=os.path.join(ROOT, "deploy/qos/handshare_qos.xml"))
    ap.add_argument("--also", action="append", default=[], metavar="LABEL=FILE",
                    help="another QoS file to measure (a variant of the settings)")
    args = ap.parse_args()
    configs = [("before", args.before), ("after", args.after)] + [tuple(a.split("=", 1)) for a in args.also]
    rows = []
    print(f"load before: {uptime()}", flush=True)
    domain = args.domain
    try:
        for name in args.cases.split(","):
            for run in range(args.runs):
                for label, qos in configs:
                    res = run_isolated(args, name, label, qos, domain, seed=11 + 2 * run)
                    rows.append((name, label, res))
                    print(f"{name:10s} {label:6s} {res}", flush=True)
    except Skip as e:
        print(f"SKIP: {e}", flush=True)
        sys.exit(SKIP_RETURN_CODE)
    except Failure as e:
        print(f"FAIL: {e}", flush=True)
        sys.exit(1)
    print(f"load after: {uptime()}")
    print()
    print("| case | QoS | received | within | p50 ms | p99 ms | max ms | IP packets in at B | UDP datagrams in at B | B's delayer |")
    print("|---|---|---|---|---|---|---|---|---|---|")
    for name, label, r in rows:
        print(f"| {name} | {label} | {r['received']}/{r['expected']} | {r['within']} (<= {r['within_ms']} ms) | "
              f"{r['p50_ms']} | {r['p99_ms']} | {r['max_ms']} | {r['ip_in_B']} | {r['udp_datagrams_B']} | {r['delayer_B']} |")


if __name__ == "__main__":
    main()
