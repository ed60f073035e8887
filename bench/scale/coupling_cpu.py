#!/usr/bin/python3
"""What the event-driven coupling costs in CPU (issue "Hand to hand as fast as the wire", point 6):
sessions of scale.py's stations with the haptic nodes' coupling `polled` (before: contact sets
and object states go at the bridge's 100 Hz tick) and `woken` (after), alternately in one
sitting, in three settings:
  rest      2 users whose hands wait above the table, touching nothing, and 1 screen;
  pressing  2 users pressing the tail side by side (scale.py's pair 1), and 1 screen;
  scale     scale.py's 8 users in pairs + 8 screens + the audio guide.
Per session and kind of process (haptic node, world server, spectator, audio guide) the mean
CPU over the measured window (% of one core) and its main thread's (a haptic node's bridge, the
world server's tick), with the haptic nodes' bridge rate and the contact sets they sent. A bench: it asserts nothing.

usage: coupling_cpu.py --bin-dir BUILD [--pairs 2] [--seconds 30] [--scale-seconds 40]
                       [--settings rest,pressing,scale] [--work DIR] [--csv OUT] [--png OUT]
"""
import argparse
import csv
import datetime
import os
import sys

HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, HERE)
import scale  # noqa: E402

SETTINGS = {"rest": dict(users=2, spectators=1, at_rest=True), "pressing": dict(users=2, spectators=1),
            "scale": dict(users=8, spectators=8)}
COLUMNS = ("run", "utc", "setting", "coupling", "kind", "processes", "cpu_pct", "cpu_pct_min", "cpu_pct_max",
           "main_cpu_pct",
           "bridge_Hz", "contact_sets", "device_states", "load")


def summarise(run, setting, coupling, result):
    rows = []
    for kind in ("haptic", "world_server", "spectator", "audio_guide"):
        mine = [r for r in result["rows"] if r["kind"] == kind]
        if not mine:
            continue
        cpu = [r["cpu_pct"] or 0.0 for r in mine]
        row = {"run": run, "utc": datetime.datetime.utcnow().strftime("%H:%M:%S"), "setting": setting,
               "coupling": coupling, "kind": kind, "processes": len(mine), "cpu_pct": sum(cpu) / len(cpu),
               "cpu_pct_min": min(cpu), "cpu_pct_max": max(cpu), "load": "->".join(result["load"]),
               "main_cpu_pct": sum(r["main_cpu_pct"] or 0.0 for r in mine) / len(mine)}
        if kind == "haptic":
            row["bridge_Hz"] = sum(r.get("bridge_Hz", 0.0) for r in mine) / len(mine)
            row["contact_sets"] = sum(r.get("contact_sets", 0) for r in mine)
            row["device_states"] = sum(r.get("device_states", 0) for r in mine)
        rows.append(row)
    return rows


def plot(rows, out):
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    settings = [s for s in SETTINGS if any(r["setting"] == s for r in rows)]
    kinds = ("haptic", "world_server", "spectator")
    fig, axes = plt.subplots(1, len(kinds), figsize=(5 * len(kinds), 4.2))
    for ax, kind in zip(axes, kinds):
        for si, s in enumerate(settings):
            for ci, (c, colour) in enumerate((("polled", "tab:red"), ("woken", "tab:blue"))):
                ys = [float(r["cpu_pct"]) for r in rows if r["setting"] == s and r["coupling"] == c and r["kind"] == kind]
                ax.plot([si + 0.2 * (ci - 0.5)] * len(ys), ys, "o", color=colour, alpha=0.75,
                        label=c if si == 0 else None)
        ax.set_xticks(range(len(settings)))
        ax.set_xticklabels(settings)
        ax.set_ylabel("CPU, mean per process [% of one core]")
        ax.set_title(kind)
        ax.legend(fontsize=8)
    fig.suptitle("CPU per process, coupling polled (before) and woken (after), alternately", fontsize=9)
    fig.tight_layout()
    fig.savefig(out, dpi=110)


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--bin-dir", required=True)
    ap.add_argument("--pairs", type=int, default=2)
    ap.add_argument("--seconds", type=float, default=30.0)
    ap.add_argument("--scale-seconds", type=float, default=40.0)
    ap.add_argument("--settings", default="rest,pressing,scale")
    ap.add_argument("--domain", type=int, default=217)
    ap.add_argument("--work", default="/tmp/handshare-coupling-cpu")
    ap.add_argument("--csv", default="")
    ap.add_argument("--png", default="")
    a = ap.parse_args()
    out = []
    for run in range(a.pairs):
        for setting in a.settings.split(","):
            order = ("polled", "woken") if run % 2 == 0 else ("woken", "polled")
            for coupling in order:
                seconds = a.scale_seconds if setting == "scale" else a.seconds
                result = scale.run_session(a.bin_dir, os.path.join(a.work, setting), a.domain, fps=5.0,
                                           seconds=seconds, cache=os.path.join(a.work, "fem_cache"),
                                           coupling=coupling, **SETTINGS[setting])
                for r in summarise(run, setting, coupling, result):
                    out.append(r)
                    print(", ".join(f"{c} {scale.fmt(r.get(c))}" for c in COLUMNS), flush=True)
    if a.csv:
        with open(a.csv, "w", newline="") as f:
            w = csv.DictWriter(f, fieldnames=COLUMNS)
            w.writeheader()
            for r in out:
                w.writerow({c: scale.fmt(r.get(c)) for c in COLUMNS})
    if a.png:
        plot(out, a.png)
    return 0


if __name__ == "__main__":
    sys.exit(main())
