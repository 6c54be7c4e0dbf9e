#!/usr/bin/env python3
"""Stability map of the 2D dam break (issue #9): CFL number x density diffusion delta x
resolution. Each run ends `completed` or with the guard that stopped it (DESIGN.md §7), read from
the run's summary.json. Writes CSV rows and, with --plot, the map.

  python3 jobs/stability_map.py --out out/stability_map [--end 0.6] [--jobs 2]
  python3 jobs/stability_map.py --out out/stability_map --plot docs/figures/stability_map.png

With --dem, the DEM half: contact stiffness kn x dem.dt_factor on the 300-bead pile
(inputs/sphere_pile.yaml, 0.5 s). Each run ends at rest, or with the guard that stopped it; a run
that completes also records its final kinetic energy and pile height (the height against the
run at the smallest step of the same kn shows a step that is stable but wrong).

  python3 jobs/stability_map.py --dem --out out/dem_map [--jobs 2]
  python3 jobs/stability_map.py --dem --out out/dem_map --plot docs/figures/dem_stability_map.png

Runs whose result is already in OUT/map.csv are not repeated.
"""
import argparse
import csv
import itertools
import json
import os
import subprocess
import sys
from concurrent.futures import ThreadPoolExecutor

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
L = 0.146
CFLS = [0.1, 0.2, 0.3, 0.5]
DELTAS = [0.0, 0.05, 0.1]
RES = [20, 30]  # dp = L / RES

KNS = [20.0, 500.0, 2e3, 2e4, 2e5]  # N/m, grain-grain and grain-wall
DT_FACTORS = [0.5, 1.0, 2.0, 5.0, 10.0, 20.0, 40.0]  # dt = dt_factor t_c / 50
DEM_FIELDS = ["kn", "dt_factor", "result", "t_end", "steps", "wall", "ke_end", "top_z",
              "max_overlap_per_d", "failure"]

GUARDS = [("DEM overlap", "overlap"), ("left the domain", "left"), ("non-finite", "nan"),
          ("NaN or Inf", "nan"), ("density out of bounds", "density"),
          ("Mach number too high", "mach"), ("fluid inside a solid", "penetration"),
          ("time step at its floor", "dt_floor")]


def classify(summary):
    status = summary.get("status", "?")
    if status == "completed":
        return "stable", ""
    failure = summary.get("failure", "")
    for text, name in GUARDS:
        if text in failure:
            return name, failure
    return status, failure


def run_one(args, cfl, delta, res):
    name = f"cfl{cfl}_delta{delta}_L{res}"
    out = os.path.join(args.out, name)
    sets = [f"time.cfl={cfl}", f"fluid.diffusion.delta={delta}", f"sph.dp={L / res:.10g}",
            f"time.end={args.end}"]
    if delta == 0:
        sets[1] = "fluid.diffusion.model=none"
    cmd = [args.sphdem, "run", os.path.join(ROOT, "inputs/dam_break_2d.yaml"), "--out", out,
           "--quiet"]
    for s in sets:
        cmd += ["--set", s]
    env = dict(os.environ, OMP_NUM_THREADS="1")
    p = subprocess.run(cmd, env=env, capture_output=True, text=True)
    try:
        with open(os.path.join(out, "summary.json")) as f:
            summary = json.load(f)
    except (OSError, ValueError):
        return dict(cfl=cfl, delta=delta, res=res, result="error", t_end=0, steps=0, wall=0,
                    failure=(p.stderr or p.stdout).strip().splitlines()[-1:])
    result, failure = classify(summary)
    return dict(cfl=cfl, delta=delta, res=res, result=result, t_end=summary["sim_time"],
                steps=summary["steps"], wall=summary["wall_seconds"], failure=failure)


def run_dem(args, kn, f):
    out = os.path.join(args.out, f"kn{kn:g}_f{f:g}")
    cmd = [args.sphdem, "run", os.path.join(ROOT, "inputs/sphere_pile.yaml"), "--out", out,
           "--quiet", "--set", f"dem.grain_grain.kn={kn:g}", "--set", f"dem.grain_wall.kn={kn:g}",
           "--set", f"dem.dt_factor={f:g}"]
    env = dict(os.environ, OMP_NUM_THREADS="1")
    p = subprocess.run(cmd, env=env, capture_output=True, text=True)
    row = dict(kn=kn, dt_factor=f, result="error", t_end=0, steps=0, wall=0, ke_end="",
               top_z="", max_overlap_per_d="", failure="")
    try:
        with open(os.path.join(out, "summary.json")) as fh:
            summary = json.load(fh)
    except (OSError, ValueError):
        row["failure"] = (p.stderr or p.stdout).strip().splitlines()[-1:]
        return row
    result, failure = classify(summary)
    row.update(result=result, t_end=summary["sim_time"], steps=summary["steps"],
               wall=summary["wall_seconds"], failure=failure)
    with open(os.path.join(out, "grains.csv")) as fh:
        g = list(csv.DictReader(fh))
    if g:
        row.update(ke_end=g[-1]["kinetic_energy"], top_z=g[-1]["top_z"],
                   max_overlap_per_d=max(float(r["max_overlap_per_d"]) for r in g))
    return row


def plot_dem(rows, path):
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    colours = {"stable": "tab:green", "overlap": "tab:orange", "left": "tab:red",
               "nan": "tab:red", "error": "black"}
    fig, ax = plt.subplots(figsize=(9, 4.6))
    for r in rows:
        x, y = DT_FACTORS.index(float(r["dt_factor"])), KNS.index(float(r["kn"]))
        ax.scatter([x], [y], s=1700, c=colours.get(r["result"], "black"), marker="s")
        if r["result"] == "stable":
            label = (f"ovl {100 * float(r['max_overlap_per_d']):.1f}%\n"
                     f"KE {float(r['ke_end']):.0e}")
        else:
            label = f"{r['result']}\nt={float(r['t_end']):.3f}"
        ax.annotate(label, (x, y), ha="center", va="center", fontsize=6.5, color="white")
    ax.set_xticks(range(len(DT_FACTORS)))
    ax.set_xticklabels([f"{f:g}" for f in DT_FACTORS])
    ax.set_yticks(range(len(KNS)))
    ax.set_yticklabels([f"{k:g}" for k in KNS])
    ax.set_xlim(-0.6, len(DT_FACTORS) - 0.4)
    ax.set_ylim(-0.6, len(KNS) - 0.4)
    ax.set_xlabel("dem.dt_factor (dt = dt_factor t_c / 50)")
    ax.set_ylabel("contact stiffness kn, N/m")
    ax.set_title("300 beads of 8 mm rained into a box, 0.5 s: green = completed (label: largest "
                 "overlap sampled\nevery 0.01 s, % of d; final kinetic energy, J), else the guard "
                 "that stopped it", fontsize=9)
    fig.tight_layout()
    fig.savefig(path, dpi=120)


def plot(rows, path):
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    import matplotlib.ticker
    colours = {"stable": "tab:green", "density": "tab:orange", "nan": "tab:red",
               "mach": "tab:purple", "penetration": "tab:brown", "dt_floor": "tab:gray",
               "error": "black"}
    fig, axes = plt.subplots(1, len(RES), figsize=(5 * len(RES), 4), sharey=True)
    for ax, res in zip(axes, RES):
        for r in rows:
            if int(r["res"]) != res:
                continue
            x, y = float(r["cfl"]), float(r["delta"])
            c = colours.get(r["result"], "black")
            ax.scatter([x], [y], s=1500, c=c, marker="s")
            short = {"penetration": "penetr."}.get(r["result"], r["result"])
            label = short if r["result"] == "stable" else f"{short}\nt={float(r['t_end']):.2f}"
            ax.annotate(label, (x, y), ha="center", va="center", fontsize=7, color="white")
        ax.set_xscale("log")
        ax.xaxis.set_minor_formatter(matplotlib.ticker.NullFormatter())
        ax.set_xticks(CFLS)
        ax.set_xticklabels([str(c) for c in CFLS])
        ax.set_yticks(DELTAS)
        ax.set_xlim(0.07, 0.7)
        ax.set_ylim(-0.03, 0.13)
        ax.set_xlabel("CFL number (time.cfl)")
        ax.set_title(f"2D dam break, dp = L/{res}")
    axes[0].set_ylabel("density diffusion delta (0 = none)")
    fig.suptitle("2D dam break to t = 0.6 s, Verlet (Euler every 40), mDBC: stable, or the guard that fired")
    fig.tight_layout()
    fig.savefig(path, dpi=120)


def main():
    ap = argparse.ArgumentParser(description=__doc__)
    ap.add_argument("--out", required=True)
    ap.add_argument("--end", type=float, default=0.6)
    ap.add_argument("--jobs", type=int, default=2)
    ap.add_argument("--sphdem", default=os.path.join(ROOT, "build/sphdem"))
    ap.add_argument("--plot", help="write the map PNG from OUT/map.csv and exit")
    ap.add_argument("--dem", action="store_true", help="the DEM map (kn x dt_factor)")
    args = ap.parse_args()
    os.makedirs(args.out, exist_ok=True)
    table = os.path.join(args.out, "map.csv")
    if args.dem:
        return dem_main(args, table)
    fields = ["cfl", "delta", "res", "result", "t_end", "steps", "wall", "failure"]
    rows = read_table(table)
    if args.plot:
        plot(rows, args.plot)
        return 0
    done = {(float(r["cfl"]), float(r["delta"]), int(r["res"])) for r in rows}
    todo = [c for c in itertools.product(CFLS, DELTAS, RES) if c not in done]
    sweep(args, table, fields, rows, todo, run_one,
          lambda r: f"cfl {r['cfl']} delta {r['delta']} L/{r['res']}")
    return 0


def read_table(table):
    if not os.path.exists(table):
        return []
    with open(table) as f:
        return list(csv.DictReader(f))


def sweep(args, table, fields, rows, todo, run, name):
    """Runs run(args, *case) for each case, two at a time by default; after each, prints a line
    and rewrites the table with every row so far (an interrupted sweep resumes where it stopped)."""
    with ThreadPoolExecutor(args.jobs) as pool:
        for r in pool.map(lambda c: run(args, *c), todo):
            rows.append(r)
            print(f"{name(r)}: {r['result']} at t = {float(r['t_end']):.3f} s ({r['steps']} "
                  f"steps, {float(r['wall']):.0f} s)", flush=True)
            with open(table, "w", newline="") as f:
                w = csv.DictWriter(f, fieldnames=fields)
                w.writeheader()
                for row in rows:
                    w.writerow({k: row[k] for k in fields})


def dem_main(args, table):
    rows = read_table(table)
    if args.plot:
        plot_dem(rows, args.plot)
        return 0
    done = {(float(r["kn"]), float(r["dt_factor"])) for r in rows}
    todo = [c for c in itertools.product(KNS, DT_FACTORS) if c not in done]
    sweep(args, table, DEM_FIELDS, rows, todo, run_dem,
          lambda r: f"kn {float(r['kn']):g} dt_factor {float(r['dt_factor']):g}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
