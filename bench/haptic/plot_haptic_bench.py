#!/usr/bin/python3
"""Plots `haptic_bench --csv` output (scenario,p50_us,p99_us[,lost_share]) as grouped bars with
the 50 us target line; lost_share (finger-steps whose proxy is > 15 mm from its fingertip, must
be 0) goes under each scenario's name when the file has it (older results do not).
Usage: plot_haptic_bench.py RESULTS.csv OUT.png  (Debian's python3-matplotlib)."""
import csv
import sys

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402


def main() -> int:
    if len(sys.argv) != 3:
        print(__doc__, file=sys.stderr)
        return 2
    with open(sys.argv[1], newline="") as f:
        rows = [r for r in csv.DictReader(row for row in f if not row.startswith("#"))]
    names = [r["scenario"] for r in rows]
    if rows and "lost_share" in rows[0]:
        names = [f"{n}\nlost {100.0 * float(r['lost_share']):.2f}%" for n, r in zip(names, rows)]
    p50 = [float(r["p50_us"]) for r in rows]
    p99 = [float(r["p99_us"]) for r in rows]
    x = range(len(names))
    fig, ax = plt.subplots(figsize=(max(9.0, 0.8 * len(names)), 4.5))  # room for each name
    ax.bar([i - 0.2 for i in x], p50, width=0.4, label="p50")
    ax.bar([i + 0.2 for i in x], p99, width=0.4, label="p99")
    ax.axhline(50.0, color="red", linestyle="--", linewidth=1, label="target p99 50 us")
    ax.set_yscale("log")
    ax.set_ylabel("HapticWorld::Step, 5 fingers [us]")
    ax.set_xticks(list(x))
    ax.set_xticklabels(names, rotation=20 if len(names) <= 10 else 45, ha="right", fontsize=8 if len(names) > 10 else None)
    ax.set_title("Full haptic step (collision, proxy, contact solve, forces), 1 kHz trajectories")
    ax.legend(loc="upper left")
    fig.tight_layout()
    fig.savefig(sys.argv[2], dpi=120)
    return 0


if __name__ == "__main__":
    sys.exit(main())
