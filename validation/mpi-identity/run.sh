#!/usr/bin/env bash
# Every example experiment run in one process and under `mpirun -np RANKS --oversubscribe` (the
# sample split over the ranks), its run folders compared file by file, byte for byte. Only what
# depends on the clock and the launch is left out: manifest.json, summary.json's timings, and
# the plot and report made from the tables (`output.plot=false` in both runs).
#
#   validation/mpi-identity/run.sh [RANKS] [EXAMPLE.toml ...]    (default: 4, every example run)
#
# Calibrations (examples/calibrate-*.toml) spread their trials over ranks instead: each trial is a
# whole run on one rank (tests/test_mpi.cpp compares such a calibration with one process).
# Environment: BRECCIA (default build/breccia), OUT (default runs/mpi-identity), THREADS (per rank,
# default 1), ONE_THREADS (for the one process, default THREADS: results do not depend on it, so
# the reference run may take every core), MPIRUN (default mpirun), PYTHON (default /usr/bin/python3),
# JOBS (examples at once, default 1: each example runs in one process, then on RANKS ranks, so
# JOBS x RANKS cores keep every rank on a core of its own), RESUME (1: keep what an earlier call
# left in OUT, resume a run it left unfinished from its checkpoint with the same build, and
# reuse a complete one; the times are then this call's only).
# Prints a table; exits 1 if any file differs.
set -uo pipefail
root="$(cd "$(dirname "${BASH_SOURCE[0]}")/../.." && pwd)"
ranks="${1:-4}"
shift || true
breccia="${BRECCIA:-$root/build/breccia}"
out="${OUT:-$root/runs/mpi-identity}"
threads="${THREADS:-1}"
one_threads="${ONE_THREADS:-$threads}"
mpirun="${MPIRUN:-mpirun}"
python="${PYTHON:-/usr/bin/python3}"
jobs="${JOBS:-1}"
resume="${RESUME:-0}"
examples=("$@")
if [ ${#examples[@]} -eq 0 ]; then
  for f in "$root"/examples/*.toml; do
    case "$(basename "$f")" in calibrate-*) ;; *) examples+=("$f") ;; esac
  done
fi
export OMPI_ALLOW_RUN_AS_ROOT=1 OMPI_ALLOW_RUN_AS_ROOT_CONFIRM=1
export OMPI_MCA_btl="${OMPI_MCA_btl:-self,vader}"
export OMPI_MCA_btl_vader_single_copy_mechanism="${OMPI_MCA_btl_vader_single_copy_mechanism:-none}"
export OMP_NUM_THREADS="$threads"
compare="$root/validation/mpi-identity/compare.py"

# One side of an example (one | ranks): its run folder, run now, resumed from the checkpoint an
# earlier call left (RESUME=1), or as that call completed it. `launcher` is empty for one process.
run_side() {
  local name="$1" side="$2" threads_here="$3"
  shift 3
  local launcher=("$@") dir state
  local common=(--quiet --threads "$threads_here")
  dir="$(ls -d "$out/$name/$side"/2*/ 2>/dev/null | head -1)"
  if [ "$resume" = 1 ] && [ -n "$dir" ]; then
    dir="${dir%/}"
    state=$("$python" -c 'import json,sys; print(json.load(open(sys.argv[1]))["status"])' \
      "$dir/manifest.json" 2>/dev/null)
    if [ "$state" = complete ]; then
      echo "$dir"
      return
    fi
    OMP_NUM_THREADS="$threads_here" "${launcher[@]}" "$breccia" resume "$dir" "${common[@]}" \
      2>>"$out/$name/$side.log" | tail -1
    return
  fi
  OMP_NUM_THREADS="$threads_here" "${launcher[@]}" "$breccia" run "$ex" "${common[@]}" \
    --set output.plot=false --output "$out/$name/$side" 2>"$out/$name/$side.log" | tail -1
}

# One example, both ways; prints its table row, and fails when a run failed or a file differs.
one_example() {
  local ex="$1" name a b t0 t1 t2 result
  name="$(basename "$ex" .toml)"
  [ "$resume" = 1 ] || rm -rf "${out:?}/$name"
  mkdir -p "$out/$name/one" "$out/$name/ranks"
  t0=$(date +%s)
  a=$(run_side "$name" one "$one_threads")
  t1=$(date +%s)
  b=$(run_side "$name" ranks "$threads" "$mpirun" --oversubscribe --bind-to none -np "$ranks")
  t2=$(date +%s)
  if [ -z "$a" ] || [ -z "$b" ] || [ ! -d "$a" ] || [ ! -d "$b" ]; then
    echo "| $name | $((t1 - t0)) s | $((t2 - t1)) s | - | run failed (see $out/$name/*.log) |"
    return 1
  fi
  local rc=0
  result=$("$python" "$compare" "$a" "$b") || rc=1
  echo "| $name | $((t1 - t0)) s | $((t2 - t1)) s | $result |"
  return $rc
}

status=0
echo "| example | one process | $ranks ranks | files compared | differing |"
echo "|---|---|---|---|---|"
running=0
for ex in "${examples[@]}"; do
  if [ "$jobs" -le 1 ]; then
    one_example "$ex" || status=1
    continue
  fi
  if [ "$running" -ge "$jobs" ]; then
    wait -n || status=1
    running=$((running - 1))
  fi
  one_example "$ex" &
  running=$((running + 1))
done
while [ "$running" -gt 0 ]; do
  wait -n || status=1
  running=$((running - 1))
done
exit $status
