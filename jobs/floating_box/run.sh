#!/usr/bin/env bash
# Floating-box draft against resolution (issue #6): inputs/floating_box.yaml in a smaller cell
# (0.16 m period, water 0.08 m deep once the box floats) with the box released at rest at its
# Archimedes position (centre on the still-water level), at 8, 12 and 16 particles across the
# 0.08 m cube. The draft is the surface gauge (0, 0) (a corner of the periodic cell, 0.04 m from
# the box) minus the box bottom, averaged over the last 0.45 s (one heave period).
# Usage: jobs/floating_box/run.sh OUTDIR [DPS]    -> OUTDIR/summary.csv
# Cost on the 2-core VM (2 threads): dp 0.01 about 2 min, 0.00667 about 8 min, 0.005 about 35 min.
set -euo pipefail
cd "$(dirname "$0")/../.."
out=${1:?output folder}
dps=${2:-"0.01 0.0066666667 0.005"}
bin=${SPHDEM:-build/sphdem}
end=${END:-0.8}
win=0.45
mkdir -p "$out"
echo "dp_m,across,fluid,draft_m,draft_err_pct,heave_range_m,fluid_force_N,weight_N,wall_s" > "$out/summary.csv"
for dp in $dps; do
  d="$out/dp_$dp"
  "$bin" run inputs/floating_box.yaml --out "$d" --quiet \
    --set sph.dp="$dp" --set time.end="$end" \
    --set "domain.hi=[0.16, 0.16, 0.2]" --set "fluid_blocks[0].hi=[0.16, 0.16, 0.09]" \
    --set "dem.bodies[0].position=[0.08, 0.08, 0.09]" \
    --set "diagnostics.height_gauges=[{name: surface, x: 0, y: 0}]" > /dev/null
  fluid=$(sed -n 's/^particles: \([0-9]*\) fluid.*/\1/p' "$d/run.log" | head -1)
  wall=$(sed -n 's/.*"wall_seconds": \([0-9.e]*\).*/\1/p' "$d/summary.json")
  # bodies.csv: t,id,x,y,z,...,fz (column 14); surface.csv: t,h. Same diagnostic times.
  awk -F, -v W=$win -v dp="$dp" -v fl="$fluid" -v wall="$wall" '
    NR == FNR { if (FNR > 1) { st[FNR] = $1; sh[FNR] = $2; ns = FNR } next }
    FNR > 1 { t = $1; z[t] = $5; f[t] = $14; last = t }
    END {
      for (i = 2; i <= ns; ++i) {
        t = st[i]; if (t < last - W - 1e-9 || !(t in z)) continue
        n++; s += sh[i]; zb += z[t]; fz += f[t]
        if (n == 1 || z[t] < lo) lo = z[t]; if (n == 1 || z[t] > hi) hi = z[t]
      }
      d = s / n - (zb / n - 0.04); w = 500 * 0.08^3 * 9.81
      printf "%s,%.0f,%s,%.5f,%.2f,%.5f,%.4f,%.4f,%s\n", dp, 0.08 / dp, fl, d, 100 * (d / 0.04 - 1),
             hi - lo, fz / n, w, wall
    }' "$d/surface.csv" "$d/bodies.csv" >> "$out/summary.csv"
done
cat "$out/summary.csv"
