#!/usr/bin/python3
"""Plots particle pressure against rho0 g (H - z) from hydrostatic_profile.csv.

Usage: /usr/bin/python3 app/plot_hydrostatic.py hydrostatic_profile.csv OUT.png
The CSV is written by the ctest TankLeak.ThreeLayerWallHoldsForTenSeconds (in build/tests).
"""
import csv
import sys

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402


def main():
    z, p, pe = [], [], []
    with open(sys.argv[1]) as f:
        for row in csv.DictReader(f):
            z.append(float(row["z"]))
            p.append(float(row["p"]))
            pe.append(float(row["p_exact"]))
    fig, ax = plt.subplots(figsize=(5, 4.5))
    ax.plot(p, z, ".", ms=2, label="sphdem particles (t = 10 s)")
    order = sorted(range(len(z)), key=lambda i: z[i])
    ax.plot([pe[i] for i in order], [z[i] for i in order], "k-", label="rho0 g (H - z)")
    ax.set_xlabel("pressure (Pa)")
    ax.set_ylabel("z (m)")
    ax.legend()
    fig.tight_layout()
    fig.savefig(sys.argv[2], dpi=110)


if __name__ == "__main__":
    main()
