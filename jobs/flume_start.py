#!/usr/bin/env python3
"""How the flume's debris starts (issue #6): the seed lets poured debris settle for 2.5 s behind a
closed gate before removing it; sphdem's flume.yaml starts from the settled state (a level
surface, hydrostatic) with the gate open at t = 0. This driver runs both, and the poured block
released at t = 0 with no settling, and compares them with times counted from the opening:

  settled  inputs/flume/flume.yaml as shipped                       (gate open at t = 0)
  gated    the poured block behind the gate, removed at 2.5 s       (the seed's timeline; the
           settling leg runs without the mDBC penetration control, which feeds energy into a
           sloshing pool, and the run goes on from its 2.5 s checkpoint with it)
  poured   the poured block, gate open at t = 0                     (no settling)

  python3 jobs/flume_start.py --out runs/start [--dp 0.01] [--after 1.5] [--cases settled gated]
     -> OUT/summary.csv: front at the barrier, peak forces and their times, largest run-up,
        upstream share at the end, wall time
Each case runs with OMP_NUM_THREADS as set (runs already finished are read back, not rerun).
"""
import argparse
import csv
import json
import os
import subprocess

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
SCENE = os.path.join(ROOT, "inputs", "flume", "flume.yaml")
POURED = "fluid_blocks[0]={lo: [-0.2, 0, 0], hi: [0, 0.4, 0.04327]}"
SETTLE = 2.5


def case_sets(case, after):
    if case == "settled":
        return 0.0, ["time.end=%g" % after]
    if case == "poured":
        return 0.0, ["time.end=%g" % after, POURED]
    if case == "gated":
        return SETTLE, ["solids[1].removed_at=%g" % SETTLE, "time.end=%g" % (SETTLE + after),
                        POURED, "diagnostics.profiles[0].times=[%g]" % (SETTLE + 0.7),
                        "checkpoint.every_time=%g" % SETTLE]
    raise SystemExit("unknown case " + case)


def rows(path):
    with open(path) as f:
        return list(csv.DictReader(f))


def analyse(run_dir, t0, barrier_x=0.6, thickness=0.013):
    force = rows(os.path.join(run_dir, "impact_force.csv"))
    walls = sum(1 for c in force[0]
                if c.startswith("barrier_") and c.endswith("_fx") and "_grain_" not in c)
    mid = "barrier_%d_fx" % ((walls + 1) // 2)
    front = rows(os.path.join(run_dir, "front.csv"))
    runup = rows(os.path.join(run_dir, "runup.csv"))
    trap = rows(os.path.join(run_dir, "trap.csv"))
    summ = json.load(open(os.path.join(run_dir, "summary.json")))
    after = [r for r in force if float(r["t"]) >= t0 - 1e-9]
    arrive = next((float(r["t"]) - t0 for r in front
                   if float(r["x_front"]) >= barrier_x - thickness / 2), float("nan"))
    pm = max(after, key=lambda r: float(r[mid]))
    pt = max(after, key=lambda r: float(r["total_f"]))
    ru = max(runup, key=lambda r: float(r["runup"]))
    up, down = float(trap[-1]["fluid_mass_upstream"]), float(trap[-1]["fluid_mass_downstream"])
    tail = [float(r[mid]) for r in after[-max(1, len(after) // 10):]]
    return {
        "front_at_barrier_s": "%.3f" % arrive,
        "peak_mid_N": "%.3f" % float(pm[mid]), "t_peak_mid_s": "%.3f" % (float(pm["t"]) - t0),
        "peak_total_N": "%.3f" % float(pt["total_f"]),
        "t_peak_total_s": "%.3f" % (float(pt["t"]) - t0),
        "static_mid_N": "%.3f" % (sum(tail) / len(tail)),
        "max_runup_m": "%.4f" % float(ru["runup"]), "t_runup_s": "%.3f" % (float(ru["t"]) - t0),
        "upstream_share_end": "%.3f" % (up / max(up + down, 1e-30)),
        "t_end_after_opening_s": "%.3f" % (float(trap[-1]["t"]) - t0),
        "status": summ["status"], "wall_s": "%.0f" % summ["wall_seconds"],
    }


def main():
    ap = argparse.ArgumentParser(description=__doc__)
    ap.add_argument("--out", required=True)
    ap.add_argument("--dp", type=float, default=0.01)
    ap.add_argument("--after", type=float, default=1.5, help="simulated seconds after the opening")
    ap.add_argument("--cases", nargs="+", default=["settled", "gated", "poured"])
    ap.add_argument("--sphdem", default=os.path.join(ROOT, "build", "sphdem"))
    a = ap.parse_args()
    os.makedirs(a.out, exist_ok=True)
    table = []
    for case in a.cases:
        t0, sets = case_sets(case, a.after)
        run_dir = os.path.join(a.out, case)
        if not os.path.exists(os.path.join(run_dir, "summary.json")):
            cmd = [a.sphdem, "run", SCENE, "--out", run_dir, "--quiet", "--set", "sph.dp=%g" % a.dp,
                   "--set", "frames.every=0"]
            for s in sets:
                cmd += ["--set", s]
            if t0 > 0:  # the settling leg, then on from its checkpoint
                subprocess.run(cmd + ["--set", "sph.no_penetration=false", "--set",
                                      "time.end=%g" % t0], check=False)
                cmd += ["--restart", "latest"]
            subprocess.run(cmd, check=False)
        row = {"case": case, "dp_m": a.dp, "opening_s": t0}
        row.update(analyse(run_dir, t0))
        table.append(row)
        print(row, flush=True)
    with open(os.path.join(a.out, "summary.csv"), "w", newline="") as f:
        w = csv.DictWriter(f, fieldnames=list(table[0].keys()))
        w.writeheader()
        w.writerows(table)
    print(open(os.path.join(a.out, "summary.csv")).read())


if __name__ == "__main__":
    main()
