#!/usr/bin/env bash
# CPU benchmark of the 3D dam break, 1 and 2 OpenMP threads, double (build/) and float
# (build-float/) precision. Output: one JSON object per line.
# Usage: jobs/bench_cpu.sh [STEPS] > bench.jsonl
#   SIZES="100000 1000000" (default)   fluid particle counts
#   SETS="--set sph.h_factor=1.0"      extra scene overrides for every run (default none)
#   BOUNDARIES="mdbc dbc"              one pass per wall model (default: the scene's, mdbc)
# The issue's seed kernel ratio h/dp = 1.73 (about 170 neighbours) at 25k and 170k particles:
#   SIZES="25000 170000" SETS="--set sph.h_factor=1.0" BOUNDARIES="mdbc dbc" jobs/bench_cpu.sh 10
set -euo pipefail
cd "$(dirname "$0")/.."
steps=${1:-5}
sizes=${SIZES:-100000 1000000}
boundaries=${BOUNDARIES:-mdbc}
for build in build build-float; do
  [ -x "$build/sphdem" ] || continue
  for b in $boundaries; do
    for n in $sizes; do
      for t in 1 2; do
        warm=2; s=$steps
        if [ "$n" -ge 1000000 ]; then warm=1; s=$(( steps < 3 ? steps : 3 )); fi
        # shellcheck disable=SC2086
        OMP_NUM_THREADS=$t OMP_WAIT_POLICY=passive "$build/sphdem" bench inputs/dam_break_3d.yaml \
          --particles "$n" --steps "$s" --warmup "$warm" --backend host --json \
          --set "sph.boundary=$b" ${SETS:-} | tr -d '\n '
        echo
      done
    done
  done
done
