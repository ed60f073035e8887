#!/usr/bin/python3
"""Plots `fem_accuracy` output: the linear model's error against press depth, per part.

usage: /usr/bin/python3 plot_fem_accuracy.py ACCURACY.csv USER_DEPTHS.csv OUT.png SUMMARY.csv

Top row: the press force's error (linear against CalculiX NLGEOM, dashed, and neo-Hooke, solid)
for each press; bottom row: the displacement of the free surface under the fingers and the whole
surface field, one-finger normal press. Marked: 5 % and 10 %, a quarter of the part's local
thickness, the depths the scripted users press (tour: red, test sessions: orange) and
haptic_bench's deepest press (3.2 mm). Writes SUMMARY.csv: per part, press and model, the depth
at which the force error first reaches 5 % and 10 % (linear between the two depths that bracket
it; "< D" if it does at the first depth D, "> D" if not up to the deepest converged depth D;
what `fem_accuracy --check` holds a re-run to), and prints it as the markdown table of
docs/fem.md.
"""

import csv
import sys
from collections import defaultdict

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402

PARTS = ["tail", "head", "leg", "belly", "horn"]
PRESSES = [("one_normal", "1 finger, normal", "C0"), ("one_oblique", "1 finger, 30 deg oblique", "C1"),
           ("five_normal", "5 fingers, normal", "C2"), ("five_oblique", "5 fingers, 30 deg oblique", "C3")]
STYLE = {"neo_hooke": "-", "nlgeom": "--"}
HAPTIC_BENCH_DEEPEST_MM = 3.2


def main():
    rows = defaultdict(list)
    all_rows = {}
    thickness = {}
    with open(sys.argv[1]) as f:
        for r in csv.DictReader(f):
            all_rows.setdefault((r["part"], r["press"], r["model"]), []).append(r)
            if r["converged"] != "1":
                continue
            rows[(r["part"], r["press"], r["model"])].append(r)
            thickness[r["part"]] = float(r["thickness_mm"])
    users = defaultdict(list)
    with open(sys.argv[2]) as f:
        for r in csv.DictReader(f):
            users[r["part"]].append((r["script"], float(r["depth_mm"])))
    fig, axes = plt.subplots(2, 5, figsize=(22, 9), sharex="col")
    for col, part in enumerate(PARTS):
        ax = axes[0][col]
        for press, label, colour in PRESSES:
            for model, ls in STYLE.items():
                pts = rows.get((part, press, model))
                if not pts:
                    continue
                ax.plot([float(r["depth_mm"]) for r in pts], [100 * float(r["force_err"]) for r in pts],
                        ls, color=colour, marker=".", label=f"{label}, {model.replace('_', '-')}")
        ax.set_title(f"{part} (local thickness {thickness.get(part, float('nan')):.0f} mm)")
        ax.set_ylabel("force error of the linear model [%]")
        bottom = axes[1][col]
        for model, ls in STYLE.items():
            pts = rows.get((part, "one_normal", model))
            if not pts:
                continue
            d = [float(r["depth_mm"]) for r in pts]
            bottom.plot(d, [100 * float(r["disp_err"]) for r in pts], ls, color="C4", marker=".",
                        label=f"under the finger, {model.replace('_', '-')}")
            bottom.plot(d, [100 * float(r["field_err"]) for r in pts], ls, color="C5", marker=".",
                        label=f"whole surface, {model.replace('_', '-')}")
        bottom.set_ylabel("field error, 1 finger normal [%]")
        bottom.set_xlabel("press depth [mm]")
        for a in (ax, bottom):
            a.set_yscale("log")
            a.axhline(5, color="grey", lw=0.8)
            a.axhline(10, color="black", lw=0.8)
            if part in thickness:
                a.axvline(thickness[part] / 4, color="black", ls="-.", lw=1)
            a.axvline(HAPTIC_BENCH_DEEPEST_MM, color="grey", ls=":", lw=1.2)
            for script, depth in users.get(part, []):
                a.axvline(depth, color="red" if script.startswith("tour") else "orange", lw=1.5, alpha=0.7)
            a.grid(True, which="both", alpha=0.3)
    axes[0][0].legend(fontsize=7, loc="lower right")
    axes[1][0].legend(fontsize=7, loc="lower right")
    fig.suptitle("How deep before the linear model lies: linear FEM against CalculiX (NLGEOM dashed, neo-Hooke "
                 "solid). Lines: 5 % grey, 10 % black; a quarter of the local thickness dash-dot; users' presses: "
                 "tour red, test sessions orange; haptic_bench's deepest dotted", fontsize=10)
    fig.tight_layout(rect=(0, 0, 1, 0.96))
    fig.savefig(sys.argv[3], dpi=80)
    summary(all_rows, sys.argv[4])
    errors_table(all_rows)


TABLE_DEPTHS = ["0.500", "2.000", "4.000", "8.000", "12.000", "20.000", "30.000"]


def errors_table(all_rows):
    """Force / displacement under the fingers / surface field errors at a few depths, each
    part's reference model (neo-Hooke for the soft parts, NLGEOM for the horn)."""
    print()
    print("| part | press | model | " + " | ".join(f"{float(d):g} mm" for d in TABLE_DEPTHS) + " |")
    print("|---|---|---|" + "---|" * len(TABLE_DEPTHS))
    for (part, press, model), pts in all_rows.items():
        reference = "nlgeom" if part == "horn" else "neo_hooke"
        if model != reference:
            continue
        by_depth = {r["depth_mm"]: r for r in pts}
        cells = []
        for d in TABLE_DEPTHS:
            r = by_depth.get(d)
            if r is None:
                cells.append("")
            elif r["converged"] != "1":
                cells.append("no conv.")
            else:
                cells.append(f"{100 * float(r['force_err']):.1f} / {100 * float(r['disp_err']):.1f} / "
                             f"{100 * float(r['field_err']):.1f}")
        print(f"| {part} | {press} | {model.replace('_', '-')} | " + " | ".join(cells) + " |")


def crossing(pts, threshold):
    """The depth at which the force error first reaches threshold, as text."""
    prev = None
    for r in pts:
        d, e = float(r["depth_mm"]), float(r["force_err"])
        if e >= threshold:
            if prev is None:
                return f"< {d:g}"
            return f"{prev[0] + (threshold - prev[1]) / (e - prev[1]) * (d - prev[0]):.2f}"
        prev = (d, e)
    return f"> {prev[0]:g}" if prev else "not converged"


def summary(all_rows, out):
    print("| part | press | model | thickness [mm] | 5 % at [mm] | 10 % at [mm] | deepest converged [mm] | error there | ccx stopped at [mm] |")
    print("|---|---|---|---|---|---|---|---|---|")
    with open(out, "w") as f:
        f.write("part,press,model,thickness_mm,depth_5pct_mm,depth_10pct_mm,deepest_mm,err_at_deepest,failed_at_mm\n")
        for (part, press, model), pts in all_rows.items():
            ok = [r for r in pts if r["converged"] == "1"]
            failed = [r["depth_mm"] for r in pts if r["converged"] != "1"]
            d5, d10 = crossing(ok, 0.05), crossing(ok, 0.10)
            deepest = ok[-1]["depth_mm"] if ok else ""
            err = f"{float(ok[-1]['force_err']):.4f}" if ok else ""
            fail = f"{float(failed[0]):g}" if failed else ""
            f.write(f"{part},{press},{model},{float(pts[0]['thickness_mm']):.1f},{d5},{d10},{deepest},{err},{fail}\n")
            print(f"| {part} | {press} | {model.replace('_', '-')} | {float(pts[0]['thickness_mm']):.0f} | {d5} | {d10} | "
                  f"{float(deepest):g} | {100 * float(err):.1f} % | {fail or '-'} |" if ok else
                  f"| {part} | {press} | {model.replace('_', '-')} | {float(pts[0]['thickness_mm']):.0f} | - | - | - | - | {fail} |")


if __name__ == "__main__":
    main()
