#!/usr/bin/env bash
# Slurm job: runs one sphdem scene on N ranks, and continues from the newest checkpoint when
# requeued or resubmitted (on any rank count: the checkpoint is redistributed).
#   sbatch --ntasks=4 jobs/slurm_run.sh inputs/dam_break_3d.yaml out/dam_break_3d
#   sbatch --ntasks=1 --gpus-per-task=1 jobs/slurm_run.sh inputs/dam_break_3d.yaml out/db3d_gpu
# Resources: --ntasks ranks, each with --cpus-per-task OpenMP threads. The domain is split into
# one box per rank (PETSc DMDA; --procs below fixes the process grid, default: PETSc chooses).
# With --gpus-per-task=1 every rank uses its own GPU (node-local rank modulo the node's GPUs;
# the halo is staged through host memory; this path is compiled but was never run on a GPU);
# without GPUs every rank runs on its CPU cores.
# Outputs: OUT/run.log, OUT/summary.json, OUT/*.csv, OUT/checkpoint_*.h5, OUT/frames.xdmf.
# Time limit: Slurm sends SIGTERM --signal seconds before the end (below: 300 s); sphdem writes a
# checkpoint on every rank and exits with status 4, and the script requeues itself, so the next
# start continues with --restart latest. Exit status 3 means a stability guard fired (see
# OUT/run.log; an emergency checkpoint is in OUT).
#SBATCH --job-name=sphdem
#SBATCH --ntasks=4
#SBATCH --cpus-per-task=8
#SBATCH --time=04:00:00
#SBATCH --signal=TERM@300
#SBATCH --requeue
#SBATCH --output=sphdem-%j.out
set -uo pipefail
scene=${1:?scene file}
out=${2:?output folder}
shift 2
sphdem=${SPHDEM:-build/sphdem}
export OMP_NUM_THREADS=${SLURM_CPUS_PER_TASK:-1}
restart=()
if ls "$out"/checkpoint_*.h5 >/dev/null 2>&1; then restart=(--restart latest); fi
# srun starts --ntasks ranks; with Open MPI without Slurm PMI support use
#   mpirun -n "$SLURM_NTASKS" "$sphdem" ...
srun "$sphdem" run "$scene" --out "$out" "${restart[@]}" "$@" &
pid=$!
trap 'kill -TERM $pid' TERM
wait $pid; status=$?
[ $status -eq 143 ] && { wait $pid; status=$?; }
if [ $status -eq 4 ]; then
  echo "stopped at the time limit with a checkpoint; requeueing"
  scontrol requeue "$SLURM_JOB_ID"
fi
exit $status
