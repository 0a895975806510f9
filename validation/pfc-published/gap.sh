#!/bin/bash
# Seed 003's PFC3D sandstone with PFC 3.x/4 ball stiffness, bonded at six installation gaps
# (sample.bond_gap_tolerance): how the bond coordination sets E and Poisson's ratio.
#   validation/pfc-published/gap.sh OUT    (six UCS runs, 14-22 min each on 1 thread)
#   /usr/bin/python3 validation/pfc-published/compare.py OUT
set -euo pipefail
here=$(cd "$(dirname "$0")" && pwd)
breccia=${BRECCIA:-$here/../../build/breccia}
out=${1:?usage: gap.sh OUT}
for g in 0 5e-6 2e-5 5e-5 7.5e-5 1e-4; do
  "$breccia" run "$here/sandstone-ucs.toml" --threads 1 --set contact.ball_stiffness=true \
    --set sample.bond_gap_tolerance=$g --output "$out/gap_$g"
done
