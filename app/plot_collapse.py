#!/usr/bin/python3
"""Final heap of the 2D column collapse: particles coloured by displacement (static = the
unyielded region), the initial column, and the Rankine failure line 45 + phi/2.

Usage: /usr/bin/python3 app/plot_collapse.py column_collapse_final.csv OUT.png [phi_deg]
The CSV is written by the ctest ColumnCollapse.* (disabled study) in build/tests.
"""
import csv
import math
import sys

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402


def main():
    rows = list(csv.DictReader(open(sys.argv[1])))
    phi = float(sys.argv[3]) if len(sys.argv) > 3 else 19.8
    x = [float(r["x"]) for r in rows]
    z = [float(r["z"]) for r in rows]
    d = [float(r["displacement"]) for r in rows]
    fig, ax = plt.subplots(figsize=(9, 3.2))
    sc = ax.scatter(x, z, c=[min(v, 0.05) for v in d], s=4, cmap="viridis")
    fig.colorbar(sc, ax=ax, label="displacement (m, capped at 0.05)")
    ax.plot([0, 0.2, 0.2], [0.1, 0.1, 0], "k--", lw=1, label="initial column")
    ang = math.radians(45 + phi / 2)
    ax.plot([0.2, 0.2 - 0.1 / math.tan(ang)], [0, 0.1], "r-", lw=1,
            label=f"Rankine line {45 + phi / 2:.1f} deg")
    ax.set_aspect("equal")
    ax.set_xlim(0, 0.5)
    ax.set_ylim(0, 0.12)
    ax.set_xlabel("x (m)")
    ax.set_ylabel("z (m)")
    ax.legend(fontsize=8, loc="upper right")
    fig.tight_layout()
    fig.savefig(sys.argv[2], dpi=110)


if __name__ == "__main__":
    main()
