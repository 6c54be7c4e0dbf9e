#!/usr/bin/env bash
# PBS job: runs one sphdem scene and continues from the newest checkpoint when resubmitted.
#   qsub -v SCENE=inputs/dam_break_3d.yaml,OUT=out/dam_break_3d jobs/pbs_run.sh
# Resources: one chunk with one GPU; single-rank (see jobs/slurm_run.sh). PBS sends SIGTERM
# before killing a job at its walltime; sphdem then writes a checkpoint and exits with status 4:
# resubmit the same command to continue (--restart latest is added automatically).
#PBS -N sphdem
#PBS -l select=1:ncpus=8:ngpus=1
#PBS -l walltime=04:00:00
#PBS -j oe
set -uo pipefail
cd "${PBS_O_WORKDIR:-.}"
sphdem=${SPHDEM:-build/sphdem}
export OMP_NUM_THREADS=8
restart=()
if ls "$OUT"/checkpoint_*.h5 >/dev/null 2>&1; then restart=(--restart latest); fi
"$sphdem" run "$SCENE" --out "$OUT" "${restart[@]}"
