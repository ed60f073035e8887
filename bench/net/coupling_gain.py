#!/usr/bin/python3
"""What the event-driven coupling gains a jointly pressed tail: tests/net/net_dds_test.py's
delayed_tail press (alice and bob at simulated HIRO IIs press the triceratops tail, each 1 mm
deeper in turn while the other holds still, then both hold) at 0 ms between the nodes, with the
haptic nodes' coupling `polled` (before: contact sets leave and are taken at the bridge's 100 Hz
tick) and `woken` (after), alternately, with the two nodes on one host (shared memory between
them) and on two network namespaces (UDP over veth). A bench: it asserts nothing.

Per session and user it writes the stiffness felt (force change over fingertip depth change
between the press's holds), the force while both hold still, its RMS above 5 Hz and its swing
(ripple), and what the coupling's passivity controller had to do: the coupling-steps it held a
displacement back (and per second of coupling), the energy the channels absorbed
(E_tx + E_grant - E_rx, from the node's exit line; per second of coupling), its observer's lowest
value, the largest position drift it made, and what it granted at rest.

Then the hand-over of tests/net/net_dds_test.py's handover case (alice lifts the Moon's ball,
bob grasps it, alice lets go, the server hands it to bob) at 0 and 50 ms one-way, polled and
woken alternately: when the server handed it over and when bob's node could have it (seconds
after alice's hand began to open), how far the ball went from where alice held it until then
and until bob lifted it, the speed it was handed over at, bob's held weight against m g and his
lift.

usage: coupling_gain.py --bin-dir BUILD --nfq-delay BUILD/tests/nfq_delay --work DIR
                        [--pairs N] [--handover-pairs N] [--domain D] [--csv OUT.csv] [--png OUT.png]
                        [--handover-csv OUT.csv]
(run as root: it builds network namespaces; the haptic loops run SCHED_FIFO when permitted)
"""
import argparse
import csv
import datetime
import os
import sys

HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, os.path.join(HERE, "..", "..", "tests", "net"))
import net_dds_test  # noqa: E402
from netharness import Network  # noqa: E402

COLUMNS = ("run", "utc", "load1", "placement", "coupling", "user", "k_N_per_m", "force_N", "hf_rms_N", "swing_N",
           "held_back", "held_back_per_s", "absorbed_J", "absorbed_J_per_s", "observer_min_J", "drift_max_mm",
           "granted_J", "coupling_s", "field_converged_s", "loop_Hz", "faults")


HANDOVER_COLUMNS = ("run", "utc", "load1", "delay_ms", "coupling", "t_handed_s", "t_bob_s", "hold_far_mm", "far_mm",
                    "handed_speed_m_per_s", "weight_error_pct", "rise_mm")


def row_of(run, placement, coupling, r):
    coupling_s = 1e-3 * r["coupling_steps"]  # the nodes' loops run at 1 kHz
    absorbed = r["energy_sent_J"] + r["granted_J"] - r["energy_received_J"]
    return {"run": run, "utc": datetime.datetime.utcnow().strftime("%H:%M:%S"),
            "load1": os.getloadavg()[0], "placement": placement, "coupling": coupling, "user": r["user"],
            "k_N_per_m": r["k_N_per_m"], "force_N": r["force_N"], "hf_rms_N": r["hf_rms_N"], "swing_N": r["swing_N"],
            "held_back": r["held_back"], "held_back_per_s": r["held_back"] / max(coupling_s, 1e-9),
            "absorbed_J": absorbed, "absorbed_J_per_s": absorbed / max(coupling_s, 1e-9),
            "observer_min_J": r["observer_min_J"], "drift_max_mm": r["drift_max_mm"], "granted_J": r["granted_J"],
            "coupling_s": coupling_s, "field_converged_s": r["field_converged_s"], "loop_Hz": r["loop_Hz"],
            "faults": r["faults"]}


def write_csv(path, columns, rows):
    with open(path, "w", newline="") as f:
        w = csv.DictWriter(f, fieldnames=columns)
        w.writeheader()
        for r in rows:
            w.writerow({k: (f"{v:.6g}" if isinstance(v, float) else v) for k, v in r.items()})


def plot(rows, out):
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    metrics = (("k_N_per_m", "stiffness felt [N/m]", 1.0), ("hf_rms_N", "force RMS above 5 Hz, both holding [mN]", 1e3),
               ("swing_N", "force swing, both holding [mN]", 1e3),
               ("held_back_per_s", "controller: held-back steps per s of coupling", 1.0),
               ("absorbed_J_per_s", "controller: energy absorbed per s [mJ/s]", 1e3),
               ("drift_max_mm", "controller: largest drift [mm]", 1.0))
    fig, axes = plt.subplots(1, len(metrics), figsize=(4 * len(metrics), 4.2))
    groups = [(p, c) for p in ("one host", "namespaces") for c in ("polled", "woken")]
    for ax, (key, title, scale) in zip(axes, metrics):
        for gi, (p, c) in enumerate(groups):
            for ui, (u, marker) in enumerate((("alice", "o"), ("bob", "s"))):
                ys = [scale * float(r[key]) for r in rows if r["placement"] == p and r["coupling"] == c and r["user"] == u]
                ax.plot([gi + 0.15 * (ui - 0.5)] * len(ys), ys, marker, color="tab:red" if c == "polled" else "tab:blue",
                        alpha=0.7, label=u if (key == "k_N_per_m" and gi == 0) else None)
        ax.set_xticks(range(len(groups)))
        ax.set_xticklabels([f"{p}\n{c}" for p, c in groups], fontsize=7)
        ax.set_title(title, fontsize=8)
    axes[0].legend(fontsize=7)
    fig.suptitle("the tail pressed by two users at 0 ms between nodes: coupling polled (before, red) and woken "
                 "(after, blue)", fontsize=9)
    fig.tight_layout()
    fig.savefig(out, dpi=110)


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--bin-dir", required=True)
    ap.add_argument("--nfq-delay", required=True)
    ap.add_argument("--work", required=True)
    ap.add_argument("--domain", type=int, default=96)
    ap.add_argument("--pairs", type=int, default=3, help="before/after pairs per placement")
    ap.add_argument("--csv", default="")
    ap.add_argument("--png", default="")
    ap.add_argument("--handover-pairs", type=int, default=2)
    ap.add_argument("--handover-csv", default="")
    args = ap.parse_args()
    rows, handovers = [], []
    with Network(3, nfq_delay=args.nfq_delay) as net:
        for run in range(args.pairs):
            for placement in ("one host", "namespaces"):
                # Alternate which goes first, so a drift in the machine's load favours neither.
                order = ("polled", "woken") if run % 2 == 0 else ("woken", "polled")
                for coupling in order:
                    results, _, _, _ = net_dds_test.measure_delayed_tail(args, net, (0,), coupling,
                                                                        one_host=placement == "one host")
                    for r in results:
                        rows.append(row_of(run, placement, coupling, r))
                        x = rows[-1]
                        print(f"{x['utc']} load {x['load1']:.2f} {placement:10s} {coupling:6s} {x['user']:5s} "
                              f"k {x['k_N_per_m']:7.1f} N/m  rms>5Hz {1e3 * x['hf_rms_N']:.3f} mN  "
                              f"swing {1e3 * x['swing_N']:.2f} mN  held back {x['held_back']} "
                              f"({x['held_back_per_s']:.1f}/s)  absorbed {1e3 * x['absorbed_J_per_s']:.4f} mJ/s  "
                              f"observer min {x['observer_min_J']:.2e} J  drift {x['drift_max_mm']:.3f} mm",
                              flush=True)
        for run in range(args.handover_pairs):
            for delay_ms in (0, 50):
                order = ("polled", "woken") if run % 2 == 0 else ("woken", "polled")
                for coupling in order:
                    m = net_dds_test.measure_handover(args, net, delay_ms, coupling)
                    x = {"run": run, "utc": datetime.datetime.utcnow().strftime("%H:%M:%S"),
                         "load1": os.getloadavg()[0], "delay_ms": delay_ms, "coupling": coupling,
                         "t_handed_s": m["t_handed_s"], "t_bob_s": m["t_bob_s"], "hold_far_mm": 1e3 * m["hold_far_m"],
                         "far_mm": 1e3 * m["far_m"], "handed_speed_m_per_s": m["handed_speed"],
                         "weight_error_pct": 100.0 * (m["weight_N"] / m["mg_N"] - 1.0), "rise_mm": 1e3 * m["rise_m"]}
                    handovers.append(x)
                    print(f"{x['utc']} load {x['load1']:.2f} hand-over {delay_ms:3d} ms {coupling:6s} handed at "
                          f"{x['t_handed_s']:.3f} s, bob's at {x['t_bob_s']:.3f} s, held within {x['hold_far_mm']:.3f} mm, "
                          f"until his lift {x['far_mm']:.3f} mm, handed at {x['handed_speed_m_per_s']:.1e} m/s, "
                          f"weight {x['weight_error_pct']:+.2f} %, lift {x['rise_mm']:.1f} mm", flush=True)
    if args.handover_csv:
        write_csv(args.handover_csv, HANDOVER_COLUMNS, handovers)
    if args.csv:
        write_csv(args.csv, COLUMNS, rows)
    if args.png:
        plot(rows, args.png)
    return 0


if __name__ == "__main__":
    sys.exit(main())
