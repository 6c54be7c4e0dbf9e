#!/usr/bin/python3
"""Bingham and Herschel-Bulkley channel: binned SPH velocity profile against the exact one
(FORMULAS.md §4), with the same channel run without the yield term.

Usage: /usr/bin/python3 app/plot_bingham.py DIR OUT.png
DIR holds the CSVs (z,u,u_exact) written by the ctest Bingham.* in the working directory:
bingham_profile.csv, bingham_noyield_profile.csv, hb_profile.csv, hb_noyield_profile.csv.
"""
import csv
import os
import sys

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402


def read(path):
    if not os.path.exists(path):
        return None
    rows = list(csv.DictReader(open(path)))
    return ([1e3 * float(r["z"]) for r in rows], [1e3 * float(r["u"]) for r in rows],
            [1e3 * float(r["u_exact"]) for r in rows])


def main():
    d, out = sys.argv[1], sys.argv[2]
    fig, axes = plt.subplots(1, 2, figsize=(9, 4), sharey=True)
    cases = [("Bingham, $\\tau_0$ = 0.245 Pa", "bingham", 1.5),
             ("Herschel-Bulkley n = 0.8, $\\tau_0$ = 0.2 Pa", "hb", 1.227)]
    for ax, (title, stem, y0) in zip(axes, cases):
        p = read(os.path.join(d, stem + "_profile.csv"))
        q = read(os.path.join(d, stem + "_noyield_profile.csv"))
        if p:
            z, u, ue = p
            ax.plot(ue, z, "k-", lw=1.2, label="exact")
            ax.plot(u, z, "o", ms=3.5, mfc="none", color="C0", label="sphdem (binned)")
        if q:
            z, u, _ = q
            ax.plot(u, z, "x", ms=3.5, color="C3", label="sphdem, yield term removed")
        ax.axhspan(-y0, y0, color="0.9", zorder=0, label="exact plug")
        ax.set_title(title, fontsize=10)
        ax.set_xlabel("u (mm/s)")
        ax.legend(fontsize=8, loc="lower right")
    axes[0].set_ylabel("z (mm)")
    fig.tight_layout()
    fig.savefig(out, dpi=110)


if __name__ == "__main__":
    main()
