#!/usr/bin/python3
"""Speed against accuracy for the Bingham channel: plug-width error and velocity L2 error against
wall time, one point per Papanastasiou m (from the ctest study Bingham.DISABLED_SweepM).

Usage: /usr/bin/python3 app/plot_speed_accuracy.py bingham_m_sweep.csv OUT.png
"""
import csv
import sys

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402


def main():
    rows = list(csv.DictReader(open(sys.argv[1])))
    wall = [float(r["wall_s"]) for r in rows]
    plug = [abs(float(r["plug_half"]) / float(r["plug_exact"]) - 1) * 100 for r in rows]
    l2 = [float(r["l2"]) * 100 for r in rows]
    fig, ax = plt.subplots(figsize=(6, 4.2))
    ax.loglog(wall, plug, "o-", label="plug half-width error")
    ax.loglog(wall, l2, "s-", label="velocity L2 error")
    for w, p, r in zip(wall, plug, rows):
        ax.annotate(f"m = {r['m']} s", (w, p), textcoords="offset points", xytext=(4, 4), fontsize=8)
    ax.set_xlabel("wall time to t = 0.5 s (s, 1 CPU thread)")
    ax.set_ylabel("error (%)")
    ax.set_title("Bingham channel, 20 particles across")
    ax.legend()
    ax.grid(True, which="both", alpha=0.3)
    fig.tight_layout()
    fig.savefig(sys.argv[2], dpi=110)


if __name__ == "__main__":
    main()
