#!/usr/bin/env python3
"""Speed against accuracy on start-up Poiseuille flow (issue #9): inputs/poiseuille_2d.yaml
(Morris et al. 1997: plates 1 mm apart, nu = 1e-6 m^2/s, body force 2e-4 m/s^2) to t = 0.225 s,
the velocity profile across the gap against the series solution (FORMULAS.md §2), over
resolution, precision, integrator, density-diffusion variant and wall condition. The error is
the relative L2 norm sqrt(sum (u - u_ref)^2 / sum u_ref^2) over the particle rows z = (k + 1/2) dp,
the velocity being the profile diagnostic's kernel interpolation (quantity: velocity). A run a
guard stops is recorded with the guard's message: Verlet is expected to fail here.

  python3 jobs/speed_accuracy_poiseuille.py --out out/sa_poiseuille [--float build-float/sphdem]
  /usr/bin/python3 jobs/speed_accuracy_poiseuille.py --out out/sa_poiseuille --plot docs/figures/speed_accuracy_poiseuille.png

Runs already in OUT/runs.csv are not repeated. One thread each (OMP_NUM_THREADS=1), one at a
time, so the wall times compare.
"""
import argparse
import csv
import json
import math
import os
import subprocess
import sys

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import speed_accuracy  # noqa: E402  (the dam-break driver: its Pareto front)

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
GAP, NU, F, T_END = 1e-3, 1e-6, 2e-4, 0.225

BASE = {"integrator": "symplectic", "diffusion": "molteni", "boundary": "mdbc",
        "precision": "double"}
VARIANTS = [
    ("baseline", {}, [10, 20, 40, 80]),
    ("verlet", {"integrator": "verlet"}, [20, 40]),
    ("fourtakas", {"diffusion": "fourtakas"}, [20, 40]),
    ("no diffusion", {"diffusion": "none"}, [20, 40]),
    ("dbc", {"boundary": "dbc"}, [20, 40]),
    ("float", {"precision": "float"}, [20, 40]),
]
FIELDS = ["label", "res", "integrator", "diffusion", "boundary", "precision", "status", "steps",
          "wall", "l2_error", "failure"]


def u_series(z, t, terms=200):
    u = F / (2 * NU) * z * (GAP - z)
    for n in range(terms):
        k = 2 * n + 1
        u -= (4 * F * GAP * GAP / (NU * math.pi ** 3 * k ** 3) * math.sin(math.pi * z * k / GAP)
              * math.exp(-k * k * math.pi ** 2 * NU * t / GAP ** 2))
    return u


def l2_error(profile_csv):
    num = den = 0.0
    with open(profile_csv) as f:
        for r in csv.DictReader(f):
            t, z, u = float(r["t"]), float(r["z"]), float(r["u"])
            ref = u_series(z, t)
            num += (u - ref) ** 2
            den += ref ** 2
    return math.sqrt(num / den) if den > 0 else float("nan")


def run(args, label, cfg, res):
    name = "%s_%d" % (label.replace(" ", "_"), res)
    out = os.path.join(args.out, name)
    binary = args.float if cfg["precision"] == "float" else args.sphdem
    dp = GAP / res
    profile = ("{name: velocity_profile, from: [5e-4, 0, %.10g], to: [5e-4, 0, %.10g], "
               "samples: %d, quantity: velocity, times: [%g]}" % (dp / 2, GAP - dp / 2, res, T_END))
    sets = ["sph.dp=%.10g" % dp, "time.end=%g" % T_END, "diagnostics.every=0.0225",
            "diagnostics.profiles=[%s]" % profile, "time.integrator=" + cfg["integrator"],
            "sph.boundary=" + cfg["boundary"], "fluid.diffusion.model=" + cfg["diffusion"]]
    # The plates: 2h deep at every resolution (boundary_layers 0 fills the kernel support).
    cmd = [binary, "run", os.path.join(ROOT, "inputs/poiseuille_2d.yaml"), "--out", out, "--quiet"]
    for s in sets:
        cmd += ["--set", s]
    p = subprocess.run(cmd, env=dict(os.environ, OMP_NUM_THREADS="1"), capture_output=True,
                       text=True)
    try:
        with open(os.path.join(out, "summary.json")) as f:
            summ = json.load(f)
    except (OSError, ValueError):
        return dict(label=label, res=res, **cfg, status="error", steps=0, wall=0,
                    l2_error=float("nan"), failure=(p.stderr or p.stdout).strip()[-200:])
    failure = ""
    err = float("nan")
    if summ["status"] == "completed":
        err = l2_error(os.path.join(out, "velocity_profile_%g.csv" % T_END))
    else:
        for line in open(os.path.join(out, "run.log")):
            if "unstable" in line.lower() or "stopping" in line.lower() or "guard" in line.lower():
                failure = line.strip()[:200]
                break
    return dict(label=label, res=res, **cfg, status=summ["status"], steps=summ["steps"],
                wall=summ["wall_seconds"], l2_error=err, failure=failure)


def pareto(rows):
    return speed_accuracy.pareto(rows, "l2_error")


def plot(rows, path):
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    fig, ax = plt.subplots(figsize=(7.5, 5))
    markers = dict(zip([v[0] for v in VARIANTS], "osD^vx"))
    for label, _, _ in VARIANTS:
        pts = [r for r in rows if r["label"] == label and r["status"] == "completed"]
        if pts:
            ax.plot([float(r["wall"]) for r in pts], [100 * float(r["l2_error"]) for r in pts],
                    markers[label], label=label, linestyle="-" if label == "baseline" else "none")
            for r in pts:
                ax.annotate("%s across" % r["res"], (float(r["wall"]), 100 * float(r["l2_error"])),
                            fontsize=7, xytext=(3, 3), textcoords="offset points")
    failed = [r for r in rows if r["status"] != "completed"]
    for r in failed:
        ax.axvline(max(float(r["wall"]), 1e-2), color="r", lw=0.6, ls=":")
    front = pareto(rows)
    ax.plot([float(r["wall"]) for r in front], [100 * float(r["l2_error"]) for r in front], "k--",
            lw=1, label="Pareto front")
    ax.set_xscale("log")
    ax.set_yscale("log")
    ax.set_xlabel("wall time, s (1 thread, to t = 0.225 s)")
    ax.set_ylabel("velocity profile L2 error vs series, %")
    title = "start-up Poiseuille (Morris 1997), t = 0.225 s"
    if failed:
        title += "\n(red dotted: runs a guard stopped, at their wall time)"
    ax.set_title(title, fontsize=10)
    ax.legend(fontsize=8)
    fig.tight_layout()
    fig.savefig(path, dpi=120)


def main():
    ap = argparse.ArgumentParser(description=__doc__)
    ap.add_argument("--out", required=True)
    ap.add_argument("--sphdem", default=os.path.join(ROOT, "build/sphdem"))
    ap.add_argument("--float", default=os.path.join(ROOT, "build-float/sphdem"))
    ap.add_argument("--plot")
    args = ap.parse_args()
    os.makedirs(args.out, exist_ok=True)
    table = os.path.join(args.out, "runs.csv")
    rows = []
    if os.path.exists(table):
        with open(table) as f:
            rows = list(csv.DictReader(f))
    if args.plot:
        plot(rows, args.plot)
        for r in pareto(rows):
            print("Pareto: %s %s across: %.3f%% in %.1f s" % (r["label"], r["res"],
                                                            100 * float(r["l2_error"]), float(r["wall"])))
        return 0
    done = {(r["label"], int(r["res"])) for r in rows}
    for label, change, resolutions in VARIANTS:
        cfg = dict(BASE, **change)
        if cfg["precision"] == "float" and not os.path.exists(args.float):
            print("skipping %s: no %s" % (label, args.float))
            continue
        for res in resolutions:
            if (label, res) in done:
                continue
            r = run(args, label, cfg, res)
            rows.append(r)
            print(r, flush=True)
            with open(table, "w", newline="") as f:
                w = csv.DictWriter(f, fieldnames=FIELDS)
                w.writeheader()
                w.writerows(rows)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
