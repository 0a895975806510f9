#!/usr/bin/env bash
# Seed 003's triaxial tests at 20 MPa on its calibrated PFC sandstone (preset pfc_sandstone), with
# and without the circular smooth joint (radius 6 mm, 27 degrees from the axis, friction 0.2), on
# a 10 x 20 mm cylinder. Run by hand (about 15-25 min per run on 1 thread), not by CI.
#   validation/seed-003-jointed/run.sh [output folder]
set -euo pipefail
root="$(cd "$(dirname "${BASH_SOURCE[0]}")/../.." && pwd)"
out="${1:-/tmp/breccia-seed-003}"
bin="$root/build/breccia"
example="$root/examples/triaxial-smooth-joint.toml"
dir="output.directory=\"$out\""
OMP_NUM_THREADS=1 "$bin" run "$example" --set "$dir" &
OMP_NUM_THREADS=1 "$bin" run "$example" --set "$dir" --set 'name="triaxial-intact"' \
  --set 'joint.planes=[]' &
wait
OMP_NUM_THREADS=1 "$bin" run "$example" --set "$dir" \
  --set 'name="triaxial-jointed-frictionless-walls"' --set contact.wall_friction=0.0
for f in "$out"/*/summary.json; do
  /usr/bin/python3 -c "import json,sys; s=json.load(open(sys.argv[1])); \
print(s['experiment'], round(s['peak_deviatoric_stress_mpa'], 1), 'MPa at', \
round(100*s['axial_strain_at_peak'], 2), '%,', s['bonds_broken'], 'cracks')" "$f"
done
