#!/usr/bin/env python3
"""The slit-barrier flume studies (issue #6, seed §5.2-5.4), one case per run:

  --study arrangement  inputs/flume/flume.yaml, one case per barrier preset (--presets)
  --study fraction     boulders at the seed's solid volume fractions 0, 0.167, 0.334, 0.822 and
                       1.176 % of the 3.46 L of debris: 0, 3, 5, 13, 19 glass beads
                       (inputs/flume/flume_boulders.yaml; 0 is flume.yaml)
  --study shape        13 boulders (0.822 %): 16 mm glass beads against irregular grains of the
                       same volume (random convex polyhedra, 12 planes, 8 seeded variants)

It writes OUT/summary.csv and OUT/summary.md with, per case, the opening ratio (from
`sphdem check`), the peak force on the middle wall and its time (the largest sample, and the
peak of the 0.05 s running mean, with the total's), the final (static) force, the
largest run-up, the trap ratio (fluid upstream of the row over the fluid still in the domain)
and the upstream share of all the debris, the boulders upstream and downstream at the end, the largest
front speed (over 0.05 s windows of front.csv), and the run's steps and wall time
(summary.json), and draws OUT/force.png (middle-wall force against time, every case on one
axis), OUT/profiles.png (centreline surface at the profile time) and, for cases with grains,
OUT/boulders.png (each boulder's position along the channel against time) and
OUT/barrier_loads.png (the fluid's and the boulders' contact force on all barrier walls).

  python3 jobs/flume_study.py --out runs/flume_study [--study arrangement]
      [--presets P00 P30 P45 V30 V45] [--sphdem build/sphdem]
      [--set sph.dp=0.01 --set time.end=1.2 ...] [--summarize-only] [--until T]

--symmetry models half of each case that is symmetric about the centre line y = 0.2 (P00 and
the case without boulders; the V layouts as built are not symmetric, and grains are not
mirrored): `symmetry: {axis: y, at: 0.2}`, whose diagnostics are the full scene's
(docs/VALIDATION.md, "Symmetry plane"). Where `sphdem check` says the full scene's walls are not
symmetric at the given settings (P00 at dp = 0.00714285714), that case runs as the full scene
and the driver says so.

--channel-end X ends the domain at x = X (an open outflow: fluid past it is removed and
counted), so the fluid that has passed the barrier costs nothing once it is X - 0.6 m below the
row. For V30 at dp = 10 mm and X = 0.9 the middle-wall peak and the run-up are the whole
channel's and the force means and the upstream mass agree to 4 % (docs/VALIDATION.md, "Ending
the domain below the barrier"; other cases and resolutions not compared); front.csv and the
profile then stop at X.

--trend CSV draws OUT/<CSV name>_trend.png from a fraction study's summary table instead of
running: the middle-wall and total peaks (0.05 s running mean) and the largest run-up against
the solid fraction, one point per beads_N row (empty cells are skipped).

  python3 jobs/flume_study.py --out docs/figures --trend docs/figures/flume_fraction_dp5.csv

Each run goes to OUT/<case>/ and is skipped if OUT/<case>/summary.json says it completed (so an
interrupted study continues). Extra --set options apply to every case.
"""
import argparse
import csv
import json
import os
import re
import subprocess
import sys

HERE = os.path.dirname(os.path.abspath(__file__))
ROOT = os.path.dirname(HERE)
SCENE = os.path.join(ROOT, "inputs", "flume", "flume.yaml")
BOULDERS = os.path.join(ROOT, "inputs", "flume", "flume_boulders.yaml")
# The seed's solid volume fractions (§5.3) as bead counts: fraction x 3.46 L / (pi 0.016^3 / 6).
FRACTIONS = [("0", 0), ("0.167%", 3), ("0.334%", 5), ("0.822%", 13), ("1.176%", 19)]
SYMMETRY = "symmetry={axis: y, at: 0.2}"
BARRIER_X = 0.6  # the barrier row of inputs/flume/flume*.yaml (barrier.x), unless --set
IRREGULAR = ("dem.shapes[0]={name: bead, type: polyhedron, diameter: 0.016, planes: 12, "
             "variants: 8, seed: 3}")


def cases(study, presets):
    """(name, scene, extra --set options) per case."""
    if study == "arrangement":
        return [(p, SCENE, ["barrier.preset=" + p]) for p in presets]
    if study == "fraction":
        return [("beads_%d" % n, SCENE if n == 0 else BOULDERS,
                 [] if n == 0 else ["dem.packs[0].count=%d" % n]) for _, n in FRACTIONS]
    if study == "shape":
        return [("spheres_13", BOULDERS, []), ("irregular_13", BOULDERS, [IRREGULAR])]
    raise SystemExit("unknown study " + study)


def read_csv(path):
    with open(path) as f:
        rows = list(csv.reader(f))
    if not rows:  # a file not written to yet (a run that has not reached its first row)
        return [], []
    header = rows[0]
    return header, [[float(v) for v in r] for r in rows[1:] if r]


def check_output(sphdem, scene, case_sets, sets):
    cmd = [sphdem, "check", scene]
    for s in case_sets + sets:
        cmd += ["--set", s]
    return subprocess.run(cmd, check=True, capture_output=True, text=True).stdout


def opening_ratio(sphdem, scene, case_sets, sets):
    out = check_output(sphdem, scene, case_sets, sets)
    m = re.search(r"effective opening ratio ([0-9.]+)", out)
    return float(m.group(1)) if m else float("nan")


def half_is_valid(sphdem, scene, case_sets, sets):
    """Whether the half scene is the full scene's half at these settings: sphdem check warns
    when a wall of the modelled side has no mirror image among the full scene's walls (at
    dp = 0.4 m / 56 the barrier's faces fall on lattice rows and the full barrier is built dp/2
    off the centre line). Returns (valid, the warning lines)."""
    out = check_output(sphdem, scene, case_sets + [SYMMETRY], sets)
    warn = [l for l in out.splitlines() if l.startswith("warning: symmetry:")]
    return not any("have no mirror image among the full scene" in l for l in warn), warn


def finished(run_dir):
    try:
        with open(os.path.join(run_dir, "summary.json")) as f:
            return json.load(f).get("status") == "completed"
    except (OSError, ValueError):
        return False


def write_table(base, cols, rows, fmt=str):
    """BASE.csv (values as fmt gives them) and BASE.md (floats to 4 digits); prints the table."""
    with open(base + ".csv", "w") as f:
        f.write(",".join(cols) + "\n")
        for r in rows:
            f.write(",".join(fmt(r[c]) for c in cols) + "\n")
    with open(base + ".md", "w") as f:
        f.write("| " + " | ".join(cols) + " |\n|" + "---|" * len(cols) + "\n")
        for r in rows:
            f.write("| " + " | ".join(
                "%.4g" % r[c] if isinstance(r[c], float) else str(r[c]) for c in cols) + " |\n")
    print(open(base + ".md").read())


def running_mean(t, f, window):
    """Mean of f over the trailing window (s) ending at each sample."""
    out, j, acc = [], 0, 0.0
    for i in range(len(f)):
        acc += f[i]
        while t[i] - t[j] > window - 1e-9:
            acc -= f[j]
            j += 1
        out.append(acc / (i - j + 1))
    return out


def summarize(run_dir, until=float("inf")):
    """Numbers of one case from its CSV files (rows up to t = until)."""
    h, rows = read_csv(os.path.join(run_dir, "impact_force.csv"))
    rows = [r for r in rows if r[0] <= until]
    walls = sum(1 for c in h
                if c.endswith("_fx") and c.startswith("barrier_") and "_grain_" not in c)
    mid = h.index("barrier_%d_fx" % ((walls + 1) // 2))
    t = [r[0] for r in rows]
    f_mid = [r[mid] for r in rows]
    f_tot = [r[h.index("total_fx")] for r in rows]
    k = max(range(len(rows)), key=lambda i: f_mid[i]) if rows else 0
    # The samples (every diagnostics.every) catch single spikes at coarse dp: the peak of the
    # 0.05 s running mean is the steadier figure.
    s_mid, s_tot = running_mean(t, f_mid, 0.05), running_mean(t, f_tot, 0.05)
    ks = max(range(len(rows)), key=lambda i: s_mid[i]) if rows else 0
    # Static force: mean over the last 10 % of the run.
    def static(f):
        tail = [v for ti, v in zip(t, f) if ti >= t[-1] - 0.1 * (t[-1] - t[0])] if rows else []
        return sum(tail) / len(tail) if tail else 0.0
    # The boulders' contact force on the walls (columns of runs with grains on DEM barrier walls).
    nan = float("nan")
    g_mid_col = "barrier_%d_grain_fx" % ((walls + 1) // 2)
    grains = {"peak_grain_mid_50ms": nan, "static_grain_mid": nan, "static_grain_total": nan,
              "peak_grain_total_50ms": nan, "peak_mid_with_grains_50ms": nan,
              "static_mid_with_grains": nan}
    g_series = g_tot_series = None
    if g_mid_col in h and rows:
        g_mid = [r[h.index(g_mid_col)] for r in rows]
        g_tot = [r[h.index("total_grain_fx")] for r in rows]
        both = [a + b for a, b in zip(f_mid, g_mid)]
        g_series = (t, running_mean(t, g_mid, 0.05))
        g_tot_series = (t, running_mean(t, g_tot, 0.05))
        grains = {"peak_grain_mid_50ms": max(g_series[1]), "static_grain_mid": static(g_mid),
                  "static_grain_total": static(g_tot),
                  "peak_grain_total_50ms": max(g_tot_series[1]),
                  "peak_mid_with_grains_50ms": max(running_mean(t, both, 0.05)),
                  "static_mid_with_grains": static(both)}
    _, ru = read_csv(os.path.join(run_dir, "runup.csv"))
    ru = [r for r in ru if r[0] <= until]
    trap = os.path.join(run_dir, "trap.csv")
    _, tr = read_csv(trap) if os.path.exists(trap) else ([], [])
    tr = [r for r in tr if r[0] <= until]
    up, down = (tr[-1][1], tr[-1][2]) if tr else (0.0, 0.0)
    # Front speed: the largest over 0.05 s windows of front.csv (its rows are every diagnostics.every).
    speed = 0.0
    fpath = os.path.join(run_dir, "front.csv")
    if os.path.exists(fpath):
        _, fr = read_csv(fpath)
        fr = [r for r in fr if r[0] <= until]
        j = 0
        for i in range(len(fr)):
            while fr[i][0] - fr[j][0] > 0.05:
                j += 1
            if fr[i][0] - fr[j][0] >= 0.04:
                speed = max(speed, (fr[i][1] - fr[j][1]) / (fr[i][0] - fr[j][0]))
    grains_up = grains_down = float("nan")
    if tr and len(tr[-1]) > 3:
        grains_up = tr[-1][3]
    if tr and len(tr[-1]) > 4:  # older trap.csv files stop at grains_upstream
        grains_down = tr[-1][4]
    # mdbc_limiter.csv (mDBC with a barrier): the most wall particles the limiter clipped (or,
    # with it off, would have clipped) at one sample, the largest fitted wall density, and the
    # largest change it makes (or would make) to one (files of older runs lack that column).
    clips_max = fit_max = cut_max = float("nan")
    mpath = os.path.join(run_dir, "mdbc_limiter.csv")
    if os.path.exists(mpath):
        _, ml = read_csv(mpath)
        ml = [r for r in ml if r[0] <= until]
        if ml:
            clips_max = max(r[1] for r in ml)
            fit_max = max(r[2] for r in ml)
            if len(ml[0]) > 3:
                cut_max = max(r[3] for r in ml)
    # Wall time and steps of the whole run (summary.json; absent while a run is going).
    wall_s, steps = float("nan"), float("nan")
    try:
        with open(os.path.join(run_dir, "summary.json")) as f:
            sj = json.load(f)
        wall_s, steps = float(sj.get("wall_seconds", "nan")), float(sj.get("steps", "nan"))
    except (OSError, ValueError):
        pass
    return {
        "grains_upstream": grains_up,
        "grains_downstream": grains_down,
        "wall_s": wall_s,
        "steps": steps,
        "limiter_clips_max": clips_max,
        "wall_fit_max": fit_max,
        "wall_cut_max": cut_max,
        "front_speed": speed,
        "t_end": t[-1] if t else 0.0,
        "peak_force_mid": f_mid[k] if rows else 0.0,
        "t_peak": t[k] if rows else 0.0,
        "peak_mid_50ms": s_mid[ks] if rows else 0.0,
        "t_peak_50ms": t[ks] if rows else 0.0,
        "peak_total_50ms": max(s_tot, default=0.0),
        "static_force_mid": static(f_mid),
        "static_total": static(f_tot),
        **grains,
        "max_runup": max((r[1] for r in ru), default=0.0),
        "trap_ratio": up / (up + down) if up + down > 0 else float("nan"),
        # Upstream over all the debris released (trap.csv's first row): fluid that left the
        # domain counts as passed, so this one does not depend on where the domain ends.
        "upstream_of_total": up / (tr[0][1] + tr[0][2]) if tr and tr[0][1] + tr[0][2] > 0
        else float("nan"),
        "series": (t, f_mid),
        "smooth": (t, s_mid),
        "grain_smooth": g_series,
        "total_smooth": (t, s_tot),
        "grain_total_smooth": g_tot_series,
    }


def trend(table, out):
    """Peaks and run-up against the solid fraction, from a fraction study's summary table."""
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    fraction = {"beads_%d" % n: float(f.rstrip("%")) for f, n in FRACTIONS}
    with open(table) as f:
        rows = [r for r in csv.DictReader(f) if r["preset"] in fraction]
    rows.sort(key=lambda r: fraction[r["preset"]])
    panels = [("peak_mid_50ms", "middle-wall peak (N)"), ("peak_total_50ms", "total peak (N)"),
              ("max_runup", "largest run-up (m)")]
    fig, axes = plt.subplots(1, 3, figsize=(10, 3.2))
    for ax, (col, label) in zip(axes, panels):
        pts = [(fraction[r["preset"]], float(r[col])) for r in rows if r.get(col, "") != ""]
        ax.plot([p[0] for p in pts], [p[1] for p in pts], "o-")
        ax.set_xlabel("solid volume fraction (%)")
        ax.set_ylabel(label)
    fig.tight_layout()
    path = os.path.join(out, os.path.splitext(os.path.basename(table))[0] + "_trend.png")
    fig.savefig(path, dpi=120)
    print("wrote", path)


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawTextHelpFormatter)
    ap.add_argument("--out", required=True)
    ap.add_argument("--study", choices=["arrangement", "fraction", "shape"], default="arrangement")
    ap.add_argument("--presets", nargs="+", default=["P00", "P30", "P45", "V30", "V45"])
    ap.add_argument("--sphdem", default=os.path.join(ROOT, "build", "sphdem"))
    ap.add_argument("--set", dest="sets", action="append", default=[])
    ap.add_argument("--summarize-only", action="store_true")
    ap.add_argument("--until", type=float, default=float("inf"),
                    help="summarize rows up to this time only (compare cases that ended early)")
    ap.add_argument("--symmetry", action="store_true",
                    help="model half of the cases symmetric about y = 0.2 (P00, no boulders)")
    ap.add_argument("--channel-end", type=float, metavar="X",
                    help="end the domain (an open outflow) at x = X instead of the channel's "
                         "1.4 m, and the centreline profile with it (docs/VALIDATION.md, "
                         "'Ending the domain below the barrier')")
    ap.add_argument("--trend", metavar="CSV",
                    help="draw the fraction trend from this summary table and stop")
    a = ap.parse_args()
    os.makedirs(a.out, exist_ok=True)
    if a.trend:
        trend(a.trend, a.out)
        return
    if a.channel_end is not None:
        if not BARRIER_X < a.channel_end <= 1.4:
            sys.exit("--channel-end %g: must lie between the barrier row (x = %g m) and the "
                     "channel's end (1.4 m)" % (a.channel_end, BARRIER_X))
        a.sets = ["domain.hi[0]=%r" % a.channel_end,
                  "diagnostics.profiles[0].to[0]=%r" % a.channel_end] + a.sets
    results = []
    for p, scene, case_sets in cases(a.study, a.presets):
        run_dir = os.path.join(a.out, p)
        symmetric = scene == SCENE and (p in ("P00", "beads_0"))
        if a.symmetry and symmetric:
            valid, warn = half_is_valid(a.sphdem, scene, case_sets, a.sets)
            if valid:
                case_sets = case_sets + [SYMMETRY]
                print("case %s: half of it, mirrored about y = 0.2" % p, flush=True)
            else:
                print("case %s: the full scene, since its half is not its half here (sphdem "
                      "check: %s)" % (p, " ".join(warn)), flush=True)
        if not a.summarize_only and not finished(run_dir):
            cmd = [a.sphdem, "run", scene, "--out", run_dir]
            for s in case_sets + a.sets:
                cmd += ["--set", s]
            print(" ".join(cmd), flush=True)
            rc = subprocess.run(cmd).returncode
            if rc != 0:
                print("case %s stopped (exit %d): see %s/run.log" % (p, rc, run_dir), flush=True)
        if not os.path.exists(os.path.join(run_dir, "impact_force.csv")):
            continue
        r = summarize(run_dir, a.until)
        r["preset"] = p
        r["opening_ratio"] = opening_ratio(a.sphdem, scene, case_sets, a.sets)
        r["finished"] = finished(run_dir)
        results.append(r)
    cols = ["preset", "opening_ratio", "peak_force_mid", "t_peak", "peak_mid_50ms", "t_peak_50ms",
            "peak_total_50ms", "static_force_mid", "static_total", "peak_grain_mid_50ms",
            "static_grain_mid", "static_grain_total", "peak_grain_total_50ms",
            "peak_mid_with_grains_50ms", "static_mid_with_grains", "max_runup", "trap_ratio",
            "upstream_of_total", "grains_upstream", "grains_downstream", "front_speed", "t_end",
            "limiter_clips_max", "wall_fit_max", "wall_cut_max", "steps", "wall_s", "finished"]
    write_table(os.path.join(a.out, "summary"), cols, results)
    try:
        import matplotlib
        matplotlib.use("Agg")
        import matplotlib.pyplot as plt
    except ImportError:
        print("matplotlib missing: no plots (apt-get install python3-matplotlib)", file=sys.stderr)
        return
    fig, ax = plt.subplots(figsize=(7, 4))
    for r in results:
        line, = ax.plot(*r["smooth"], label="%s (opening %.3f)" % (r["preset"], r["opening_ratio"]))
        ax.plot(*r["series"], color=line.get_color(), alpha=0.25, linewidth=0.7)
        if r["grain_smooth"]:
            ax.plot(*r["grain_smooth"], color=line.get_color(), linestyle="--", linewidth=1,
                    label="%s: boulders' contact force" % r["preset"])
    ax.set_xlabel("t (s)")
    ax.set_ylabel("force on the middle wall along the channel (N)\n(fluid: 0.05 s running mean, "
                  "samples faint;\nboulders' contacts dashed, 0.05 s running mean)")
    ax.legend()
    fig.tight_layout()
    fig.savefig(os.path.join(a.out, "force.png"), dpi=120)
    # The whole barrier: the fluid's force on all walls and the boulders' contacts on all walls.
    with_loads = [r for r in results if r["grain_total_smooth"]]
    if with_loads:
        fig, ax = plt.subplots(figsize=(7, 4))
        for r in with_loads:
            line, = ax.plot(*r["total_smooth"], label="%s: fluid" % r["preset"])
            ax.plot(*r["grain_total_smooth"], color=line.get_color(), linestyle="--",
                    label="%s: boulders' contacts" % r["preset"])
        ax.set_xlabel("t (s)")
        ax.set_ylabel("force on all barrier walls along the channel (N)\n(0.05 s running mean)")
        ax.legend()
        fig.tight_layout()
        fig.savefig(os.path.join(a.out, "barrier_loads.png"), dpi=120)
    fig, ax = plt.subplots(figsize=(7, 4))
    for r in results:
        path = os.path.join(a.out, r["preset"], "runup_profile.csv")
        if not os.path.exists(path):
            continue
        _, rows = read_csv(path)  # t, s, x, y, z_surface
        if not rows:
            continue
        t0 = rows[0][0]
        ax.plot([q[2] for q in rows if q[0] == t0], [q[4] for q in rows if q[0] == t0],
                label="%s, t = %.2f s" % (r["preset"], t0))
    ax.set_xlabel("x along the channel (m)")
    ax.set_ylabel("surface elevation (m)")
    ax.legend()
    fig.tight_layout()
    fig.savefig(os.path.join(a.out, "profiles.png"), dpi=120)
    # Boulders: each grain's position along the channel against time (bodies.csv), one panel per
    # case with grains, the barrier row dashed.
    with_grains = [r for r in results
                   if os.path.exists(os.path.join(a.out, r["preset"], "bodies.csv"))]
    if with_grains:
        barrier_x = BARRIER_X  # or the last --set barrier.x=...
        for opt in a.sets:
            if opt.replace(" ", "").startswith("barrier.x="):
                barrier_x = float(opt.split("=", 1)[1])
        fig, axes = plt.subplots(1, len(with_grains), figsize=(3.5 * len(with_grains), 3.5),
                                 sharey=True, squeeze=False)
        for ax, r in zip(axes[0], with_grains):
            h, rows = read_csv(os.path.join(a.out, r["preset"], "bodies.csv"))
            it, iid, ix = h.index("t"), h.index("id"), h.index("x")
            tracks = {}
            for q in rows:
                tracks.setdefault(int(q[iid]), ([], []))
                tracks[int(q[iid])][0].append(q[it])
                tracks[int(q[iid])][1].append(q[ix])
            for tt, xx in tracks.values():
                ax.plot(tt, xx, linewidth=0.8)
            ax.axhline(barrier_x, color="k", linestyle="--", linewidth=0.8)
            ax.set_title(r["preset"])
            ax.set_xlabel("t (s)")
        axes[0][0].set_ylabel("boulder x along the channel (m)\n(barrier row dashed)")
        fig.tight_layout()
        fig.savefig(os.path.join(a.out, "boulders.png"), dpi=120)


if __name__ == "__main__":
    main()
