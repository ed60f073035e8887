#!/usr/bin/python3
"""Plots `fem_bench --csv` output.

usage: /usr/bin/python3 plot_fem_bench.py BENCH.csv OUT_DIR

Writes OUT_DIR/fem_fig10.png (update frequency against surface node count: the paper's Fig. 10
and its extension to 10,000 nodes) and OUT_DIR/fem_error_vs_time.png (error against step time
for float32/float64 storage, regularization and mesh resolution, and the model rows: the linear
model and the stiffening correction on the tail and the belly against CalculiX's neo-Hookean
solid), and prints markdown tables of the numbers for docs/fem.md.
"""

import csv
import sys
from collections import defaultdict

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402


def load(path):
    rows = defaultdict(dict)  # method -> {surface_nodes: (contacts, step_us, rel_error)}
    with open(path) as f:
        for r in csv.DictReader(f):
            p99 = r.get("p99_us")
            rows[r["method"]][int(r["surface_nodes"])] = (
                int(r["contacts"]), float(r["step_us"]), float(r["rel_error"]),
                float(p99) if p99 else None, float(r.get("storage_bytes") or 0))
    return rows


FIG10 = [
    ("elementary_displacement", "elementary displacement (paper form, T^d f32, full surface)", "o-"),
    ("compliance_full_update_columns_int16", "exact forces + surface from int16 column copy", "*-"),
    ("compliance_full_update_columns_float16", "exact forces + surface from f16 column copy", "P-"),
    ("compliance_full_update_columns_float32", "exact forces + surface from f32 column copy", "p-"),
    ("compliance_full_update_float32", "compliance form, full surface (f32 packed symmetric)", "s-"),
    ("compressed_full_update_tol_0.001", "compressed compliance (tol 1e-3), full surface", "h-"),
    ("compliance_force_only", "compliance form, forces only", "^-"),
    ("sherman_morrison_woodbury", "Sherman-Morrison-Woodbury (dense K^-1)", "d-"),
    ("gauss_elimination", "Gauss elimination (dense LU of full K)", "x-"),
    ("cholmod_direct", "CHOLMOD direct solve per step", "v-"),
]


def fig10(rows, out):
    fig, axes = plt.subplots(1, 2, figsize=(13, 5.8))
    for ax, (lo, hi, log) in zip(axes, [(0, 700, False), (0, 20000, True)]):
        for method, label, style in FIG10:
            pts = sorted((n, 1e6 / v[1]) for n, v in rows.get(method, {}).items() if lo < n <= hi)
            if pts:
                ax.plot([p[0] for p in pts], [p[1] for p in pts], style, label=label)
        ax.axhline(1000, color="grey", ls="--", lw=1)
        ax.text(ax.get_xlim()[0] if not log else 110, 1150, "1 kHz haptic rate", color="grey", fontsize=8)
        ax.set_yscale("log")
        if log:
            ax.set_xscale("log")
        ax.set_xlabel("free surface nodes")
        ax.set_ylabel("update frequency [Hz] (5 contacts)")
        ax.grid(True, which="both", alpha=0.3)
    axes[0].set_title("HIRO II Fig. 10 range (cubes, 100-600 surface nodes)")
    axes[1].set_title("extended to 10,149 surface nodes (plate)")
    handles, labels = axes[1].get_legend_handles_labels()
    fig.legend(handles, labels, loc="lower center", ncol=3, fontsize=8)
    fig.tight_layout(rect=(0, 0.1, 1, 1))
    fig.savefig(out, dpi=110)


def error_vs_time(rows, out):
    fig, ax = plt.subplots(figsize=(11, 6))
    # Storage precision: each (N) point of the float64 and float32 force-only/full-update series.
    for method, label, marker, color, hollow in [
        ("compliance_force_only", "forces, float64 storage", "o", "C0", False),
        ("compliance_force_only_float32", "forces, float32 storage", "o", "C0", True),
        ("compliance_full_update", "full surface, float64", "s", "C1", False),
        ("compliance_full_update_float32", "full surface, float32", "s", "C1", True),
    ]:
        pts = sorted(rows.get(method, {}).items())
        ax.scatter([v[1] for _, v in pts], [max(v[2], 1e-17) for _, v in pts], marker=marker,
                   label=label, facecolors="none" if hollow else color, edgecolors=color, s=40)
    # Faster / smaller storages of the surface field and the compressed compliance.
    for method, label, marker, color in [
        ("elementary_displacement", "paper form T^d float32, full surface", "o", "C2"),
        ("elementary_displacement_float16", "paper form T^d float16, full surface", "v", "C2"),
        ("compliance_full_update_columns_float32", "exact forces + f32 column copy", "p", "C4"),
        ("compliance_full_update_columns_float16", "exact forces + f16 column copy", "P", "C4"),
        ("compliance_full_update_columns_int16", "exact forces + int16 column copy", "*", "C4"),
        ("compressed_full_update_tol_0.001", "compressed tol 1e-3, full surface", "h", "C5"),
        ("compressed_full_update_tol_1e-05", "compressed tol 1e-5, full surface", "H", "C5"),
        ("compressed_force_only_tol_0.001", "compressed tol 1e-3, forces", "<", "C6"),
        ("compressed_force_only_tol_1e-05", "compressed tol 1e-5, forces", ">", "C6"),
        ("compressed_force_only_tol_0.001_f16factors", "compressed tol 1e-3, float16 factors, forces", "^", "C7"),
    ]:
        pts = sorted(rows.get(method, {}).items())
        ax.scatter([v[1] for _, v in pts], [max(v[2], 1e-17) for _, v in pts], marker=marker, label=label,
                   color=color, s=40)
    # Regularization (eps relative to the mean diagonal compliance), at every model size.
    for rel, marker in [("0.001", "1"), ("0.01", "2"), ("0.1", "3")]:
        pts = sorted(rows.get("compliance_force_only_reg_" + rel, {}).items())
        ax.scatter([v[1] for _, v in pts], [v[2] for _, v in pts], marker=marker, s=70,
                   label=f"forces, regularized eps = {rel} x mean C_kk")
    # Mesh resolution: a Hertz fingertip patch (push-only), error against the finest mesh.
    res = sorted((v[1], v[2], m) for m, d in rows.items() if m.startswith("sphere_patch_a_over_h_")
                 for _, v in d.items())
    if res:
        ax.plot([r[0] for r in res], [r[1] for r in res], "k*-", label="fingertip patch: mesh a/h = 2, 3, 4, 6")
        for t, e, m in res:
            ax.annotate("a/h=" + m.rsplit("_", 1)[1], (t, e), fontsize=7, xytext=(4, 4), textcoords="offset points")
    # Model error: the linear model and the stiffening correction on the scenes' parts, against
    # CalculiX's neo-Hookean solid (worst press force error at the users' depth), timed as one
    # haptic step's deformable contact on the part's real mesh; an arrow from linear to corrected.
    for part, color in [("tail", "C8"), ("belly", "C9")]:
        lin = rows.get("model_linear_" + part, {})
        cor = rows.get("model_stiffening_" + part, {})
        for method, d, marker, label in [("linear", lin, "D", f"model error: linear FEM, {part} (vs CalculiX neo-Hooke)"),
                                         ("stiffening", cor, "X", f"model error: stiffening correction, {part}")]:
            if d:
                ax.scatter([v[1] for v in d.values()], [v[2] for v in d.values()], marker=marker, s=80, color=color,
                           edgecolors="k", label=label, zorder=5)
        for n in set(lin) & set(cor):
            ax.annotate("", xy=(cor[n][1], cor[n][2]), xytext=(lin[n][1], lin[n][2]),
                        arrowprops=dict(arrowstyle="->", color=color, lw=1.2))
            ax.annotate(f"{part} ({n} nodes)", (lin[n][1], lin[n][2]), fontsize=7, xytext=(6, 4),
                        textcoords="offset points")
    ax.set_xscale("log")
    ax.set_yscale("log")
    ax.set_xlabel("step time [us]")
    ax.set_ylabel("relative error")
    ax.set_title("accuracy against run time (solver errors vs direct sparse solve; resolution vs finest mesh;\n"
                 "model errors vs CalculiX neo-Hooke at the users' press depth)", fontsize=10)
    ax.grid(True, which="both", alpha=0.3)
    ax.legend(fontsize=7, loc="upper left", bbox_to_anchor=(1.01, 1.0))
    fig.tight_layout()
    fig.savefig(out, dpi=110)


def tables(rows):
    sizes = sorted({n for m in FIG10 for n in rows.get(m[0], {})})
    methods = [m for m, *_ in FIG10] + [
        "compliance_full_update", "compliance_full_update_float32_coherent",
        "compliance_full_update_columns_float32_coherent", "compliance_full_update_columns_float16_coherent",
        "compliance_full_update_columns_int16_coherent",
        "elementary_displacement_coherent", "elementary_displacement_float16",
        "elementary_displacement_float16_coherent", "elementary_displacement_float64",
        "compressed_force_only_tol_0.001", "compressed_force_only_tol_1e-05", "compressed_full_update_tol_1e-05",
        "compressed_force_only_tol_0.001_f16factors", "compressed_full_update_tol_0.001_f16factors"]
    def table(cell):
        """One row per method, one column per size; cell(v, n) formats a row's values."""
        print("| method | " + " | ".join(str(n) for n in sizes) + " |")
        print("|---|" + "---|" * len(sizes))
        for m in methods:
            cells = []
            for n in sizes:
                v = rows.get(m, {}).get(n)
                cells.append("-" if v is None else cell(v, n))
            print(f"| {m} | " + " | ".join(cells) + " |")

    table(lambda v, n: f"{v[1]:.3g}" if v[1] < 1e4 else f"{v[1] / 1e3:.3g} ms")
    print()
    print("| method | worst rel_error |")
    print("|---|---|")
    for m in sorted(rows):
        print(f"| {m} | {max(v[2] for v in rows[m].values()):.2e} |")
    print()
    print("Model rows (the part's compliance nodes; error against CalculiX neo-Hooke):")
    print("| method | nodes | most patch nodes | median [us] | p99 [us] | force error |")
    print("|---|---|---|---|---|---|")
    for m in sorted(k for k in rows if k.startswith("model_")):
        for n, v in sorted(rows[m].items()):
            print(f"| {m} | {n} | {v[0]} | {v[1]:.3g} | {v[3]:.3g} | {100 * v[2]:.1f} % |")
    print()
    print("p99 [us] and storage [bytes / N^2]:")
    table(lambda v, n: "-" if v[3] is None else f"{v[3]:.3g} / {v[4] / (n * n):.3g}")


def main():
    if len(sys.argv) != 3:
        sys.exit(__doc__)
    rows = load(sys.argv[1])
    fig10(rows, f"{sys.argv[2]}/fem_fig10.png")
    error_vs_time(rows, f"{sys.argv[2]}/fem_error_vs_time.png")
    tables(rows)


if __name__ == "__main__":
    main()
