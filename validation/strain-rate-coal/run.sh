#!/usr/bin/env bash
# Seed 004's strain-rate study: UCS of the `coal` preset at several loading rates (no density
# scaling), the fit UCS = a exp(b rate) and the failure plane, beside the seed's numbers.
# Run by hand, not by CI.
#   validation/strain-rate-coal/run.sh [output folder] [rates...]   (default: 0.5 1 5 10)
#   validation/strain-rate-coal/run.sh SWEEP_FOLDER                  (finish a stopped sweep)
# The steps grow as 1 / rate: 0.5-10 /s take about 30 min on 2 cores; 0.1 /s (2.27 M steps)
# about 2 hours of one core, 0.05 /s (4.55 M steps) about 3.4 hours on 2 threads. A sweep
# stopped on the way (Ctrl-C, a time limit) keeps its checkpoints: give its folder to finish it.
set -euo pipefail
here="$(cd "$(dirname "${BASH_SOURCE[0]}")" && pwd)"
root="$(cd "$here/../.." && pwd)"
out="${1:-/tmp/breccia-strain-rate}"
shift $(( $# > 0 ? 1 : 0 ))
rates=("$@")
[ ${#rates[@]} -eq 0 ] && rates=(0.5 1 5 10)
status=0
if [ -f "$out/sweep-plan.json" ]; then
  folder=$("$root/build/breccia" resume "$out" | tail -1) || status=$?
else
  folder=$("$root/build/breccia" sweep "$root/examples/strain-rate.toml" --output "$out" \
    --strain-rates "${rates[@]}" | tail -1) || status=$?
fi
if [ "$status" -ne 0 ]; then
  echo "the sweep stopped (exit $status); finish it with: $0 $folder" >&2
  exit "$status"
fi
/usr/bin/python3 "$here/compare.py" "$folder"
