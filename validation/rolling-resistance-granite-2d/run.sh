#!/bin/bash
# Friction angle of the 2D Lac du Bonnet granite with and without rolling resistance:
# UCS and membrane biaxial tests at 10 and 30 MPa, packings 1 and 2, rolling friction 0 and 0.3.
#   validation/rolling-resistance-granite-2d/run.sh OUT   (12 runs, about 20 min on 2 cores)
#   /usr/bin/python3 validation/rolling-resistance-granite-2d/compare.py OUT
set -euo pipefail
here=$(cd "$(dirname "$0")" && pwd)
breccia=${BRECCIA:-$here/../../build/breccia}
out=${1:?usage: run.sh OUT}
for seed in 1 2; do
  for mr in 0 0.3; do
    dir=$out/s${seed}_mr${mr}
    "$breccia" run "$here/ucs.toml" --set engine.seed=$seed --set contact.rolling_friction=$mr \
      --output "$dir"
    for s3 in 10e6 30e6; do
      "$breccia" run "$here/biaxial.toml" --set engine.seed=$seed \
        --set contact.rolling_friction=$mr --set test.confining_stress=$s3 --output "$dir"
    done
  done
done
