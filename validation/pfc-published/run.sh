#!/bin/bash
# Seed 003's PFC3D sandstone entered as published, with the contact stiffness of PFC 5+
# (deformability) and of PFC 3.x/4 (ball stiffness 4 R E_c in series): two UCS runs.
#   validation/pfc-published/run.sh OUT    (about 11 min on 2 cores)
#   /usr/bin/python3 validation/pfc-published/compare.py OUT
set -euo pipefail
here=$(cd "$(dirname "$0")" && pwd)
breccia=${BRECCIA:-$here/../../build/breccia}
out=${1:?usage: run.sh OUT}
for b in false true; do
  "$breccia" run "$here/sandstone-ucs.toml" --set contact.ball_stiffness=$b \
    --output "$out/ball_stiffness_$b"
done
