#!/usr/bin/env bash
# Seed 003's triaxial tests at 20 and 40 MPa on its calibrated PFC sandstone (preset
# pfc_sandstone), with and without the circular smooth joint (radius 6 mm, 27 degrees from the
# axis, friction 0.2), on a 10 x 20 mm cylinder, then where the cracks and events lie
# (localisation.py); and the smaller joints of the seed's Table 3 (radii 2, 3, 4 mm) at 20 MPa in the
# membrane. Run by hand (about 10-30 min per run on 1 thread, two at a time), not by CI.
#   validation/seed-003-jointed/run.sh [output folder]
set -euo pipefail
root="$(cd "$(dirname "${BASH_SOURCE[0]}")/../.." && pwd)"
out="${1:-/tmp/breccia-seed-003}"
bin="$root/build/breccia"
example="$root/examples/triaxial-smooth-joint.toml"
dir="output.directory=\"$out\""
for s3 in 20 40; do
  conf="test.confining_stress=${s3}e6"
  OMP_NUM_THREADS=1 "$bin" run "$example" --set "$dir" --set "$conf" \
    --set "name=\"triaxial-jointed-$s3\"" &
  OMP_NUM_THREADS=1 "$bin" run "$example" --set "$dir" --set "$conf" \
    --set "name=\"triaxial-intact-$s3\"" --set 'joint.planes=[]' &
  wait
  OMP_NUM_THREADS=1 "$bin" run "$example" --set "$dir" --set "$conf" \
    --set "name=\"triaxial-jointed-$s3-frictionless-walls\"" --set contact.wall_friction=0.0
  # A flexible membrane instead of the cylindrical wall (the platens keep their friction).
  OMP_NUM_THREADS=1 "$bin" run "$example" --set "$dir" --set "$conf" --set test.membrane=true \
    --set "name=\"triaxial-jointed-$s3-membrane\"" &
  OMP_NUM_THREADS=1 "$bin" run "$example" --set "$dir" --set "$conf" --set test.membrane=true \
    --set "name=\"triaxial-intact-$s3-membrane\"" --set 'joint.planes=[]' &
  wait
done
# Table 3's smaller joints at 20 MPa, in the membrane.
for r in 2 3 4; do
  OMP_NUM_THREADS=1 "$bin" run "$example" --set "$dir" --set test.confining_stress=20e6 \
    --set test.membrane=true --set "joint.planes=[{dip_deg=63, radius=${r}e-3}]" \
    --set "name=\"triaxial-jointed-r${r}mm-20-membrane\"" &
  if [ "$r" = 3 ]; then wait; fi  # two at a time
done
wait
for f in "$out"/*/summary.json; do
  /usr/bin/python3 -c "import json,sys; s=json.load(open(sys.argv[1])); \
print(s['experiment'], round(s['peak_deviatoric_stress_mpa'], 1), 'MPa at', \
round(100*s['axial_strain_at_peak'], 2), '%,', s['bonds_broken'], 'cracks')" "$f"
done
for s3 in 20 40; do
  jointed=$(ls -d "$out"/*-triaxial-jointed-$s3 | tail -1)
  /usr/bin/python3 "$root/validation/seed-003-jointed/localisation.py" "$out"/*-triaxial-jointed-$s3*
  /usr/bin/python3 "$root/validation/seed-003-jointed/localisation.py" \
    "$out"/*-triaxial-intact-$s3 --plane-from "$jointed"
done
