#!/usr/bin/python3
"""Plots `deadband_bench --csv` output of one or more recordings: the share of contact sets the
deadband keeps home (left) and the force error a receiver holds on deformables, p99 (right),
against the Weber fraction, one line per case and user.
Usage: plot_deadband_bench.py OUT.png CASE=RESULTS.csv [CASE=RESULTS.csv ...]
(Debian's python3-matplotlib)."""
import csv
import sys

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402


def main() -> int:
    if len(sys.argv) < 3 or any("=" not in a for a in sys.argv[2:]):
        print(__doc__, file=sys.stderr)
        return 2
    fig, (left, right) = plt.subplots(1, 2, figsize=(10, 4))
    for arg in sys.argv[2:]:
        case, path = arg.split("=", 1)
        with open(path, newline="") as f:
            rows = list(csv.DictReader(row for row in f if not row.startswith("#")))
        for user in sorted({r["user"] for r in rows}):
            mine = sorted((r for r in rows if r["user"] == user), key=lambda r: float(r["weber"]))
            w = [100.0 * float(r["weber"]) for r in mine]
            left.plot(w, [float(r["reduction_pct"]) for r in mine], marker="o", label=f"{case} {user}")
            right.plot(w, [float(r["force_err_p99_N"]) for r in mine], marker="o", label=f"{case} {user}")
    left.axhline(80.0, color="red", linestyle="--", linewidth=1, label="target 80 %")
    left.set_xlabel("Weber fraction [%]")
    left.set_ylabel("contact sets kept home [%]")
    left.set_ylim(0, 100)
    left.legend(fontsize=8)
    right.set_xlabel("Weber fraction [%]")
    right.set_ylabel("force error held by a receiver, p99 [N]")
    right.legend(fontsize=8)
    fig.suptitle("Contact-set deadband: packets saved against force error")
    fig.tight_layout()
    fig.savefig(sys.argv[1], dpi=110)
    return 0


if __name__ == "__main__":
    sys.exit(main())
