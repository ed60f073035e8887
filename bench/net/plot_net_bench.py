#!/usr/bin/python3
"""Plots `net_bench --csv` output (transport,measure,p50_us,p99_us,max_us): left, the contact set's
one-way latency and its split per transport (p50 bars, p99 whiskers, the 0.5 ms target); right,
the node path (haptic step to haptic step through two haptic nodes' own loop and bridge) and its split.
Usage: plot_net_bench.py RESULTS.csv OUT.png  (Debian's python3-matplotlib)."""
import csv
import sys

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402

HOP = ["contact_one_way", "write_call", "write_to_wake", "wake_to_taken", "serialize", "deserialize"]
NODE = ["node_path", "node_sender_handoff", "node_write_call", "node_dds_and_tick", "node_receiver_handoff"]
COLOURS = {"shm": "tab:blue", "udp": "tab:orange", "netns": "tab:green"}


def panel(ax, rows, measures, title, target_us=None):
    transports = [t for t in ("shm", "udp", "netns") if any(r["transport"] == t for r in rows)]
    width = 0.8 / max(1, len(transports))
    for k, t in enumerate(transports):
        xs, p50, err = [], [], []
        for i, m in enumerate(measures):
            r = [r for r in rows if r["transport"] == t and r["measure"] == m]
            if not r:
                continue
            lo = float(r[0]["p50_us"])
            xs.append(i - 0.4 + width * (k + 0.5))
            p50.append(max(lo, 0.05))
            err.append(max(float(r[0]["p99_us"]) - lo, 0.0))
        ax.bar(xs, p50, width=width, color=COLOURS[t], label=f"{t} (p50, whisker p99)",
               yerr=[[0] * len(err), err], capsize=3)
    if target_us is not None:
        ax.axhline(target_us, color="red", linestyle="--", linewidth=1, label="target p99 0.5 ms")
    ax.set_yscale("log")
    ax.set_ylabel("microseconds")
    ax.set_xticks(range(len(measures)))
    ax.set_xticklabels(measures, rotation=25, ha="right")
    ax.set_title(title)
    ax.legend(loc="upper right", fontsize=8)


def main() -> int:
    if len(sys.argv) != 3:
        print(__doc__, file=sys.stderr)
        return 2
    with open(sys.argv[1], newline="") as f:
        rows = list(csv.DictReader(row for row in f if not row.startswith("#")))
    fig, (a, b) = plt.subplots(1, 2, figsize=(13, 5), gridspec_kw={"width_ratios": [3, 2]})
    panel(a, rows, HOP, "Contact set, writer -> reader (1 kHz, best-effort)", 500.0)
    panel(b, rows, NODE, "Node path: haptic step -> peer's haptic step")
    fig.tight_layout()
    fig.savefig(sys.argv[2], dpi=110)
    return 0


if __name__ == "__main__":
    sys.exit(main())
