#!/usr/bin/python3
"""Plots the 2D dam-break front and column height against Koshizuka & Oka (1996).

Usage: /usr/bin/python3 app/plot_dam_break.py OUT.png RUN_DIR[:label] [RUN_DIR[:label] ...]
Each RUN_DIR is a `sphdem run` output folder of inputs/dam_break_2d.yaml (front.csv and
column_height.csv). Needs Debian's python3-matplotlib.
"""
import csv
import math
import os
import sys

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402

L = 0.146
G = 9.81
REF = os.path.join(os.path.dirname(__file__), "..", "tests", "data", "reference", "dambreak_2d")


def read(path, tcol=0, vcol=1):
    xs, ys = [], []
    with open(path) as f:
        for row in csv.reader(f):
            if not row or row[0].startswith("#"):
                continue
            try:
                xs.append(float(row[tcol]))
                ys.append(float(row[vcol]))
            except ValueError:
                continue
    return xs, ys


def interp(x, xs, ys):
    for i in range(1, len(xs)):
        if x <= xs[i]:
            return ys[i - 1] + (ys[i] - ys[i - 1]) * (x - xs[i - 1]) / (xs[i] - xs[i - 1])
    return ys[-1]


def main():
    out = sys.argv[1]
    runs = sys.argv[2:]
    ts = math.sqrt(2 * G / L)
    fig, (a1, a2) = plt.subplots(1, 2, figsize=(11, 4.2))
    t, z = read(os.path.join(REF, "koshizuka_oka1996_surge_front_L0.146.csv"))
    a1.plot(t, z, "ko", label="Koshizuka & Oka (1996)")
    t, z = read(os.path.join(REF, "mm1952_surge_front_n2sq2_a2.25in_table.csv"))
    a1.plot(t, z, "k^", mfc="none", label="Martin & Moyce (1952)")
    t, h = read(os.path.join(REF, "koshizuka_oka1996_column_height_smoothedparticles.csv"))
    a2.plot(t, h, "ko", label="Koshizuka & Oka (1996)")
    rt, rz = read(os.path.join(REF, "koshizuka_oka1996_surge_front_L0.146.csv"))
    for spec in runs:
        d, _, label = spec.partition(":")
        t, x = read(os.path.join(d, "front.csv"))
        # Front error against Koshizuka & Oka for 1 <= T <= 3 (same measure as the ctest).
        errs = []
        for ti, xi in zip(t, x):
            T = ti * ts
            if 1 <= T <= 3:
                zr = interp(T, rt, rz)
                errs.append((xi / L - zr) / zr)
        if errs:
            rms = math.sqrt(sum(e * e for e in errs) / len(errs))
            print(f"{label or d}: front vs K&O, 1<=T<=3: max {max(abs(e) for e in errs):.3f}, "
                  f"rms {rms:.3f}, mean {sum(errs) / len(errs):+.3f}")
        a1.plot([v * ts for v in t], [v / L for v in x], "-", label=label or d)
        t, h = read(os.path.join(d, "column_height.csv"))
        a2.plot([v * ts for v in t], [v / (2 * L) for v in h], "-", label=label or d)
    a1.set_xlabel("T = t sqrt(2g/L)")
    a1.set_ylabel("Z = x_front / L")
    a1.set_xlim(0, 3.2)
    a1.legend(fontsize=8)
    a2.set_xlabel("T = t sqrt(2g/L)")
    a2.set_ylabel("H = h / 2L at x = 0.01 m")
    a2.set_xlim(0, 3.2)
    a2.legend(fontsize=8)
    fig.tight_layout()
    fig.savefig(out, dpi=110)


if __name__ == "__main__":
    main()
