#!/usr/bin/python3
"""Plots what tests/net/net_dds_test.py's delayed_tail wrote to its --work folder: each user's
force through the run at every one-way delay (left); against the delay the stiffness each
felt relative to the no-delay run and the force RMS above 5 Hz while both held still (middle);
each node's field of the tail against the world server's through the run (right).
Usage: plot_delayed_tail.py WORK_DIR OUT.png   (Debian's python3-matplotlib)."""
import csv
import os
import sys

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402


def main() -> int:
    if len(sys.argv) != 3:
        print(__doc__, file=sys.stderr)
        return 2
    work, out = sys.argv[1], sys.argv[2]
    with open(os.path.join(work, "delayed_tail.csv"), newline="") as f:
        rows = list(csv.DictReader(f))
    with open(os.path.join(work, "delayed_tail_forces.csv"), newline="") as f:
        forces = list(csv.DictReader(f))
    delays = sorted({int(r["delay_ms"]) for r in rows})
    users = sorted({r["user"] for r in rows})
    with open(os.path.join(work, "delayed_tail_field.csv"), newline="") as f:
        field = list(csv.DictReader(f))
    fig, (left, right, third) = plt.subplots(1, 3, figsize=(18, 4.5))
    for d in delays:
        for u, style in zip(users, ("-", "--")):
            series = [(float(r["t_s"]), float(r["fz_N"])) for r in forces
                      if int(r["delay_ms"]) == d and r["user"] == u]
            left.plot([t for t, _ in series], [v for _, v in series], style, linewidth=0.8, label=f"{u}, {d} ms")
    left.set_xlabel("script time [s]")
    left.set_ylabel("force on the fingertip, z [N]")
    left.set_title("each user's force (alice presses 1 mm deeper at 6 s, bob at 12 s)")
    left.legend(fontsize=7, ncol=2)
    for u, marker in zip(users, ("o", "s")):
        mine = sorted((r for r in rows if r["user"] == u), key=lambda r: int(r["delay_ms"]))
        k0 = float(mine[0]["k_N_per_m"])
        right.plot([int(r["delay_ms"]) for r in mine], [100.0 * (float(r["k_N_per_m"]) / k0 - 1.0) for r in mine],
                   marker=marker, label=f"{u}: stiffness vs 0 ms [%]")
        right.plot([int(r["delay_ms"]) for r in mine], [1e3 * float(r["hf_rms_N"]) for r in mine],
                   marker=marker, linestyle=":", label=f"{u}: force RMS above 5 Hz [mN]")
    right.axhline(5.0, color="red", linestyle="--", linewidth=1, label="stiffness bound +-5 %")
    right.axhline(-5.0, color="red", linestyle="--", linewidth=1)
    right.set_xlabel("one-way delay [ms]")
    right.set_title("stiffness felt and force noise, against delay")
    right.legend(fontsize=7)
    for d in delays:
        for u, style in zip(users, ("-", "--")):
            series = [(float(r["t_s"]), 1e6 * float(r["divergence_m"])) for r in field
                      if int(r["delay_ms"]) == d and r["user"] == u]
            third.plot([t for t, _ in series], [max(v, 0.1) for _, v in series], style, linewidth=0.8,
                       label=f"{u}, {d} ms")
    third.axhline(50.0, color="red", linestyle="--", linewidth=1, label="bound at rest (50 um)")
    third.set_yscale("log")
    third.set_xlabel("script time [s]")
    third.set_ylabel("largest vertex difference [um]")
    third.set_title("one body, one shape: each node's field vs the server's")
    third.legend(fontsize=6, ncol=2)
    fig.suptitle("Two users at simulated HIRO IIs press the triceratops tail across a delayed network")
    fig.tight_layout()
    fig.savefig(out, dpi=100)
    return 0


if __name__ == "__main__":
    sys.exit(main())
