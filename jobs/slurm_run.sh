#!/usr/bin/env bash
# Slurm job: runs one sphdem scene, and continues from the newest checkpoint when resubmitted.
#   sbatch jobs/slurm_run.sh inputs/dam_break_3d.yaml out/dam_break_3d
# Resources: one task with one GPU (sphdem uses the GPU it sees, or the CPU cores when there is
# none). sphdem is single-rank for now: the MPI decomposition module exists but is not yet wired
# into the time loop, so do not raise --ntasks.
# Outputs: OUT/run.log, OUT/summary.json, OUT/*.csv, OUT/checkpoint_*.h5, OUT/frames.xdmf.
# Time limit: Slurm sends SIGTERM --signal seconds before the end (below: 300 s); sphdem writes a
# checkpoint and exits with status 4, and the script requeues itself, so the next start continues
# with --restart latest. Exit status 3 means a stability guard fired (see OUT/run.log).
#SBATCH --job-name=sphdem
#SBATCH --ntasks=1
#SBATCH --cpus-per-task=8
#SBATCH --gpus-per-task=1
#SBATCH --time=04:00:00
#SBATCH --signal=TERM@300
#SBATCH --requeue
#SBATCH --output=sphdem-%j.out
set -uo pipefail
scene=${1:?scene file}
out=${2:?output folder}
sphdem=${SPHDEM:-build/sphdem}
export OMP_NUM_THREADS=${SLURM_CPUS_PER_TASK:-1}
restart=()
if ls "$out"/checkpoint_*.h5 >/dev/null 2>&1; then restart=(--restart latest); fi
srun --ntasks=1 "$sphdem" run "$scene" --out "$out" "${restart[@]}" &
pid=$!
trap 'kill -TERM $pid' TERM
wait $pid; status=$?
[ $status -eq 143 ] && { wait $pid; status=$?; }
if [ $status -eq 4 ]; then
  echo "stopped at the time limit with a checkpoint; requeueing"
  scontrol requeue "$SLURM_JOB_ID"
fi
exit $status
