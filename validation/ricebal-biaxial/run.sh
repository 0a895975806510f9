#!/usr/bin/env bash
# Seed 002's confining sweep (0, 2, 5, 10, 15, 20, 25, 30, 40, 50 MPa; biaxial tests between
# membranes to 10.3 % axial strain) on a RICEBAL-style 2D rock, then the table beside the paper's
# numbers (compare.py). Run by hand, not by CI: the sweep's ten tests go two at a time.
#   validation/ricebal-biaxial/run.sh [experiment.toml] [output folder] [extra --set ...]
# An experiment whose preset is lac_du_bonnet_2d (lac-du-bonnet-2d-small.toml) is compared with
# the seed's granite.
# The default experiment is berea-2d-small.toml (the 2D Berea preset on the calibration's sample
# of about 860 grains: about 5 min per test on 1 thread); examples/biaxial-berea-2d.toml is the
# same rock on about 3,400 grains (12-15 min per test on 1 thread; the sweep 66 min on 2 cores).
set -euo pipefail
here="$(cd "$(dirname "${BASH_SOURCE[0]}")" && pwd)"
root="$(cd "$here/../.." && pwd)"
experiment="${1:-$here/berea-2d-small.toml}"
out="${2:-/tmp/breccia-ricebal-biaxial}"
shift $(( $# > 2 ? 2 : $# ))
sets=()
for s in "$@"; do sets+=(--set "$s"); done
folder=$("$root/build/breccia" sweep "$experiment" --output "$out" \
  --confining-mpa 0 2 5 10 15 20 25 30 40 50 "${sets[@]}" | tail -1)
rock=berea
grep -q 'lac_du_bonnet' "$experiment" && rock=lac_du_bonnet
/usr/bin/python3 "$here/compare.py" "$folder" --rock "$rock"
