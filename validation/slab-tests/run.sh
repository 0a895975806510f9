#!/usr/bin/env bash
# Seed 001's slab tests with the four calibrated sandstones (brenna, mucharz, radkow, tumlin):
# one sweep over the slab thickness per rock and test. Run by hand (not CI): about 70 min on one
# core for the impact sweeps at two thicknesses. Usage: validation/slab-tests/run.sh [OUT]
# then: /usr/bin/python3 validation/slab-tests/table.py OUT
set -euo pipefail
here="$(cd "$(dirname "$0")" && pwd)"
root="$(cd "$here/../.." && pwd)"
out="${1:-$root/build/validation-slab-tests}"
breccia="${BRECCIA:-$root/build/breccia}"
mkdir -p "$out"
for rock in brenna mucharz radkow tumlin; do
  "$breccia" sweep "$root/examples/impact.toml" --set material.preset="\"$rock\"" \
    --set name="\"impact-$rock\"" --set engine.threads=1 --jobs 1 --output "$out/impact" \
    --over sample.slab_thickness 5e-3 10e-3
done
