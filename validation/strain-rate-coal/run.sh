#!/usr/bin/env bash
# Seed 004's strain-rate study: UCS of the `coal` preset at several loading rates (no density
# scaling), the fit UCS = a exp(b rate) and the failure plane, beside the seed's numbers.
# Run by hand, not by CI.
#   validation/strain-rate-coal/run.sh [output folder] [rates...]   (default: 0.5 1 5 10)
# The steps grow as 1 / rate: 0.5-10 /s take about 30 min on 2 cores; adding 0.05 and 0.1 /s
# (the seed's lowest) takes about 3 hours.
set -euo pipefail
here="$(cd "$(dirname "${BASH_SOURCE[0]}")" && pwd)"
root="$(cd "$here/../.." && pwd)"
out="${1:-/tmp/breccia-strain-rate}"
shift $(( $# > 0 ? 1 : 0 ))
rates=("$@")
[ ${#rates[@]} -eq 0 ] && rates=(0.5 1 5 10)
folder=$("$root/build/breccia" sweep "$root/examples/strain-rate.toml" --output "$out" \
  --strain-rates "${rates[@]}" | tail -1)
/usr/bin/python3 "$here/compare.py" "$folder"
