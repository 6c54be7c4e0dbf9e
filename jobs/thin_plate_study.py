#!/usr/bin/env python3
"""The mDBC density limiter against a fine reference: the 2D thin-plate flume over resolutions
(issue #6, "the limiter default is undecided: it needs a finer reference").

inputs/flume/thin_plate_2d.yaml is the flume's centreline section with one closed 13 mm wall,
as thin as the 3D barrier's walls. It is cheap enough in 2D to run at dp = 0.89 mm (15 dp
across the wall), which the 3D flume is not on a CPU. Each dp runs twice, limiter off and on,
one thread each, --jobs at a time:

  /usr/bin/python3 jobs/thin_plate_study.py --out runs/thin_plate

Figures, each over 0 <= t <= --until: the plate's peak force along the channel (0.05 s running
mean, as the flume studies), its impulse (the integral of that force), its mean force over the
last 0.1 s, and the largest elevation at the gauge 10 mm upstream of the plate. The differences
are taken against the finest run with the limiter off (the finest "on" run is in the table, so
the two references can be compared). A run that stopped early (a guard) is listed with the
time and message and left out of the differences. --spread-cfl runs each case at --spread-dps
again with other CFL numbers: a different step sequence, the same physics, so the scatter of
those runs is the run-to-run spread that the flow's chaos gives at that dp (small markers).
--mach-max sets guards.mach_max for the runs it starts; the table gives each run's value and its
largest Mach number over all steps (guards.csv), so a stop shows how far past the others it went.
Writes OUT/thin_plate_study.{csv,md} and,
with matplotlib, OUT/thin_plate_study.png (difference against wall time, log axes).
"""
import argparse
import json
import os
import subprocess
import sys
from concurrent.futures import ThreadPoolExecutor

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import flume_study  # noqa: E402  (read_csv, running_mean, write_table)

HERE = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
DPS = [0.00714285714, 0.005, 0.00357142857, 0.0025, 0.00178571429, 0.00125, 0.000892857143]


def run_dir(out, dp, lim, cfl=None):
    return os.path.join(out, "dp%.3fmm_%s%s" % (dp * 1e3, "on" if lim else "off",
                                                "" if cfl is None else "_cfl%g" % cfl))


def run_case(sphdem, scene, out, dp, lim, until, cfl=None, mach_max=None):
    d = run_dir(out, dp, lim, cfl)
    js = os.path.join(d, "summary.json")
    if os.path.exists(js):
        with open(js) as f:
            if json.load(f).get("status") == "completed":
                return d
    env = dict(os.environ, OMP_NUM_THREADS="1")
    cmd = [sphdem, "run", scene, "--out", d, "--set", "sph.dp=%r" % dp,
           "--set", "sph.mdbc_limiter=%s" % ("true" if lim else "false"),
           "--set", "time.end=%r" % until]
    if cfl is not None:
        cmd += ["--set", "time.cfl=%r" % cfl]
    if mach_max is not None:
        cmd += ["--set", "guards.mach_max=%r" % mach_max]
    with open(d + ".log", "w") as log:
        subprocess.run(cmd, env=env, stdout=log, stderr=subprocess.STDOUT)
    return d


def mach_max_of(d, js):
    """guards.mach_max as the run used it: summary.json's "guards" (default included). Runs of
    sphdem before that field have only their scene.yaml (overrides applied), read by hand since
    this Python may lack a yaml module; a scene that left the key to its default gives NaN, and
    says so."""
    if "guards" in js:
        return float(js["guards"]["mach_max"])
    with open(os.path.join(d, "scene.yaml")) as f:
        for line in f:
            if line.strip().startswith("mach_max:"):
                return float(line.split(":", 1)[1].split("#")[0])
            if "mach_max:" in line:  # flow style: guards: {mach_max: 0.2, ...}
                return float(line.split("mach_max:", 1)[1].split(",")[0].split("}")[0])
    sys.stderr.write("%s: summary.json has no \"guards\" (an older sphdem) and scene.yaml does "
                     "not set guards.mach_max: the table's mach_max is NaN\n" % d)
    return float("nan")


def summarize(d, dp, lim, until, cfl=None):
    with open(os.path.join(d, "summary.json")) as f:
        js = json.load(f)
    r = {"dp_mm": dp * 1e3, "limiter": "on" if lim else "off",
         "cfl": "scene" if cfl is None else repr(cfl), "fluid": js["particles"]["fluid"],
         "wall_s": js["wall_seconds"], "steps": js["steps"], "status": js["status"],
         "t_end": js["sim_time"], "mach_max": mach_max_of(d, js)}
    h, rows = flume_study.read_csv(os.path.join(d, "plate.csv"))
    rows = [x for x in rows if x[0] <= until + 1e-9]
    if not rows:
        raise SystemExit("%s: plate.csv has no rows (the run stopped before its first "
                         "diagnostic time; see %s.log)" % (d, d))
    t = [x[0] for x in rows]
    fx = [x[h.index("fx")] for x in rows]
    m = flume_study.running_mean(t, fx, 0.05)
    i = max(range(len(m)), key=lambda k: m[k])
    r["peak_50ms"], r["t_peak"] = m[i], t[i]
    r["impulse"] = sum(0.5 * (fx[k] + fx[k + 1]) * (t[k + 1] - t[k]) for k in range(len(t) - 1))
    late = [f for tt, f in zip(t, fx) if tt >= until - 0.1]
    r["late_mean"] = sum(late) / len(late) if late else float("nan")
    hh, g = flume_study.read_csv(os.path.join(d, "h_up.csv"))
    r["max_runup"] = max(x[1] for x in g if x[0] <= until + 1e-9)
    # The largest Mach number over every step (guards.csv; runs of sphdem before a4495a9 lack it)
    # and when: how near the run came to guards.mach_max.
    r["mach_peak"], r["t_mach_peak"] = float("nan"), float("nan")
    gp = os.path.join(d, "guards.csv")
    if os.path.exists(gp):
        hg, gr = flume_study.read_csv(gp)
        gr = [x for x in gr if x[0] <= until + 1e-9]
        if gr:
            top = max(gr, key=lambda x: x[hg.index("mach")])
            r["mach_peak"], r["t_mach_peak"] = top[hg.index("mach")], top[0]
    lp = os.path.join(d, "mdbc_limiter.csv")
    r["clips_max"], r["cut_max"] = float("nan"), float("nan")  # no file: not counted
    if os.path.exists(lp):
        hl, lr = flume_study.read_csv(lp)
        if lr:
            r["clips_max"] = int(max(x[hl.index("clipped")] for x in lr))
            r["cut_max"] = max(x[hl.index("rho_cut_max")] for x in lr)
    return r


KEYS = ["peak_50ms", "impulse", "late_mean", "max_runup"]


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawTextHelpFormatter)
    ap.add_argument("--out", required=True)
    ap.add_argument("--dps", type=float, nargs="+", default=DPS)
    ap.add_argument("--until", type=float, default=1.0)
    ap.add_argument("--jobs", type=int, default=2)
    ap.add_argument("--sphdem", default=os.path.join(HERE, "build", "sphdem"))
    ap.add_argument("--scene", default=os.path.join(HERE, "inputs", "flume", "thin_plate_2d.yaml"))
    ap.add_argument("--spread-cfl", type=float, nargs="*", default=[],
                    help="also run these time.cfl values (the scene has 0.2) at --spread-dps, to "
                    "show the run-to-run spread the flow's chaos gives")
    ap.add_argument("--spread-dps", type=float, nargs="*", default=[])
    ap.add_argument("--mach-max", type=float, default=None,
                    help="guards.mach_max for the runs this call starts (the scene has 0.2); a "
                    "run that stopped is run again, a completed one is kept")
    ap.add_argument("--summarize-only", action="store_true")
    a = ap.parse_args()
    os.makedirs(a.out, exist_ok=True)
    cases = [(dp, lim, None) for dp in sorted(a.dps, reverse=True) for lim in (False, True)]
    cases += [(dp, lim, c) for dp in sorted(a.spread_dps, reverse=True) for lim in (False, True)
              for c in a.spread_cfl]
    if not a.summarize_only:
        with ThreadPoolExecutor(a.jobs) as ex:
            list(ex.map(lambda c: run_case(a.sphdem, a.scene, a.out, c[0], c[1], a.until, c[2],
                                           a.mach_max), cases))
    missing = [run_dir(a.out, *c) for c in cases
               if not os.path.exists(os.path.join(run_dir(a.out, *c), "summary.json"))]
    for d in missing:  # not run, or sphdem refused the case: its log says why
        print("%s: no summary.json, left out (see %s.log)" % (d, d), file=sys.stderr)
    rows = [summarize(run_dir(a.out, *c), *c[:2], a.until, c[2]) for c in cases
            if run_dir(a.out, *c) not in missing]
    done = [r for r in rows if r["status"] == "completed" and r["t_end"] >= a.until - 1e-6]
    refs = [r for r in done if r["limiter"] == "off" and r["cfl"] == "scene"]
    if not refs:
        raise SystemExit("no completed limiter-off run to compare with")
    ref = min(refs, key=lambda r: r["dp_mm"])
    for r in rows:
        ok = r in done and r is not ref
        for k in KEYS:
            r["diff_" + k] = abs(r[k] - ref[k]) / abs(ref[k]) if ok and ref[k] else float("nan")
    cols = ["dp_mm", "limiter", "cfl", "mach_max", "fluid", "steps", "wall_s", "status", "t_end", "peak_50ms",
            "t_peak", "impulse", "late_mean", "max_runup", "mach_peak", "t_mach_peak", "clips_max",
            "cut_max"] + \
        ["diff_" + k for k in KEYS]
    base = os.path.join(a.out, "thin_plate_study")
    flume_study.write_table(base, cols, rows, lambda v: v if isinstance(v, str) else repr(v))
    try:
        import matplotlib
        matplotlib.use("Agg")
        import matplotlib.pyplot as plt
    except ImportError:
        print("matplotlib missing: no plot (apt-get install python3-matplotlib)", file=sys.stderr)
        return
    fig, axs = plt.subplots(1, len(KEYS), figsize=(14, 3.8))
    for ax, k in zip(axs, KEYS):
        for lim, style in (("off", "o-"), ("on", "s--")):
            pts = [(r["wall_s"], r["diff_" + k], r["dp_mm"]) for r in rows
                   if r["limiter"] == lim and r["cfl"] == "scene" and r["diff_" + k] == r["diff_" + k] and r["diff_" + k] > 0]
            if pts:
                line = ax.loglog([p[0] for p in pts], [p[1] for p in pts], style,
                                 label="limiter " + lim)[0]
                for x, y, dp in pts:
                    ax.annotate("%.2g" % dp, (x, y), fontsize=6)
                # at the wall time of the same dp's scene-CFL run (they may have shared the cores)
                base_wall = {r["dp_mm"]: r["wall_s"] for r in rows
                        if r["limiter"] == lim and r["cfl"] == "scene"}
                var = [(base_wall[r["dp_mm"]], r["diff_" + k]) for r in rows if r["limiter"] == lim and
                       r["cfl"] != "scene" and r["dp_mm"] in base_wall and
                       r["diff_" + k] == r["diff_" + k] and r["diff_" + k] > 0]
                if var:
                    ax.loglog([v[0] for v in var], [v[1] for v in var], style[0], ms=3, alpha=0.5,
                              color=line.get_color(), label="limiter %s, other CFL" % lim)
        ax.set_title(k.replace("_", " "), fontsize=9)
        ax.set_xlabel("wall time to t = %g s (s, 1 thread)" % a.until, fontsize=8)
    axs[0].set_ylabel("difference from dp = %.2f mm, limiter off" % ref["dp_mm"], fontsize=8)
    axs[0].legend(fontsize=7)
    fig.suptitle("2D thin-plate flume: accuracy against cost, mDBC limiter off and on (labels: dp in mm)",
                 fontsize=9)
    fig.tight_layout()
    fig.savefig(base + ".png", dpi=120)


if __name__ == "__main__":
    main()
