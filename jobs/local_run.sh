#!/usr/bin/env bash
# Workstation equivalent of the cluster scripts: run a scene, continuing from the newest
# checkpoint if the output folder has one. Ctrl-C (SIGINT) stops without a checkpoint; use
# `kill -TERM <pid>` (or -USR1 to checkpoint and continue) for a clean stop.
#   jobs/local_run.sh inputs/dam_break_2d.yaml out/dam_break_2d [--set key=value ...]
set -euo pipefail
scene=${1:?scene file}; out=${2:?output folder}; shift 2
restart=()
if ls "$out"/checkpoint_*.h5 >/dev/null 2>&1; then restart=(--restart latest); fi
exec "${SPHDEM:-build/sphdem}" run "$scene" --out "$out" "${restart[@]}" "$@"
