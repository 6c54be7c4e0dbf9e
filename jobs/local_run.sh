#!/usr/bin/env bash
# Workstation equivalent of the cluster scripts: run a scene on NRANKS ranks (default 1),
# continuing from the newest checkpoint if the output folder has one. Ctrl-C (SIGINT) stops
# without a checkpoint; use `kill -TERM <pid>` (or -USR1 to checkpoint and continue) for a clean
# stop.
#   jobs/local_run.sh inputs/dam_break_2d.yaml out/dam_break_2d [--set key=value ...]
#   NRANKS=2 OMP_NUM_THREADS=1 jobs/local_run.sh inputs/dam_break_3d.yaml out/db3d
set -euo pipefail
scene=${1:?scene file}; out=${2:?output folder}; shift 2
restart=()
if ls "$out"/checkpoint_*.h5 >/dev/null 2>&1; then restart=(--restart latest); fi
sphdem=${SPHDEM:-build/sphdem}
nranks=${NRANKS:-1}
if [ "$nranks" -gt 1 ]; then
  exec mpirun --oversubscribe -n "$nranks" "$sphdem" run "$scene" --out "$out" "${restart[@]}" "$@"
fi
exec "$sphdem" run "$scene" --out "$out" "${restart[@]}" "$@"
