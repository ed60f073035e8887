#!/usr/bin/python3
"""Fits the stiffening law of the haptic world's large-deformation correction to CalculiX.

usage: /usr/bin/python3 fit_stiffening.py NODES.csv [OUT.csv]

NODES.csv is `fem_accuracy --reference-only --nodes-csv`: for every converged press of the
rubber-like parts (tail, head, leg, belly against a neo-Hookean solid of the same small-strain
moduli), each held node's self-compliance along the finger's normal c = n^T C_kk n, its linear
reaction f (the force the linear model puts on the node) and the neo-Hookean one.

The law: each held node's force is scaled by g(eps) = 1 + a eps + b eps^2, where
eps = E c^2 max(0, -f.n) is the node's local compressive strain as the linear model has it (a
node's push over the area its own compliance spans: for a single held node eps = E c delta, its
depth over the size of the elements around it). The corrected press force is sum_k g(eps_k) f_k;
(a, b) minimise the squared relative error of that sum against the neo-Hookean press force over
the fitted parts' presses (linear least squares, each press weighted by 1 / |F|^2).

Prints the law fitted on all four parts and, for each part, the law fitted on the other three
and its errors on that part (the part it was not fitted to), beside the linear model's: the
press force error per press and depth. OUT.csv gets those rows (part, press, depth_mm,
err_linear, err_corrected_loo, err_corrected_all).
"""

import csv
import sys
from collections import defaultdict

import numpy as np

PARTS = ["tail", "head", "leg", "belly"]


def load(path):
    presses = defaultdict(list)
    with open(path) as f:
        for r in csv.DictReader(f):
            if r["model"] != "neo_hooke":
                continue
            key = (r["part"], r["press"], float(r["depth_mm"]))
            n = np.array([float(r["nx"]), float(r["ny"]), float(r["nz"])])
            fl = np.array([float(r["f_lin_x_N"]), float(r["f_lin_y_N"]), float(r["f_lin_z_N"])])
            fm = np.array([float(r["f_model_x_N"]), float(r["f_model_y_N"]), float(r["f_model_z_N"])])
            E, c = float(r["E_Pa"]), float(r["c_nn_m_per_N"])
            eps = E * c * c * max(0.0, -fl.dot(n))
            presses[key].append((eps, fl, fm))
    return presses


def design(nodes):
    # F_corr - F_lin = a sum eps f + b sum eps^2 f: two 3-vectors, and the target F_model - F_lin.
    f1 = sum(e * fl for e, fl, _ in nodes)
    f2 = sum(e * e * fl for e, fl, _ in nodes)
    F_lin = sum(fl for _, fl, _ in nodes)
    F_mod = sum(fm for _, _, fm in nodes)
    return np.column_stack([f1, f2]), F_mod - F_lin, F_lin, F_mod


def fit(presses, parts):
    A, y = [], []
    for (part, _, _), nodes in presses.items():
        if part not in parts:
            continue
        M, t, _, F_mod = design(nodes)
        w = 1.0 / np.linalg.norm(F_mod)
        A.append(w * M)
        y.append(w * t)
    coef, *_ = np.linalg.lstsq(np.vstack(A), np.concatenate(y), rcond=None)
    return coef


def errors(nodes, coef):
    M, _, F_lin, F_mod = design(nodes)
    F_corr = F_lin + M @ coef
    den = np.linalg.norm(F_mod)
    return np.linalg.norm(F_lin - F_mod) / den, np.linalg.norm(F_corr - F_mod) / den


def main():
    presses = load(sys.argv[1])
    coef_all = fit(presses, PARTS)
    print(f"fitted on {', '.join(PARTS)}: a = {coef_all[0]:.6g}, b = {coef_all[1]:.6g}")
    eps_max = max(e for nodes in presses.values() for e, _, _ in nodes)
    print(f"largest node strain eps in the data: {eps_max:.3g}")
    out = []
    for part in PARTS:
        coef = fit(presses, [p for p in PARTS if p != part])
        print(f"\n{part}: fitted on the others: a = {coef[0]:.6g}, b = {coef[1]:.6g}")
        print("| press | depth [mm] | linear | corrected (not fitted to it) | corrected (fitted on all) |")
        for key in sorted(k for k in presses if k[0] == part):
            e_lin, e_loo = errors(presses[key], coef)
            _, e_all = errors(presses[key], coef_all)
            print(f"| {key[1]} | {key[2]:g} | {100 * e_lin:.1f} % | {100 * e_loo:.1f} % | {100 * e_all:.1f} % |")
            out.append((part, key[1], key[2], e_lin, e_loo, e_all))
    if len(sys.argv) > 2:
        with open(sys.argv[2], "w") as f:
            f.write("part,press,depth_mm,err_linear,err_corrected_loo,err_corrected_all\n")
            for r in out:
                f.write(f"{r[0]},{r[1]},{r[2]:g},{r[3]:.6g},{r[4]:.6g},{r[5]:.6g}\n")


if __name__ == "__main__":
    main()
