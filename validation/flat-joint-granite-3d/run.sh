#!/usr/bin/env bash
# What moves the 3D flat-joint granite's Poisson's ratio and UCS/TS: `lac_du_bonnet_fj` on the 4 mm
# prism of its resolution table (ucs.toml), one lever at a time, each a UCS test and, where the
# ratio matters, a Brazilian disc 8 mm across and 4 mm thick (the calibration's disc, at its
# platen speed of 0.02 m/s). Run by hand, not by CI: 15 runs of 1-3 min on 1 thread, one after
# another, then the table of README.md.
#   validation/flat-joint-granite-3d/run.sh [output folder]
set -euo pipefail
root="$(cd "$(dirname "${BASH_SOURCE[0]}")/../.." && pwd)"
out="${1:-/tmp/breccia-fj3d}"
bin="$root/build/breccia"
ucs="$root/validation/flat-joint-granite-3d/ucs.toml"
disc=(--set 'test.kind="brazilian"' --set test.platen_speed=0.02 --set 'sample.shape="cylinder"'
  --set sample.diameter=8e-3 --set sample.height=4e-3)
run() {
  local name=$1
  shift
  "$bin" run "$ucs" --quiet --threads 1 --output "$out" --set "name=\"$name\"" "$@"
}
both() {  # a UCS test and a Brazilian disc with the same lever
  local lever=$1
  shift
  run "ucs-$lever" "$@"
  run "disc-$lever" "$@" "${disc[@]}"
}
# The preset: kappa* 1.2, sigma_b 18.9 MPa, c_b 391 MPa (c_b / sigma_b = 20.7), one ring of three.
both preset
run ucs-strengths-x2 --set bond.tensile_strength=37.78e6 --set bond.cohesion=782.3e6
run ucs-kappa-2.5 --set bond.stiffness_ratio=2.5
run ucs-elements-1x6 --set bond.circumferential_elements=6
run ucs-elements-2x4 --set bond.radial_elements=2 --set bond.circumferential_elements=4
run ucs-gapped-0.3 --set bond.bonded_fraction=0.7 --set bond.gapped_fraction=0.3 \
  --set bond.installation_gap=2e-6
# The cohesion over the tensile strength, with kappa* lowered to keep E.
both cohesion-10 --set bond.cohesion=188.9e6
both kappa-1.6-cohesion-10 --set bond.stiffness_ratio=1.6 --set bond.cohesion=188.9e6
both kappa-1.5-cohesion-14 --set bond.stiffness_ratio=1.5 --set bond.cohesion=264.5e6
both kappa-1.35-cohesion-14 --set bond.stiffness_ratio=1.35 --set bond.cohesion=264.5e6
/usr/bin/python3 "$root/validation/flat-joint-granite-3d/table.py" "$out"
