#!/bin/bash
# One run whose sample is split over the ranks of a Slurm allocation on one node (a build with MPI;
# README, "On a cluster"). Each rank steps its part of the sample with its OpenMP threads, and the
# run folder is the one a single process writes, byte for byte. The ranks share every grain after
# each step, so keep the run on one node.
#
#   sbatch examples/slurm-run.sh EXPERIMENT.toml   # start the run
#   sbatch examples/slurm-run.sh RUN_FOLDER        # finish one that hit the time limit
#
# Five minutes before the time limit Slurm signals this script (USR1), which passes the signal to
# mpirun, which passes it to every rank: the ranks stop together with one checkpoint, in the
# format of one process, and resubmitting with the run folder continues it on any rank count.
#SBATCH --job-name=breccia-run
#SBATCH --nodes=1
#SBATCH --ntasks-per-node=4
#SBATCH --cpus-per-task=8
#SBATCH --time=12:00:00
#SBATCH --signal=B:USR1@300
set -euo pipefail
if [ $# -lt 1 ]; then
  echo "usage: sbatch examples/slurm-run.sh EXPERIMENT.toml | RUN_FOLDER" >&2
  exit 2
fi
threads=${SLURM_CPUS_PER_TASK:-1}
export OMP_NUM_THREADS=$threads OMP_PROC_BIND=close OMP_PLACES=cores
if [ -d "$1" ]; then
  command=(resume "$1" --threads "$threads")
else
  command=(run "$1" --threads "$threads" --output runs/cluster)
fi
mpirun --map-by "ppr:${SLURM_NTASKS_PER_NODE:-1}:node:pe=$threads" build/breccia "${command[@]}" &
launcher=$!
trap 'kill -USR1 "$launcher"' USR1
# `wait` returns when the trap fires; the second waits for the ranks' checkpoint.
wait "$launcher" || wait "$launcher"
