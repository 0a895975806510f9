#!/bin/bash
# A confining-stress sweep spread over the ranks of a Slurm allocation (a build with MPI; README,
# "On a cluster"). Each rank runs one run of the sweep at a time with its OpenMP threads, so
# 8 ranks run 8 confining stresses at once; the run folders are those one process writes.
#
#   sbatch examples/slurm-sweep.sh                # start the sweep
#   sbatch examples/slurm-sweep.sh SWEEP_FOLDER   # finish one that hit the time limit
#
# Five minutes before the time limit Slurm signals this script (USR1), which passes the signal to
# mpirun, which passes it to every rank: each run stops with a checkpoint, and resubmitting with
# the sweep folder continues them where they stopped. For runs too large for one rank, add
# `--ranks-per-run K` to the sweep (and the resume): each run is then split over K ranks, and
# 8 / K runs go at once.
#SBATCH --job-name=breccia-sweep
#SBATCH --nodes=2
#SBATCH --ntasks-per-node=4
#SBATCH --cpus-per-task=8
#SBATCH --time=12:00:00
#SBATCH --signal=B:USR1@300
set -euo pipefail
threads=${SLURM_CPUS_PER_TASK:-1}
export OMP_NUM_THREADS=$threads OMP_PROC_BIND=close OMP_PLACES=cores
if [ $# -ge 1 ]; then
  command=(resume "$1")
else
  command=(sweep --confining-mpa 0 5 10 20 30 40 60 80 --set engine.threads="$threads"
           --set output.directory=\"runs/cluster\")
fi
mpirun --map-by "ppr:${SLURM_NTASKS_PER_NODE:-1}:node:pe=$threads" build/breccia "${command[@]}" &
launcher=$!
trap 'kill -USR1 "$launcher"' USR1
# `wait` returns when the trap fires; the second waits for the ranks' checkpoints.
wait "$launcher" || wait "$launcher"
