#!/usr/bin/env python3
"""Sphere settling against resolution (issue #6): inputs/sphere_settling.yaml at several particle
counts across the 10 mm sphere, each run's terminal slip velocity against Stokes' drag with
Hasimoto's correction for the simple cubic array (the same reference as
tests/validation/test_settling.cpp).

Usage: jobs/settling/run.py OUTDIR [ACROSS ...]       -> OUTDIR/summary.csv
  ACROSS: particles across the sphere, d/dp (default 6 8 10 12); the 30 mm box must hold a whole
  number of particles (3 * ACROSS). Env: SPHDEM (binary, default build/sphdem), END (simulated s,
  default 0.05), OMP_NUM_THREADS.
Cost on the 2-core VM (2 threads): d/dp 6 about 0.5 min, 8 about 1 min, 10 about 2 min, 12 about
5 min.
"""
import csv
import json
import math
import os
import subprocess
import sys

root = os.path.abspath(os.path.join(os.path.dirname(__file__), "..", ".."))
out = os.path.abspath(sys.argv[1])
across = [int(a) for a in sys.argv[2:]] or [6, 8, 10, 12]
binary = os.path.abspath(os.environ.get("SPHDEM", os.path.join(root, "build", "sphdem")))
end = float(os.environ.get("END", "0.05"))

d, rho_s, rho0, nu, g, box = 0.01, 2000.0, 1000.0, 2.33e-3, 9.81, 0.03
os.makedirs(out, exist_ok=True)
rows = []
for n in across:
    dp = d / n
    run_dir = os.path.join(out, "across_%d" % n)
    subprocess.run([binary, "run", os.path.join(root, "inputs", "sphere_settling.yaml"), "--out",
                    run_dir, "--quiet", "--set", "sph.dp=%.10g" % dp, "--set",
                    "time.end=%g" % end], check=True, stdout=subprocess.DEVNULL)
    summary = json.load(open(os.path.join(run_dir, "summary.json")))
    fluid = summary["particles"]["fluid"]
    grain = summary["particles"]["grain_boundary"]
    vs = math.pi * d ** 3 / 6
    ms, c = rho_s * vs, vs / box ** 3
    mf = fluid * rho0 * dp ** 3
    rho_mix = (mf + ms) / (mf / rho0 + vs)
    force = (rho_s - rho_mix) * g * vs
    inv_k = 1 - 1.7601 * c ** (1 / 3) + c - 1.5593 * c * c
    u_ref = force * inv_k / (6 * math.pi * rho0 * nu * d / 2)
    body = list(csv.DictReader(open(os.path.join(run_dir, "bodies.csv"))))
    energy = list(csv.DictReader(open(os.path.join(run_dir, "energy.csv"))))
    t_end = float(body[-1]["t"])
    last, before = [], []
    for b, e in zip(body, energy):
        t = float(b["t"])
        slip = (1 - c) * (float(e["pz"]) / mf - float(b["vz"]))
        if t > t_end - 0.01 + 1e-9:
            last.append(slip)
        elif t > t_end - 0.02 + 1e-9:
            before.append(slip)
    u = sum(last) / len(last)
    u_before = sum(before) / len(before)
    rows.append({
        "across": n, "dp_m": "%.6g" % dp, "fluid": fluid, "grain_particles": grain,
        "reynolds": "%.4f" % (u_ref * d / nu), "u_m_s": "%.6f" % u, "u_ref_m_s": "%.6f" % u_ref,
        "err_pct": "%.2f" % (100 * (u / u_ref - 1)),
        "drift_pct": "%.2f" % (100 * (u / u_before - 1)),
        "steps": summary.get("steps"), "wall_s": "%.1f" % summary.get("wall_seconds", 0)})
    print(rows[-1], flush=True)

with open(os.path.join(out, "summary.csv"), "w", newline="") as f:
    w = csv.DictWriter(f, fieldnames=list(rows[0].keys()))
    w.writeheader()
    w.writerows(rows)
print(open(os.path.join(out, "summary.csv")).read())
