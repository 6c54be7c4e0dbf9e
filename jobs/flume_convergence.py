#!/usr/bin/env python3
"""The flume's peak impact force and largest run-up against wall time over resolutions
(issues #6 and #9: "a convergence table of peak impact force and largest run-up at three
resolutions"; "for the flume, do the same: peak impact force and largest run-up against wall
time").

Each run is one flume case (same preset and start, different sph.dp), already run into its own
folder, for example the P00 half scene:

  build/sphdem run inputs/flume/flume.yaml --out runs/f10 --set sph.dp=0.01 \\
      --set "symmetry={axis: y, at: 0.2}" --set time.end=1.5 --set frames.every=0

(the half scene only where `sphdem check` does not warn that the full scene's walls lack mirror
images: at dp = 0.00714285714 they do, and runs/f7 must be the full scene), then

  /usr/bin/python3 jobs/flume_convergence.py --until 1.0 --out docs/figures/flume_convergence \\
      runs/f10:0.01 runs/f7:0.00714285714 runs/f5:0.005

Every figure is taken over 0 <= t <= --until (so runs that went on longer compare on the same
window): the middle wall's and the total's peak of the 0.05 s running mean of the force along
the channel, the largest run-up, the first contact (the total force first above a tenth of its
peak), and the share of the debris upstream of the barrier at --until. The wall time to --until is the run's wall time
scaled by until / its simulated time (the step is nearly constant in these runs: acoustic
limit). RUN_DIR:dp:SECONDS gives the wall time to --until instead (a run continued past it by
a restart, whose summary holds the last segment's wall time only). --reuse TABLE:dp takes the
row of dp from an earlier OUT.csv, for a run whose folder is gone (say so where the table is
quoted). The differences are taken against the finest row. Writes OUT.csv, OUT.md and, with
matplotlib, OUT.png (difference against wall time, log axes).
"""
import argparse
import json
import os
import sys

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import flume_study  # noqa: E402  (summarize, read_csv)

def first_contact(run_dir, until, peak_total):
    """First time the total force along the channel passes a tenth of its (0.05 s mean) peak."""
    h, rows = flume_study.read_csv(os.path.join(run_dir, "impact_force.csv"))
    k = h.index("total_fx")
    for r in rows:
        if r[0] <= until and r[k] > 0.1 * peak_total:
            return r[0]
    return float("nan")


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawTextHelpFormatter)
    ap.add_argument("runs", nargs="*", help="RUN_DIR:dp or RUN_DIR:dp:wall_seconds_to_until")
    ap.add_argument("--reuse", action="append", default=[], metavar="TABLE:dp",
                    help="the row of dp from an earlier table written by this script")
    ap.add_argument("--until", type=float, required=True)
    ap.add_argument("--out", required=True, help="output path without extension")
    a = ap.parse_args()
    rows = []
    for spec in a.reuse:
        table, dp = spec.rsplit(":", 1)
        h, data = flume_study.read_csv(table)
        hit = [r for r in data if abs(r[h.index("dp")] - float(dp)) <= 1e-9 * float(dp)]
        if len(hit) != 1:
            raise SystemExit("--reuse %s: %d rows of %s have dp = %s" % (spec, len(hit), table, dp))
        row = {k: hit[0][h.index(k)] for k in h if not k.startswith("diff_")}
        row["fluid"], row["boundary"] = int(row["fluid"]), int(row["boundary"])
        rows.append(row)
    for spec in a.runs:
        parts = spec.split(":")
        if len(parts) not in (2, 3):
            raise SystemExit("%s: give RUN_DIR:dp or RUN_DIR:dp:wall_seconds" % spec)
        run_dir, dp = parts[0], parts[1]
        wall = float(parts[2]) if len(parts) == 3 else None
        with open(os.path.join(run_dir, "summary.json")) as f:
            js = json.load(f)
        if js["sim_time"] < a.until - 1e-6:
            raise SystemExit("%s ran to t = %g s, short of --until %g" % (run_dir, js["sim_time"], a.until))
        s = flume_study.summarize(run_dir, a.until)
        rows.append({
            "run": run_dir, "dp": float(dp), "fluid": js["particles"]["fluid"],
            "boundary": js["particles"]["wall_boundary"] + js["particles"]["grain_boundary"],
            "wall_s": wall if wall is not None else js["wall_seconds"] * a.until / js["sim_time"],
            "first_contact": first_contact(run_dir, a.until, s["peak_total_50ms"]),
            "peak_mid_50ms": s["peak_mid_50ms"], "t_peak_mid_50ms": s["t_peak_50ms"],
            "peak_total_50ms": s["peak_total_50ms"], "max_runup": s["max_runup"],
            "trap_ratio": s["trap_ratio"],
        })
    rows.sort(key=lambda r: -r["dp"])
    ref = rows[-1]
    keys = ["peak_mid_50ms", "peak_total_50ms", "max_runup"]
    for r in rows:
        for k in keys:
            r["diff_" + k] = abs(r[k] - ref[k]) / abs(ref[k]) if ref[k] else float("nan")
    cols = ["dp", "fluid", "boundary", "wall_s", "first_contact", "peak_mid_50ms",
            "t_peak_mid_50ms", "peak_total_50ms", "max_runup", "trap_ratio"] + \
        ["diff_" + k for k in keys]
    flume_study.write_table(a.out, cols, rows, repr)
    try:
        import matplotlib
        matplotlib.use("Agg")
        import matplotlib.pyplot as plt
    except ImportError:
        print("matplotlib missing: no plot (apt-get install python3-matplotlib)", file=sys.stderr)
        return
    fig, ax = plt.subplots(figsize=(6, 4))
    for k, label in zip(keys, ["middle-wall peak", "total peak", "largest run-up"]):
        pts = [(r["wall_s"], r["diff_" + k], r["dp"]) for r in rows[:-1]]
        ax.loglog([p[0] for p in pts], [p[1] for p in pts], "o-", label=label)
        for x, y, dp in pts:
            ax.annotate("%.1f mm" % (dp * 1e3), (x, y), fontsize=7)
    ax.set_xlabel("wall time to t = %g s (s, 2-core VM)" % a.until)
    ax.set_ylabel("difference from dp = %.1f mm" % (ref["dp"] * 1e3))
    ax.set_title("P00 flume: accuracy against cost")
    ax.legend()
    fig.tight_layout()
    fig.savefig(a.out + ".png", dpi=120)


if __name__ == "__main__":
    main()
