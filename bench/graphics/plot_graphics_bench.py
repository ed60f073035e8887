#!/usr/bin/python3
"""Plots `graphics_bench` output (mode,scene,width_px,height_px,frames,p50_ms,p99_ms,max_ms,
fps_p50) as grouped bars per scene, window and headless side by side, with the 16.7 ms line of
60 frames per second.
Usage: plot_graphics_bench.py RESULTS.csv OUT.png  (Debian's python3-matplotlib)."""
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
    if not rows:
        print(f"{sys.argv[1]}: no rows", file=sys.stderr)
        return 1
    labels = [f"{r['scene']}\n{r['mode']} {r['width_px']}x{r['height_px']}" for r in rows]
    p50 = [float(r["p50_ms"]) for r in rows]
    p99 = [float(r["p99_ms"]) for r in rows]
    x = range(len(rows))
    fig, ax = plt.subplots(figsize=(10, 4.5))
    ax.bar([i - 0.2 for i in x], p50, width=0.4, label="p50")
    ax.bar([i + 0.2 for i in x], p99, width=0.4, label="p99")
    ax.axhline(1000.0 / 60.0, color="red", linestyle="--", linewidth=1, label="60 frames/s (16.7 ms)")
    ax.set_ylabel("frame time [ms]")
    ax.set_xticks(list(x))
    ax.set_xticklabels(labels, rotation=20, ha="right", fontsize=8)
    ax.set_title("A spectator's frame: rebuild the view and draw it (Mesa software GL)")
    ax.legend(loc="upper left")
    fig.tight_layout()
    fig.savefig(sys.argv[2], dpi=120)
    return 0


if __name__ == "__main__":
    sys.exit(main())
