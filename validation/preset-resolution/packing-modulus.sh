#!/usr/bin/env bash
# E_t50 of the 2D Berea biaxial test (examples/biaxial-berea-2d.toml, 15 MPa) at the 60k-disk
# benchmark's inertia (platens 0.03 m/s, density scaling 12,500: v sqrt(s) = 3.35 m/s) on samples
# that change one thing at a time: the compaction (rows, homogeneous), the grains (20-60 or
# 24-72 um) and the size (3.8 x 6 or 7.6 x 12 mm). README, "The 60k-disk modulus". Run by hand,
# not by CI: about 25 min on one core, most of it the 7.6 mm sample.
#   validation/preset-resolution/packing-modulus.sh OUT
set -euo pipefail
root="$(cd "$(dirname "${BASH_SOURCE[0]}")/../.." && pwd)"
out="${1:?usage: packing-modulus.sh OUT}"
bin="${BRECCIA:-$root/build/breccia}"
example="$root/examples/biaxial-berea-2d.toml"
mkdir -p "$out"

case_run() {  # name, then --set overrides of the sample
  local name=$1
  shift
  "$bin" generate "$example" "$@" --output "$out/$name.geom" > "$out/$name-generate.log" 2>&1
  "$bin" run "$example" "$@" --set sample.source=\"file\" --set "sample.file=\"$out/$name.geom\"" \
    --set engine.density_scaling=12500 --set engine.threads=1 \
    --set "output.directory=\"$out\"" --set "name=\"$name\"" --quiet
}

grains=(--set sample.radius_min=24e-6 --set sample.radius_max=72e-6)
homogeneous=(--set sample.compaction=\"homogeneous\")
case_run rows-20-60
case_run hom-20-60 "${homogeneous[@]}"
case_run rows-24-72 "${grains[@]}"
case_run hom-24-72 "${homogeneous[@]}" "${grains[@]}"
case_run hom-24-72-w76 "${homogeneous[@]}" "${grains[@]}" --set sample.width=0.0076 \
  --set sample.height=0.012
for f in "$out"/*/summary.json; do
  /usr/bin/python3 -c "import json,sys; s=json.load(open(sys.argv[1])); \
print(s['experiment'], s['particles'], 'disks: E_t50', round(s['youngs_modulus_pa']/1e9, 2), \
'GPa, peak q', round(s['peak_deviatoric_stress_pa']/1e6, 1), 'MPa')" "$f"
done
grep -h "porosity" "$out"/*-generate.log
