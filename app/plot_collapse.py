#!/usr/bin/python3
"""Final heap of the 2D column collapse.

Top: the particles of the first CSV at their initial positions, marked moved (displacement over
2.5 mm at the end of the collapse, i.e. yielded) or unmoved, the initial column, the Rankine
failure line 45 + phi/2 and the run-out of the Lube et al. (2005) law. The end of the collapse
is when the kinetic energy fell back below 1e-3 m g H0 (column displacement_at_stop; the final
displacement where the CSV has no such column or the heap never stopped).
Bottom: the final free surface of every CSV given (top of the particles per x bin).

Usage: /usr/bin/python3 app/plot_collapse.py OUT.png FINAL.csv:label [FINAL.csv:label ...]
The CSVs (x0,z0,x,z,displacement[,displacement_at_stop]) are written by the ctest
ColumnCollapse.* in the working directory (column_collapse_<tag>_final.csv).

Chart: /usr/bin/python3 app/plot_collapse.py --chart STUDY.csv OUT.png
STUDY.csv (docs/column_collapse_study.csv) has columns
case,dp,m,mu_max,k,slip,overrides,runout,height,failure_deg,t_stop,t_rest,ke_end,steps,wall_s;
the chart is run-out and
H/H0 against steps, with the reference values.
"""
import csv
import math
import sys

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402

PHI = 19.8
L0, H0 = 0.2, 0.1
MOVED = 0.0025


def read(path):
    rows = list(csv.DictReader(open(path)))
    key = "displacement_at_stop" if "displacement_at_stop" in rows[0] else "displacement"
    return ([float(r["x"]) for r in rows], [float(r["z"]) for r in rows],
            [float(r[key]) for r in rows], [float(r["x0"]) for r in rows],
            [float(r["z0"]) for r in rows])


def surface(x, z, dx):
    top = {}
    for xi, zi in zip(x, z):
        b = int(xi // dx)
        top[b] = max(top.get(b, 0.0), zi)
    bs = sorted(top)
    return [(b + 0.5) * dx for b in bs], [top[b] + 0.5 * dx for b in bs]


def failure_angle(x0, z0, d, dp):
    """Same definition as tests/validation/test_column_collapse.cpp: per initial row, the
    outermost unmoved particle of the unbroken unmoved run from the wall; NaN without a wedge."""
    rows = {}
    for a, b, c in zip(x0, z0, d):
        rows.setdefault(round(b / dp - 0.5), []).append((a, c))
    zs, xs, in_range = [], [], 0
    for row, line in rows.items():
        z = (row + 0.5) * dp
        if z < 0.1 * H0 or z > 0.9 * H0:
            continue
        in_range += 1
        edge, count = -1, 0
        for a, c in sorted(line):
            if c >= MOVED:
                break
            edge, count = a, count + 1
        if count >= 2:
            zs.append(z)
            xs.append(edge)
    if 2 * len(zs) <= in_range:
        return float("nan")
    n = len(zs)
    sz, sx = sum(zs), sum(xs)
    szz = sum(v * v for v in zs)
    szx = sum(a * b for a, b in zip(zs, xs))
    dxdz = (n * szx - sz * sx) / (n * szz - sz * sz)
    return math.degrees(math.atan2(1.0, -dxdz))


def main():
    out = sys.argv[1]
    cases = []
    for arg in sys.argv[2:]:
        path, _, label = arg.partition(":")
        cases.append((read(path), label or path))
    fig, (ax, ax2) = plt.subplots(2, 1, figsize=(9, 6.2), sharex=True)
    (x, z, d, x0, z0), label = cases[0]
    dp = 2 * min(z0)  # the lowest row sits at dp/2
    moved = [v > MOVED for v in d]
    ax.scatter([a for a, m in zip(x0, moved) if m], [b for b, m in zip(z0, moved) if m], s=5,
               c="tab:orange", label="moved > 2.5 mm by the end of the collapse (yielded)")
    ax.scatter([a for a, m in zip(x0, moved) if not m], [b for b, m in zip(z0, moved) if not m],
               s=5, c="tab:blue", label="unmoved")
    ang_s = failure_angle(x0, z0, d, dp)
    ax.plot([0, L0, L0], [H0, H0, 0], "k--", lw=1, label="initial column")
    ang = math.radians(45 + PHI / 2)
    ax.plot([L0, L0 - H0 / math.tan(ang)], [0, H0], "r-", lw=1,
            label=f"Rankine line {45 + PHI / 2:.1f} deg")
    ax.axvline(L0 * (1 + 1.2 * H0 / L0), color="g", ls=":", lw=1,
               label="Lube et al. 2005 run-out")
    ax.set_title(f"{label}: initial positions, failure line {ang_s:.1f} deg", fontsize=10)
    ax.set_aspect("equal")
    ax.set_ylim(0, 0.12)
    ax.set_ylabel("z (m)")
    ax.legend(fontsize=7, loc="upper right")
    for (x, z, d, x0, z0), lab in cases:
        print(f"{lab}: failure line {failure_angle(x0, z0, d, 2 * min(z0)):.1f} deg")
        sx, sz = surface(x, z, 2 * 2 * min(z0))
        ax2.plot(sx, sz, "-", lw=1.2, label=lab)
    ax2.plot([0, L0, L0], [H0, H0, 0], "k--", lw=1, label="initial column")
    ax2.axvline(L0 * (1 + 1.2 * H0 / L0), color="g", ls=":", lw=1, label="Lube run-out")
    ax2.axhline(H0, color="0.5", ls=":", lw=1)
    ax2.set_aspect("equal")
    ax2.set_xlim(0, 0.5)
    ax2.set_ylim(0, 0.12)
    ax2.set_xlabel("x (m)")
    ax2.set_ylabel("final surface z (m)")
    ax2.legend(fontsize=7, loc="upper right")
    fig.tight_layout()
    fig.savefig(out, dpi=110)


def chart(study, out):
    rows = [r for r in csv.DictReader(open(study)) if not r["case"].startswith("#")]
    fig, axes = plt.subplots(1, 2, figsize=(10, 4))
    for ax, key, ref, tol, name in [(axes[0], "runout", 0.6, 0.2, "(L$_\\infty$ - L0)/L0"),
                                    (axes[1], "height", 1.0, 0.1, "H$_\\infty$/H0")]:
        ax.axhspan(ref * (1 - tol), ref * (1 + tol), color="0.9", label=f"reference $\\pm${tol:.0%}")
        ax.axhline(ref, color="g", lw=1)
        for dpv, mk in (("0.005", "o"), ("0.0025", "s")):
            sel = [r for r in rows if r["dp"] == dpv]
            for r in sel:
                ax.plot(float(r["steps"]), float(r[key]), mk, ms=6,
                        color="C3" if r["slip"] != "noslip" else
                        "C2" if r.get("p_min") == "0" else "C0")
                ax.annotate(r["case"], (float(r["steps"]), float(r[key])), fontsize=6,
                            xytext=(3, 3), textcoords="offset points")
        ax.set_xscale("log")
        ax.set_xlabel("steps (o: dp 5 mm, square: 2.5 mm)\n"
                      "blue: no tension floor, green: p_min = 0, red: free-slip floor", fontsize=8)
        ax.set_ylabel(name)
        ax.legend(fontsize=7)
    axes[0].set_title("run-out; reference Lube et al. 2005", fontsize=9)
    axes[1].set_title("final height at the wall; reference Nguyen et al. 2015", fontsize=9)
    fig.tight_layout()
    fig.savefig(out, dpi=110)


if __name__ == "__main__":
    if sys.argv[1] == "--chart":
        chart(sys.argv[2], sys.argv[3])
    else:
        main()
