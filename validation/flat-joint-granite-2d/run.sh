#!/bin/bash
# Friction angle of a 2D flat-joint granite against the bonded elements' friction angle phi_b and
# their strengths: UCS and membrane biaxial tests at 10 and 30 MPa per case, one thread per run.
#   validation/flat-joint-granite-2d/run.sh OUT   (24 runs, about 3 h of one core; two cases
#                                                  can run side by side on 2 cores)
#   /usr/bin/python3 validation/flat-joint-granite-2d/compare.py OUT
set -euo pipefail
here=$(cd "$(dirname "$0")" && pwd)
breccia=${BRECCIA:-$here/../../build/breccia}
out=${1:?usage: run.sh OUT}
run_case() {  # name, then --set overrides
  local name=$1
  shift
  "$breccia" run "$here/granite-fj-2d.toml" "$@" --output "$out/$name"
  for s3 in 10e6 30e6; do
    "$breccia" run "$here/granite-fj-2d.toml" --set test.kind=biaxial \
      --set test.confining_stress=$s3 "$@" --output "$out/$name"
  done
}
run_case s1_phib40
run_case s1_phib40_strong --set bond.tensile_strength=60e6 --set bond.cohesion=240e6
run_case s1_phib15 --set bond.friction_angle_deg=15
run_case s2_phib15 --set bond.friction_angle_deg=15 --set engine.seed=2
run_case s1_phib0 --set bond.friction_angle_deg=0
run_case s2_phib0 --set bond.friction_angle_deg=0 --set engine.seed=2
run_case s1_phib0_2seg --set bond.friction_angle_deg=0 --set bond.radial_elements=2
run_case s1_phib15_mu03 --set bond.friction_angle_deg=15 --set bond.friction=0.3 \
  --set contact.friction=0.3
