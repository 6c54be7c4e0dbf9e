#!/usr/bin/env bash
# GPU benchmark of the 3D dam break on the device backend: sizes x precisions x wall models x
# kernel ratios, one JSON object per line on stdout.
# Usage: jobs/bench_gpu.sh [STEPS] > bench_gpu.jsonl
#   BINS="build/sphdem build-gpu-float/sphdem"   CUDA builds to time (double, float)
#   SIZES="1000000 170000"                         fluid particle counts
#   BOUNDARIES="mdbc dbc"                          wall models
#   HFACTORS="1.2 1.0"                             sph.h_factor (1.0: the seed's h/dp = 1.73)
# Each run: 5 warm-up steps, then STEPS (default 20) timed steps; phases are timed with a
# device synchronize before each clock read (sphdem bench, solver tick()).
set -uo pipefail
steps=${1:-20}
for n in ${SIZES:-1000000 170000}; do
  for b in ${BOUNDARIES:-mdbc dbc}; do
    for hf in ${HFACTORS:-1.2 1.0}; do
      for bin in ${BINS:-build/sphdem build-gpu-float/sphdem}; do
        [ -x "$bin" ] || continue
        "$bin" bench "${SCENE:-inputs/dam_break_3d.yaml}" --particles "$n" --steps "$steps" \
          --warmup 5 --backend device --json --set "sph.boundary=$b" --set "sph.h_factor=$hf" |
          tr -d '\n '
        echo
      done
    done
  done
done
