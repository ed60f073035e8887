#!/usr/bin/python3
"""Plots the node path of `net_bench --csv` runs before and after (haptic step -> peer's haptic
step through two haptic nodes' own loop and bridge, and its stages), one panel per transport:
for each run, p50 bars with p99 whiskers per measure, on a log scale, with the targets (p99
1.5 ms on shm and udp, 2 ms on netns).
Usage: plot_node_path.py OUT.png LABEL=RESULTS.csv [LABEL=RESULTS.csv ...]
(e.g. "polled=polled_1.csv" "woken=woken_1.csv"; Debian's python3-matplotlib)."""
import csv
import sys

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402

NODE = ["node_path", "node_sender_handoff", "node_write_call", "node_dds_and_tick", "node_receiver_handoff"]
TARGET_US = {"shm": 1500.0, "udp": 1500.0, "netns": 2000.0}
COLOURS = ["tab:grey", "tab:blue", "tab:orange", "tab:green", "tab:red", "tab:purple"]


def read(path):
    with open(path, newline="") as f:
        return list(csv.DictReader(row for row in f if not row.startswith("#")))


def main() -> int:
    if len(sys.argv) < 3 or any("=" not in a for a in sys.argv[2:]):
        print(__doc__, file=sys.stderr)
        return 2
    runs = []
    for arg in sys.argv[2:]:
        label, path = arg.split("=", 1)
        runs.append((label, read(path)))
    transports = [t for t in ("shm", "udp", "netns") if any(r["transport"] == t for _, rows in runs for r in rows)]
    if not transports:
        print("plot_node_path: no node_path rows in the files given", file=sys.stderr)
        return 1
    fig, axes = plt.subplots(1, len(transports), figsize=(5.5 * len(transports), 5), squeeze=False)
    width = 0.8 / len(runs)
    for ax, t in zip(axes[0], transports):
        for k, (label, rows) in enumerate(runs):
            xs, p50, err = [], [], []
            for i, m in enumerate(NODE):
                r = [r for r in rows if r["transport"] == t and r["measure"] == m]
                if not r:
                    continue
                lo = float(r[0]["p50_us"])
                xs.append(i - 0.4 + width * (k + 0.5))
                p50.append(max(lo, 0.5))
                err.append(max(float(r[0]["p99_us"]) - lo, 0.0))
            ax.bar(xs, p50, width=width, color=COLOURS[k % len(COLOURS)], label=f"{label} (p50, whisker p99)",
                   yerr=[[0] * len(err), err], capsize=3)
        ax.axhline(TARGET_US[t], color="red", linestyle="--", linewidth=1,
                   label=f"target node_path p99 {TARGET_US[t] / 1000:.1f} ms")
        ax.set_yscale("log")
        ax.set_ylabel("microseconds")
        ax.set_xticks(range(len(NODE)))
        ax.set_xticklabels(NODE, rotation=25, ha="right")
        ax.set_title(f"{t}: haptic step -> peer's haptic step")
        ax.legend(loc="upper right", fontsize=7)
    fig.tight_layout()
    fig.savefig(sys.argv[1], dpi=110)
    return 0


if __name__ == "__main__":
    sys.exit(main())
