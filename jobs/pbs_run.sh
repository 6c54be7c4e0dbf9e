#!/usr/bin/env bash
# PBS job: runs one sphdem scene on NRANKS MPI ranks and continues from the newest checkpoint
# when resubmitted (on any rank count).
#   qsub -v SCENE=inputs/dam_break_3d.yaml,OUT=out/dam_break_3d,NRANKS=4 jobs/pbs_run.sh
# Resources: one chunk per rank (edit select= to match NRANKS; add ngpus=1 per chunk for one GPU
# per rank, see jobs/slurm_run.sh). PBS sends
# SIGTERM before killing a job at its walltime; sphdem then writes a checkpoint and exits with
# status 4: resubmit the same command to continue (--restart latest is added automatically).
# Outputs: as jobs/slurm_run.sh.
#PBS -N sphdem
#PBS -l select=4:ncpus=8:mpiprocs=1
#PBS -l walltime=04:00:00
#PBS -j oe
set -uo pipefail
cd "${PBS_O_WORKDIR:-.}"
sphdem=${SPHDEM:-build/sphdem}
nranks=${NRANKS:-4}
export OMP_NUM_THREADS=8
restart=()
if ls "$OUT"/checkpoint_*.h5 >/dev/null 2>&1; then restart=(--restart latest); fi
mpirun -n "$nranks" -x OMP_NUM_THREADS "$sphdem" run "$SCENE" --out "$OUT" "${restart[@]}"
