#!/usr/bin/env bash
# Seed 000's failure predictor on Breccia's confining sweeps: trains (leave-one-test-out
# validation, Garson importances) and prints the tables of docs/prediction.md. Run by hand.
#   validation/failure-predictor/run.sh MODEL_FOLDER SWEEP_FOLDER... [-- --inputs a,b,c]
set -euo pipefail
here="$(cd "$(dirname "${BASH_SOURCE[0]}")" && pwd)"
root="$(cd "$here/../.." && pwd)"
model="$1"; shift
folders=(); extra=()
while [ $# -gt 0 ]; do
  if [ "$1" = "--" ]; then shift; extra=("$@"); break; fi
  folders+=("$1"); shift
done
"$root/build/breccia" predict train "${folders[@]}" --output "$model" "${extra[@]}"
/usr/bin/python3 "$here/table.py" "$model"
