#!/usr/bin/python3
"""Plots what DDS-Security costs on the contact path: `net_bench --csv` run without and with
`--security` (measures suffixed _secured), p50 bars and p99 whiskers per transport for the
contact set's one-way hop (left) and the node-shaped haptic-step-to-haptic-step path (right).
Usage: plot_net_bench_security.py PLAIN.csv SECURED.csv OUT.png  (Debian's python3-matplotlib)."""
import csv
import sys

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402


def rows(path):
    with open(path) as f:
        return [r for r in csv.DictReader(line for line in f if not line.startswith("#"))]


def figure(plain, secured, measure, ax, title):
    transports = [t for t in ("shm", "udp", "netns") if any(r["transport"] == t for r in plain)]
    for k, (label, data, suffix, colour) in enumerate(
            (("without security", plain, "", "tab:blue"), ("with DDS-Security", secured, "_secured", "tab:red"))):
        xs, p50, err = [], [], []
        for i, t in enumerate(transports):
            r = [r for r in data if r["transport"] == t and r["measure"] == measure + suffix]
            if not r:
                continue
            lo, hi = float(r[0]["p50_us"]), float(r[0]["p99_us"])
            xs.append(i - 0.2 + 0.4 * k)
            p50.append(lo)
            err.append(max(hi - lo, 0.0))
        ax.bar(xs, p50, width=0.4, color=colour, label=label, yerr=[[0] * len(err), err], capsize=4)
    ax.set_xticks(range(len(transports)))
    ax.set_xticklabels(transports)
    ax.set_ylabel("microseconds (bar p50, whisker p99)")
    ax.set_title(title)
    ax.set_ylim(0, ax.get_ylim()[1] * 1.2)
    ax.legend(loc="upper center", ncol=2)


def main():
    if len(sys.argv) != 4:
        sys.exit(__doc__)
    plain, secured = rows(sys.argv[1]), rows(sys.argv[2])
    fig, axes = plt.subplots(1, 2, figsize=(11, 4.5))
    figure(plain, secured, "contact_one_way", axes[0], "contact set, writer to reader (1 kHz)")
    figure(plain, secured, "node_path", axes[1], "haptic step to haptic step (two 100 Hz bridges)")
    fig.tight_layout()
    fig.savefig(sys.argv[3], dpi=100)


if __name__ == "__main__":
    main()
