#!/usr/bin/env python3
"""Final heap of a grain-only run (rock collapse): side view of the grains' surface nodes with the
fitted repose angle, and the kinetic energy over time.

usage: python3 app/plot_heap.py RUN_DIR [OUT.png]
Reads RUN_DIR/final_nodes.csv, heap.json and grains.csv (written by `sphdem run` when the scene
has a dem.heap section).
"""
import csv
import json
import math
import sys

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402


def main():
    run = sys.argv[1]
    out = sys.argv[2] if len(sys.argv) > 2 else run + "/heap.png"
    with open(run + "/heap.json") as f:
        heap = json.load(f)
    xs, ys, zs = [], [], []
    with open(run + "/final_nodes.csv") as f:
        for row in csv.DictReader(f):
            xs.append(float(row["x"]))
            ys.append(float(row["y"]))
            zs.append(float(row["z"]))
    t, ke = [], []
    with open(run + "/grains.csv") as f:
        for row in csv.DictReader(f):
            t.append(float(row["t"]))
            ke.append(float(row["kinetic_energy"]))

    fig, (a, b) = plt.subplots(1, 2, figsize=(12, 4.2), gridspec_kw={"width_ratios": [2.2, 1]})
    a.scatter([100 * x for x in xs], [100 * z for z in zs], c=[100 * y for y in ys], s=0.3,
              cmap="viridis")
    toe, ang = heap["toe"], heap["repose_deg"]
    for angle, style, label in ((ang, "r-", f"fitted {ang:.1f}°"), (31.0, "k--", "seed 31°")):
        tn = math.tan(math.radians(angle))
        x0 = max(0.0, toe - heap["height"] / tn)
        a.plot([100 * x0, 100 * toe], [100 * (toe - x0) * tn, 0], style, lw=1.2, label=label)
    a.axvline(5.0, color="grey", lw=0.8, ls=":")
    a.text(5.2, 100 * heap["height"] * 1.02, "baffle", color="grey", fontsize=8)
    a.set_xlim(0, 35)
    a.set_ylim(0, max(15, 100 * heap["height"] * 1.15))
    a.set_aspect("equal")
    a.set_xlabel("x [cm]")
    a.set_ylabel("z [cm]")
    a.set_title(f"final heap: repose {ang:.1f}°, run-out {100 * heap['runout']:.1f} cm from "
                "the baffle (colour: y)")
    a.legend(loc="upper right", fontsize=8)
    b.semilogy(t, [max(k, 1e-12) for k in ke], "b-", lw=1)
    b.set_xlabel("t [s]")
    b.set_ylabel("kinetic energy [J]")
    b.set_title("grains' kinetic energy")
    b.grid(alpha=0.3)
    fig.tight_layout()
    fig.savefig(out, dpi=130)
    print("wrote", out)


if __name__ == "__main__":
    main()
