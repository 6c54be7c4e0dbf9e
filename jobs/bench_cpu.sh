#!/usr/bin/env bash
# CPU benchmark of the 3D dam break at ~100k and ~1M fluid particles, 1 and 2 OpenMP threads,
# double (build/) and float (build-float/) precision. Output: one JSON object per line.
# Usage: jobs/bench_cpu.sh [STEPS] > bench.jsonl
set -euo pipefail
cd "$(dirname "$0")/.."
steps=${1:-5}
for build in build build-float; do
  [ -x "$build/sphdem" ] || continue
  for n in 100000 1000000; do
    for t in 1 2; do
      warm=2; s=$steps
      if [ "$n" -ge 1000000 ]; then warm=1; s=$(( steps < 3 ? steps : 3 )); fi
      OMP_NUM_THREADS=$t OMP_WAIT_POLICY=passive "$build/sphdem" bench inputs/dam_break_3d.yaml \
        --particles "$n" --steps "$s" --warmup "$warm" --backend host --json | tr -d '\n '
      echo
    done
  done
done
