"""netharness: a small network of "hosts" (network namespaces on a bridge) for cross-process tests.

    with Network(hosts=2, nfq_delay=path) as net:      # or Skip is raised: see main()
        a, b = net.hosts                                 # a.ns, a.addr ("10.x.0.1"), a.ifname ("eth0")
        b.loss(2)                                        # drop 2% of UDP datagrams arriving at b
        b.delay(20, jitter_ms=5, seed=1)                 # arriving at b: 20 ms +- 5 ms (sd)
        p = b.start("srv", [exe, ...], log_dir)           # a process in b, output in log_dir/srv.log
        p.wait_for("text", timeout=10)                   # monotonic time of the line, or Failure
        b.partition(); b.heal()                          # all UDP into b dropped / restored
        b.drop_multicast()                               # no multicast arrives at b (for good)
        net.isolate(a); net.heal_all()                   # a cut off from everyone, both ways
        stats = b.clear_delay()                          # the delayer's counters

Impairments act on the host's INPUT hook (what arrives at the host), in that host's namespace,
in an nft table `inet hsnet` with chains: partition (priority -30), loss (-20), delay (-10, an
NFQUEUE rule `queue num Q bypass` served by nfq_delay, or netem on the bridge port where the
kernel has sch_netem), and counters (-40). IP fragments are reassembled before the INPUT hook,
so loss there drops whole datagrams.

Cleanup is always done: on leaving the `with` block, at exit, on SIGINT/SIGTERM/SIGHUP; and a
new Network first removes namespaces, links and processes left by a crashed earlier run (names
hsn<pid>n<i>..., where <pid> is no longer alive). Python 3 stdlib only.
"""
import atexit
import json
import math
import os
import re
import shutil
import signal
import subprocess
import sys
import time

PREFIX = "hsn"
SKIP_RETURN_CODE = 77
TABLE = "hsnet"


class Skip(Exception):
    """The machine cannot run this test (not root, no namespaces, no nftables, no NFQUEUE)."""


class Failure(Exception):
    pass


def check(cond, what):
    if not cond:
        raise Failure(what)


def _run(cmd, input=None, check_rc=True, timeout=30):
    r = subprocess.run(cmd, input=input, capture_output=True, text=True, timeout=timeout)
    if check_rc and r.returncode != 0:
        raise RuntimeError(f"{' '.join(cmd)}: rc {r.returncode}: {r.stderr.strip()}")
    return r


def _pid_alive(pid):
    try:
        os.kill(pid, 0)
    except ProcessLookupError:
        return False
    except PermissionError:
        return True
    return True


def _netem_works():
    """True when `tc qdisc add ... netem` works (not on this project's usual kernel)."""
    if not shutil.which("tc"):
        return False
    ns = f"{PREFIX}{os.getpid()}probe"
    try:
        _run(["ip", "netns", "add", ns])
        _run(["ip", "-n", ns, "link", "set", "lo", "up"])
        r = _run(["ip", "netns", "exec", ns, "tc", "qdisc", "add", "dev", "lo", "root", "netem", "delay", "1ms"],
                 check_rc=False)
        return r.returncode == 0
    except Exception:
        return False
    finally:
        _run(["ip", "netns", "del", ns], check_rc=False)


def cleanup_stale():
    """Removes namespaces, links and processes of harness runs whose process is gone."""
    pat = re.compile(rf"^{PREFIX}(\d+)")
    removed = []
    r = _run(["ip", "netns", "list"], check_rc=False)
    for line in r.stdout.splitlines():
        name = line.split()[0] if line.split() else ""
        m = pat.match(name)
        if m and not _pid_alive(int(m.group(1))):
            pids = _run(["ip", "netns", "pids", name], check_rc=False).stdout.split()
            for p in pids:  # processes an earlier, crashed run started in its own namespace
                try:
                    os.kill(int(p), signal.SIGKILL)
                except (ProcessLookupError, ValueError):
                    pass
            _run(["ip", "netns", "del", name], check_rc=False)
            removed.append(name)
    r = _run(["ip", "-o", "link", "show"], check_rc=False)
    for line in r.stdout.splitlines():
        parts = line.split(":")
        if len(parts) < 2:
            continue
        name = parts[1].strip().split("@")[0]
        m = pat.match(name)
        if m and not _pid_alive(int(m.group(1))):
            _run(["ip", "link", "del", name], check_rc=False)
            removed.append(name)
    return removed


def require_root_tools():
    if os.geteuid() != 0:
        raise Skip("needs root (network namespaces, veth, bridge, nftables)")
    for tool in ("ip", "nft"):
        if not shutil.which(tool):
            raise Skip(f"'{tool}' not found (Debian packages iproute2, nftables)")


class Proc:
    """A process started in a host; its output goes to a log file."""

    def __init__(self, host, label, cmd, log_path, env=None):
        self.host, self.label, self.log_path = host, label, log_path
        self.log_file = open(log_path, "w")
        self.started = time.monotonic()
        self.popen = subprocess.Popen(["ip", "netns", "exec", host.ns, *map(str, cmd)], stdout=self.log_file,
                                      stderr=subprocess.STDOUT, env=env, start_new_session=True)

    def log(self):
        if not self.log_file.closed:
            self.log_file.flush()
        with open(self.log_path, errors="replace") as f:
            return f.read()

    def wait_for(self, text, timeout, count=1):
        """Monotonic time when `text` (a string, or a compiled regex) appeared in the output for
        the `count`th time (polled every 10 ms)."""
        end = time.monotonic() + timeout
        if isinstance(text, re.Pattern):
            found = lambda log: len(text.findall(log)) >= count  # noqa: E731
        else:
            found = lambda log: log.count(text) >= count  # noqa: E731
        while True:
            if found(self.log()):
                return time.monotonic()
            if self.popen.poll() is not None and not found(self.log()):
                raise Failure(f"{self.label} ended (rc {self.popen.returncode}) without '{text}' x{count}:\n{self.log()}")
            if time.monotonic() > end:
                raise Failure(f"'{text}' x{count} not in {self.label}'s output within {timeout} s:\n{self.log()}")
            time.sleep(0.01)

    def wait(self, timeout):
        try:
            return self.popen.wait(timeout=timeout)
        except subprocess.TimeoutExpired:
            raise Failure(f"{self.label} did not end within {timeout} s")

    def stop(self, sig=signal.SIGTERM, timeout=5):
        if self.popen.poll() is None:
            try:
                self.popen.send_signal(sig)
                self.popen.wait(timeout=timeout)
            except subprocess.TimeoutExpired:
                self.popen.kill()
                self.popen.wait()
        if not self.log_file.closed:
            self.log_file.close()
        return self.popen.returncode


class Host:
    def __init__(self, net, index, ns, addr, ifname, bridge_port):
        self.net, self.index, self.ns, self.addr, self.ifname = net, index, ns, addr, ifname
        self.bridge_port = bridge_port
        self.procs = []
        self.delayer = None  # (Popen, queue) or "netem"
        self.queue_rule = None  # "nft" (queue expression) or "xt" (iptables-nft NFQUEUE target)

    def __repr__(self):
        return f"Host({self.ns}, {self.addr})"

    def nft(self, script):
        r = _run(["ip", "netns", "exec", self.ns, "nft", "-f", "-"], input=script, check_rc=False)
        if r.returncode != 0:
            raise RuntimeError(f"nft in {self.ns}: {r.stderr.strip()}\n{script}")

    def run(self, cmd, timeout=60, check_rc=True):
        """Runs a command in this host and waits: CompletedProcess (text stdout/stderr)."""
        r = subprocess.run(["ip", "netns", "exec", self.ns, *map(str, cmd)], capture_output=True, text=True,
                           timeout=timeout)
        if check_rc and r.returncode != 0:
            raise Failure(f"{cmd} in {self.ns}: rc {r.returncode}\n{r.stdout}\n{r.stderr}")
        return r

    def start(self, label, cmd, log_dir, env=None):
        p = Proc(self, label, cmd, os.path.join(log_dir, label + ".log"), env)
        self.procs.append(p)
        self.net._started_any = True
        return p

    # --- impairments on what arrives at this host ------------------------------------------------
    def loss(self, percent):
        """Drops `percent` % of arriving UDP datagrams (nft numgen, 0.01 % steps); 0 removes it."""
        rule = ""
        if percent > 0:
            rule = f"add rule inet {TABLE} loss meta l4proto udp numgen random mod 10000 < {round(percent * 100)} drop\n"
        self.nft(f"flush chain inet {TABLE} loss\n{rule}")

    def partition(self, from_hosts=None):
        """Drops all arriving UDP (or only from `from_hosts`) until heal()."""
        if from_hosts is None:
            self.nft(f"add rule inet {TABLE} partition meta l4proto udp drop\n")
        else:
            addrs = ", ".join(h.addr for h in from_hosts)
            self.nft(f"add rule inet {TABLE} partition ip saddr {{ {addrs} }} meta l4proto udp drop\n")

    def heal(self):
        self.nft(f"flush chain inet {TABLE} partition\n")

    def drop_multicast(self):
        """Drops every arriving multicast datagram (a network without multicast), for good:
        chain `multicast` (priority -35, after the counters, untouched by heal())."""
        self.nft(f"add chain inet {TABLE} multicast {{ type filter hook input priority -35; }}\n"
                 f"add rule inet {TABLE} multicast ip daddr 224.0.0.0/4 drop\n")

    def delay(self, ms, jitter_ms=0.0, seed=1, reorder=True, dist="normal", loss_percent=0.0, queue=0,
              force_nfq=False, rt_priority=50):
        """Delays arriving UDP by ms (+ jitter: normal sd, or uniform +-), optionally reordering."""
        self.clear_delay()
        if self.net.netem and not force_nfq:
            # netem on the bridge port's egress = this host's ingress.
            args = ["delay", f"{ms}ms"]
            if jitter_ms > 0:
                args += [f"{jitter_ms}ms", "distribution", dist]
            if loss_percent > 0:
                args += ["loss", f"{loss_percent}%"]
            _run(["tc", "qdisc", "replace", "dev", self.bridge_port, "root", "netem", *args])
            self.delayer = "netem"
            return None
        exe = self.net.nfq_delay
        if not exe or not os.access(exe, os.X_OK):
            raise Skip(f"no sch_netem in this kernel and nfq_delay not built ({exe!r}; needs libnetfilter-queue-dev)")
        cmd = [exe, "--queue", queue, "--delay-ms", ms, "--jitter-ms", jitter_ms, "--seed", seed, "--dist", dist,
               "--loss-percent", loss_percent, "--rt-priority", rt_priority]
        if not reorder:
            cmd.append("--no-reorder")
        p = subprocess.Popen(["ip", "netns", "exec", self.ns, *map(str, cmd)], stdout=subprocess.PIPE,
                             stderr=subprocess.STDOUT, text=True, start_new_session=True)
        line = p.stdout.readline()  # its first line says ready, or why not
        if "ready" not in line:
            p.wait(timeout=5)
            rest = p.stdout.read()
            raise Skip(f"nfq_delay cannot serve queue {queue} in {self.ns}: {(line + rest).strip()}")
        self.delayer = (p, queue)
        # bypass: if the delayer dies, packets pass instead of being dropped.
        try:
            self.nft(f"add rule inet {TABLE} delay meta l4proto udp queue num {queue} bypass\n")
            self.queue_rule = "nft"
        except RuntimeError as e:
            # Kernels without CONFIG_NFT_QUEUE (this project's VMs) still have the xtables NFQUEUE
            # target through nft_compat: iptables-nft puts it in `ip filter INPUT` (priority 0,
            # after this harness's partition and loss chains).
            if not shutil.which("iptables"):
                self.clear_delay()
                raise Skip(f"no nft queue expression in this kernel ({e.args[0].splitlines()[0]}) and no iptables "
                           "(Debian package iptables) for the xt NFQUEUE target")
            r = _run(["ip", "netns", "exec", self.ns, "iptables", "-w", "-A", "INPUT", *self._xt_rule(queue)],
                     check_rc=False)
            if r.returncode != 0:
                self.clear_delay()
                raise Skip(f"neither nft queue nor iptables NFQUEUE works here: {r.stderr.strip()}")
            self.queue_rule = "xt"
        return line.strip()

    @staticmethod
    def _xt_rule(queue):
        return ["-p", "udp", "-j", "NFQUEUE", "--queue-num", str(queue), "--queue-bypass"]

    def clear_delay(self):
        """Removes the delay; returns the delayer's counters (dict) when it was nfq_delay."""
        if self.delayer is None:
            return None
        if self.delayer == "netem":
            _run(["tc", "qdisc", "del", "dev", self.bridge_port, "root"], check_rc=False)
            self.delayer = None
            return None
        p, queue = self.delayer
        self.delayer = None
        try:
            self.nft(f"flush chain inet {TABLE} delay\n")
            if self.queue_rule == "xt":
                _run(["ip", "netns", "exec", self.ns, "iptables", "-w", "-D", "INPUT", *self._xt_rule(queue)],
                     check_rc=False)
        except Exception:
            pass
        self.queue_rule = None
        if p.poll() is None:
            p.send_signal(signal.SIGTERM)
        try:
            out, _ = p.communicate(timeout=5)
        except subprocess.TimeoutExpired:
            p.kill()
            out, _ = p.communicate()
        return parse_delayer_counters(out)

    def counters(self):
        """Arriving UDP datagrams counted before any impairment: {'udp_in': n, 'udp_in_mcast': n}."""
        r = _run(["ip", "netns", "exec", self.ns, "nft", "-j", "list", "counters", "table", "inet", TABLE])
        out = {}
        for item in json.loads(r.stdout)["nftables"]:
            c = item.get("counter")
            if c:
                out[c["name"]] = c["packets"]
        return out

    def close(self):
        for p in self.procs:
            p.stop(signal.SIGTERM, timeout=3)
        self.clear_delay()


def parse_delayer_counters(text):
    m = re.search(r"received (\d+), accepted (\d+), dropped (\d+), max held (\d+), applied delay mean ([\d.]+) ms "
                  r"sd ([\d.]+) ms, release late mean ([\d.]+) us max ([\d.]+) us", text or "")
    if not m:
        return {"raw": text}
    keys = ["received", "accepted", "dropped", "max_held", "mean_ms", "sd_ms", "late_mean_us", "late_max_us"]
    vals = [int(m.group(i)) if i <= 4 else float(m.group(i)) for i in range(1, 9)]
    d = dict(zip(keys, vals))
    d["raw"] = text.strip()
    return d


_live_networks = []
_handlers_installed = False


def _cleanup_all():
    for net in list(_live_networks):
        net.close()


def _on_signal(sig, frame):
    _cleanup_all()
    signal.signal(sig, signal.SIG_DFL)
    os.kill(os.getpid(), sig)


def _install_handlers():
    global _handlers_installed
    if _handlers_installed:
        return
    _handlers_installed = True
    atexit.register(_cleanup_all)
    for sig in (signal.SIGINT, signal.SIGTERM, signal.SIGHUP):
        if signal.getsignal(sig) in (signal.SIG_DFL, signal.default_int_handler):
            signal.signal(sig, _on_signal)


class Network:
    _count = 0

    def __init__(self, hosts=2, nfq_delay=None, use_netem=None):
        require_root_tools()
        check(1 <= hosts <= 99, "1 to 99 hosts")
        Network._count += 1
        check(Network._count < 10, "at most 9 networks per process")
        self.tag = f"{PREFIX}{os.getpid()}n{Network._count}"  # <= 13 chars: link names stay <= 15
        self.nfq_delay = nfq_delay
        self.n_hosts = hosts
        self.netem = _netem_works() if use_netem is None else use_netem
        self.hosts = []
        self.bridge = self.tag + "b"
        self.subnet = 20 + (os.getpid() * 10 + Network._count) % 200
        self._closed = False
        self._started_any = False
        self.stale_removed = []

    def __enter__(self):
        self.stale_removed = cleanup_stale()
        _install_handlers()
        _live_networks.append(self)
        try:
            self._build()
        except Skip:
            self.close()
            raise
        except Exception as e:
            self.close()
            raise Skip(f"cannot build the test network here: {e}")
        return self

    def __exit__(self, *exc):
        self.close()
        return False

    def _build(self):
        _run(["ip", "link", "add", self.bridge, "type", "bridge", "mcast_snooping", "0", "nf_call_iptables", "0",
              "nf_call_ip6tables", "0", "nf_call_arptables", "0"])
        _run(["ip", "link", "set", self.bridge, "up"])
        for k in range(self.n_hosts):
            ns = f"{self.tag}h{k}"
            port = f"{self.tag}p{k}"
            addr = f"10.{self.subnet}.0.{k + 1}"
            _run(["ip", "netns", "add", ns])
            self.hosts.append(Host(self, k, ns, addr, "eth0", port))
            _run(["ip", "link", "add", port, "type", "veth", "peer", "name", "eth0", "netns", ns])
            _run(["ip", "link", "set", port, "master", self.bridge, "up"])
            _run(["ip", "-n", ns, "addr", "add", f"{addr}/24", "dev", "eth0"])
            _run(["ip", "-n", ns, "link", "set", "eth0", "up"])
            _run(["ip", "-n", ns, "link", "set", "lo", "up"])
            _run(["ip", "-n", ns, "route", "add", "224.0.0.0/4", "dev", "eth0"])  # SPDP multicast
            h = self.hosts[-1]
            try:
                h.nft(f"""table inet {TABLE} {{
  counter udp_in {{ }}
  counter udp_in_mcast {{ }}
  chain counters {{ type filter hook input priority -40; meta l4proto udp counter name udp_in;
                   meta l4proto udp ip daddr 224.0.0.0/4 counter name udp_in_mcast; }}
  chain partition {{ type filter hook input priority -30; }}
  chain loss {{ type filter hook input priority -20; }}
  chain delay {{ type filter hook input priority -10; }}
}}
""")
            except RuntimeError as e:
                raise Skip(f"nftables unusable in a namespace: {e}")

    def isolate(self, host):
        """Cuts `host` off from every other host, both directions (drops on each INPUT)."""
        host.partition()
        for h in self.hosts:
            if h is not host:
                h.partition(from_hosts=[host])

    def heal_all(self):
        for h in self.hosts:
            h.heal()

    def close(self):
        if self._closed:
            return
        self._closed = True
        for h in self.hosts:
            try:
                h.close()
            except Exception as e:
                sys.stderr.write(f"netharness: closing {h.ns}: {e}\n")
        for h in self.hosts:
            # Anything still running in the namespace (children of our processes) goes too.
            for p in _run(["ip", "netns", "pids", h.ns], check_rc=False).stdout.split():
                try:
                    os.kill(int(p), signal.SIGKILL)
                except (ProcessLookupError, ValueError):
                    pass
            _run(["ip", "netns", "del", h.ns], check_rc=False)  # takes its veth end and nft table along
            _run(["ip", "link", "del", h.bridge_port], check_rc=False)
        _run(["ip", "link", "del", self.bridge], check_rc=False)
        if self._started_any and shutil.which("fastdds"):
            # Killed DDS participants leave shared-memory segments; this removes only the ones no
            # live process holds, so parallel tests keep theirs.
            _run(["fastdds", "shm", "clean"], check_rc=False)
        if self in _live_networks:
            _live_networks.remove(self)


def stats(values):
    n = len(values)
    if n == 0:
        return 0.0, 0.0
    mean = sum(values) / n
    sd = math.sqrt(sum((v - mean) ** 2 for v in values) / (n - 1)) if n > 1 else 0.0
    return mean, sd


def print_log_tails(work, since, lines=25):
    """The last lines of every process log (*.log) written in `work` since `since` (time.time()):
    what a failed case's processes said, for a failure in a loaded CI run that cannot be rerun."""
    try:
        logs = sorted(f for f in os.listdir(work) if f.endswith(".log"))
    except OSError:
        return
    for name in logs:
        path = os.path.join(work, name)
        try:
            if os.path.getmtime(path) < since:
                continue
            with open(path, errors="replace") as f:
                tail = f.read().splitlines()[-lines:]
        except OSError:
            continue
        print(f"----- {name} (last {len(tail)} lines) -----", flush=True)
        print("\n".join(tail), flush=True)


def main(cases, argv=None, failures=()):
    """Runs cases[name](args) with SKIP (77) for Skip and 1 for Failure (or any of `failures`,
    e.g. session_test.Failure from its helpers), then prints the tails of the processes' logs.
    args has .case."""
    import argparse
    ap = argparse.ArgumentParser()
    ap.add_argument("case", choices=sorted(cases))
    ap.add_argument("--nfq-delay", default="")
    ap.add_argument("--bin-dir", default="")
    ap.add_argument("--work", default="")
    ap.add_argument("--domain", type=int, default=70)
    ap.add_argument("--without-delayer", action="store_true",
                    help="negative control: do not insert the delayer (the delay checks must fail)")
    args = ap.parse_args(argv)
    started = time.time()
    try:
        cases[args.case](args)
    except Skip as e:
        print(f"SKIP: {args.case}: {e}", flush=True)
        sys.exit(SKIP_RETURN_CODE)
    except (Failure, *failures) as e:
        print(f"FAIL: {args.case}: {e}", flush=True)
        if args.work:
            print_log_tails(args.work, started)
        sys.exit(1)
    print(f"PASS: {args.case}", flush=True)
