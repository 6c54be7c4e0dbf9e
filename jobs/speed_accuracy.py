#!/usr/bin/env python3
"""Speed against accuracy (issue #9): the 2D dam break's front error against Koshizuka & Oka
(rms over 1 <= T <= 3, T = t sqrt(2g/L)) and the wall time, over resolution, precision,
integrator, density-diffusion variant and wall condition. Each run's numbers go to OUT/runs.csv;
--plot draws error against wall time on log axes with the Pareto front marked.

  python3 jobs/speed_accuracy.py --out out/speed_accuracy [--float build-float/sphdem]
  python3 jobs/speed_accuracy.py --out out/speed_accuracy --plot docs/figures/speed_accuracy.png

Runs already in OUT/runs.csv are not repeated. Single-threaded runs (OMP_NUM_THREADS=1), one at a
time, so the wall times compare.
"""
import argparse
import csv
import json
import math
import os
import subprocess
import sys

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
L, G = 0.146, 9.81
REF = os.path.join(ROOT, "tests/data/reference/dambreak_2d/koshizuka_oka1996_surge_front_L0.146.csv")

BASE = {"integrator": "verlet", "diffusion": "fourtakas", "boundary": "mdbc", "precision": "double"}
# (label, changes to BASE, resolutions)
VARIANTS = [
    ("baseline", {}, [10, 20, 30, 40]),
    ("symplectic", {"integrator": "symplectic"}, [20, 40]),
    ("molteni", {"diffusion": "molteni"}, [20, 40]),
    ("no diffusion", {"diffusion": "none"}, [20, 40]),
    ("dbc", {"boundary": "dbc"}, [20, 40]),
    ("float", {"precision": "float"}, [20, 40]),
]


def read_series(path):
    rows = []
    with open(path) as f:
        for line in f:
            if not line or not (line[0].isdigit() or line[0] == "-"):
                continue
            rows.append([float(c) for c in line.strip().split(",")])
    return rows


def front_error(front_csv):
    ref = read_series(REF)
    rt, rz = [r[0] for r in ref], [r[1] for r in ref]

    def at(x):
        for i in range(1, len(rt)):
            if x <= rt[i]:
                return rz[i - 1] + (rz[i] - rz[i - 1]) * (x - rt[i - 1]) / (rt[i] - rt[i - 1])
        return rz[-1]

    scale = math.sqrt(2 * G / L)
    errs = []
    for t, x in read_series(front_csv):
        T = t * scale
        if 1 <= T <= 3:
            errs.append((x / L - at(T)) / at(T))
    if len(errs) < 20:
        return float("nan")
    return math.sqrt(sum(e * e for e in errs) / len(errs))


def run(args, label, cfg, res):
    name = f"{label.replace(' ', '_')}_L{res}"
    out = os.path.join(args.out, name)
    binary = args.float if cfg["precision"] == "float" else args.sphdem
    sets = [f"sph.dp={L / res:.10g}", "time.end=0.26", "diagnostics.every=0.0025",
            f"time.integrator={cfg['integrator']}", f"sph.boundary={cfg['boundary']}"]
    if cfg["diffusion"] == "none":
        sets.append("fluid.diffusion.model=none")
    else:
        sets.append(f"fluid.diffusion.model={cfg['diffusion']}")
    cmd = [binary, "run", os.path.join(ROOT, "inputs/dam_break_2d.yaml"), "--out", out, "--quiet"]
    for s in sets:
        cmd += ["--set", s]
    subprocess.run(cmd, env=dict(os.environ, OMP_NUM_THREADS="1"), capture_output=True, text=True)
    try:
        with open(os.path.join(out, "summary.json")) as f:
            summ = json.load(f)
    except (OSError, ValueError):
        return None
    err = front_error(os.path.join(out, "front.csv")) if summ["status"] == "completed" else float("nan")
    return dict(label=label, res=res, **cfg, status=summ["status"], steps=summ["steps"],
                wall=summ["wall_seconds"], rms_error=err)


def pareto(rows, key="rms_error"):
    """The runs no other run beats on both wall time and error (rows with r[key] the error)."""
    pts = sorted((float(r["wall"]), float(r[key]), r) for r in rows
                 if r["status"] == "completed" and not math.isnan(float(r[key])))
    front, best = [], float("inf")
    for w, e, r in pts:
        if e < best:
            front.append(r)
            best = e
    return front


def self_error(out_root, row):
    """rms relative difference of the front from the finest baseline run (baseline L/40), over
    1 <= T <= 3: the discretisation and method error, free of the experiment's gate lift."""
    ref = read_series(os.path.join(out_root, "baseline_L40", "front.csv"))
    run = read_series(os.path.join(out_root, f"{row['label'].replace(' ', '_')}_L{row['res']}",
                                   "front.csv"))
    rt, rx = [r[0] for r in ref], [r[1] for r in ref]

    def at(t):  # the reference front, linearly interpolated in time
        for i in range(1, len(rt)):
            if t <= rt[i]:
                return rx[i - 1] + (rx[i] - rx[i - 1]) * (t - rt[i - 1]) / (rt[i] - rt[i - 1])
        return rx[-1]

    scale = math.sqrt(2 * G / L)
    errs = [(x - at(t)) / at(t) for t, x in run if 1 <= t * scale <= 3]
    return math.sqrt(sum(e * e for e in errs) / len(errs)) if len(errs) > 20 else float("nan")


def plot(rows, path, out_root):
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    import matplotlib.ticker
    fig, (ax, bx) = plt.subplots(1, 2, figsize=(13, 5))
    markers = dict(zip([v[0] for v in VARIANTS], "osD^vx"))
    for label, _, _ in VARIANTS:
        pts = [r for r in rows if r["label"] == label and r["status"] == "completed"]
        if not pts:
            continue
        ax.plot([float(r["wall"]) for r in pts], [100 * float(r["rms_error"]) for r in pts],
                markers[label], label=label, linestyle="-" if label == "baseline" else "none")
        for r in pts:
            ax.annotate(f"L/{r['res']}", (float(r["wall"]), 100 * float(r["rms_error"])),
                        fontsize=7, xytext=(3, 3), textcoords="offset points")
    front = pareto(rows)
    ax.plot([float(r["wall"]) for r in front], [100 * float(r["rms_error"]) for r in front], "k--",
            lw=1, label="Pareto front")
    ax.set_xscale("log")
    ax.set_yscale("log")
    ax.set_xlabel("wall time, s (1 thread, to T = 3)")
    ax.set_ylabel("front rms error vs Koshizuka & Oka, %")
    ax.yaxis.set_minor_formatter(matplotlib.ticker.NullFormatter())
    ax.set_title("against the experiment (Koshizuka & Oka)")
    ax.legend(fontsize=8)
    # Right: against the finest baseline run (L/40), the runs coarser or different from it.
    for label, _, _ in VARIANTS:
        pts = [r for r in rows if r["label"] == label and r["status"] == "completed"
               and not (label == "baseline" and int(r["res"]) == 40)]
        pts = [(float(r["wall"]), 100 * self_error(out_root, r), r) for r in pts]
        pts = [p for p in pts if not math.isnan(p[1]) and p[1] > 0]
        if not pts:
            continue
        bx.plot([p[0] for p in pts], [p[1] for p in pts], markers[label], label=label,
                linestyle="-" if label == "baseline" else "none")
        for w, e, r in pts:
            bx.annotate(f"L/{r['res']}", (w, e), fontsize=7, xytext=(3, 3), textcoords="offset points")
    bx.set_xscale("log")
    bx.set_yscale("log")
    bx.set_xlabel("wall time, s (1 thread, to T = 3)")
    bx.set_ylabel("front rms difference from the baseline L/40 run, %")
    bx.set_title("against the finest run (discretisation and method error)")
    bx.legend(fontsize=8)
    fig.suptitle("2D dam break: error against wall time")
    fig.tight_layout()
    fig.savefig(path, dpi=120)


def main():
    ap = argparse.ArgumentParser(description=__doc__)
    ap.add_argument("--out", required=True)
    ap.add_argument("--sphdem", default=os.path.join(ROOT, "build/sphdem"))
    ap.add_argument("--float", default=os.path.join(ROOT, "build-float/sphdem"),
                    help="an sphdem built with PRECISION=float (make build BUILD=build-float PRECISION=float)")
    ap.add_argument("--plot")
    args = ap.parse_args()
    os.makedirs(args.out, exist_ok=True)
    table = os.path.join(args.out, "runs.csv")
    fields = ["label", "res", "integrator", "diffusion", "boundary", "precision", "status", "steps",
              "wall", "rms_error"]
    rows = []
    if os.path.exists(table):
        with open(table) as f:
            rows = list(csv.DictReader(f))
    if args.plot:
        plot(rows, args.plot, args.out)
        for r in pareto(rows):
            print(f"Pareto: {r['label']} L/{r['res']}: {100 * float(r['rms_error']):.1f}% in {float(r['wall']):.1f} s")
        for r in rows:
            if r["status"] == "completed":
                print(f"{r['label']} L/{r['res']}: vs experiment {100 * float(r['rms_error']):.2f}%, vs L/40 "
                      f"{100 * self_error(args.out, r):.2f}%, {float(r['wall']):.1f} s")
        return 0
    done = {(r["label"], int(r["res"])) for r in rows}
    for label, change, resolutions in VARIANTS:
        cfg = dict(BASE, **change)
        if cfg["precision"] == "float" and not os.path.exists(args.float):
            print(f"skipping {label}: no {args.float}")
            continue
        for res in resolutions:
            if (label, res) in done:
                continue
            r = run(args, label, cfg, res)
            if r is None:
                print(f"{label} L/{res}: no summary.json")
                continue
            rows.append(r)
            print(f"{label} L/{res}: {r['status']}, rms {100 * r['rms_error']:.2f}%, "
                  f"{r['wall']:.1f} s", flush=True)
            with open(table, "w", newline="") as f:
                w = csv.DictWriter(f, fieldnames=fields)
                w.writeheader()
                for row in rows:
                    w.writerow({k: row[k] for k in fields})
    return 0


if __name__ == "__main__":
    sys.exit(main())
