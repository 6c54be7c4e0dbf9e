#!/usr/bin/env bash
# Catalyst in-situ overhead (docs/BENCHMARKS.md, "Catalyst in situ"): the same runs with and
# without the inputs/catalyst scripts, and the adaptor's own timing (OUT/catalyst/timing.json:
# the first extract step, which also starts ParaView's Python, and the mean of the others).
# Needs a Catalyst build: make build BUILD=build-catalyst CATALYST=ON.
# Usage: jobs/bench_catalyst.sh [OUT_ROOT]   (OMP_NUM_THREADS defaults to 1)
set -euo pipefail
cd "$(dirname "$0")/.."
root=${1:-/tmp/sphdem_bench_catalyst}
bin=build-catalyst/sphdem
export OMP_NUM_THREADS=${OMP_NUM_THREADS:-1}
all="catalyst/impact_force.py, catalyst/runup.py, catalyst/particles.py"
quiet_diag='diagnostics={every: 100, energy: false}'

# name scene steps every scripts [--set ...]: one run; prints the wall time and timing.json.
run() {
  local name=$1 scene=$2 steps=$3 every=$4 scripts=$5
  shift 5
  local out=$root/$name
  rm -rf "$out"
  local insitu=()
  [ -n "$scripts" ] && insitu=(--set "insitu={scripts: [$scripts], every_steps: $every}")
  "$bin" run "$scene" --out "$out" --quiet --max-steps "$steps" --set "$quiet_diag" \
    "${insitu[@]}" "$@" > /dev/null
  local wall
  wall=$(sed -n 's/^done: .*, \([0-9.e+-]*\) s wall.*/\1/p' "$out/run.log")
  printf '%-24s %s s wall  %s\n' "$name" "$wall" \
    "$( [ -f "$out/catalyst/timing.json" ] && cat "$out/catalyst/timing.json" || echo)"
}

echo "# $(date -u +%FT%TZ) commit $(git rev-parse --short HEAD) load $(cut -d' ' -f1-3 /proc/loadavg)"
grep -m1 'model name' /proc/cpuinfo
# 2D dam break, 3200 fluid + 1810 wall particles: 201 steps, extracts every 10 steps.
d2=inputs/dam_break_2d.yaml
run 2d-off "$d2" 201 10 ""
run 2d-all "$d2" 201 10 "$all"
for s in impact_force runup particles; do run "2d-$s" "$d2" 201 10 "catalyst/$s.py"; done
# 3D dam break at dp = 0.0044 (98,010 fluid + 82,900 wall): 5 steps, an extract every step.
d3=inputs/dam_break_3d.yaml
run 3d100k-off "$d3" 5 1 "" --set sph.dp=0.0044
run 3d100k-all "$d3" 5 1 "$all" --set sph.dp=0.0044
# 3D dam break as shipped (1,065,800 fluid + 869,600 wall): 3 steps, an extract every step.
run 3d1M-all "$d3" 3 1 "$all"
