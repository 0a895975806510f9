#!/usr/bin/env bash
# Seed 001's slab tests with the four calibrated sandstones (brenna, mucharz, radkow, tumlin): one
# sweep per rock and test, at the examples' settings. Run by hand (not CI). On one core each:
# impact at 5 and 10 mm about 80 min per rock, cantilever at 6 and 10 mm 30-50 min per rock,
# vibration at 5 and 10 mm about 35 and 75 min per rock, abrasion at 2, 30 and 60 MPa about 6
# min per rock. A sweep that stops (Ctrl-C, a time limit) is finished by `breccia resume FOLDER`.
# Usage: validation/slab-tests/run.sh [OUT [TEST...]]   (TEST: impact cantilever vibration abrasion)
# GRAINS=seed gives each rock the grain size of seed 001's own model of it: the presets' 0.22-0.36
# mm radii (and bonding gap) scaled so that the seed's cylinder would hold the seed's grain count
# (validation/tumlin-full-size: Brenna x 1.802, Radkow x 1.473, Mucharz x 1.123, Tumlin x 0.746);
# a preset's E and UCS carry over to a packing scaled as a whole. Tumlin's runs then take about
# 3.2 times as long (2.4 times the grains, a time step 0.746 times as long), Brenna's a tenth.
# ROCKS="tumlin radkow" runs only those rocks; THICKNESSES="6e-3" only those slab thicknesses
# (impact, cantilever, vibration) instead of the two each test's sweep has by default.
# then:  /usr/bin/python3 validation/slab-tests/table.py OUT
set -euo pipefail
here="$(cd "$(dirname "$0")" && pwd)"
root="$(cd "$here/../.." && pwd)"
out="${1:-$root/build/validation-slab-tests}"
shift || true
tests=("${@:-impact cantilever vibration abrasion}")
breccia="${BRECCIA:-$root/build/breccia}"
case "${GRAINS:-preset}" in preset | seed) ;; *)
  echo "GRAINS=$GRAINS: expected \"seed\" (each rock's own grain size) or \"preset\" (one size, the default)" >&2
  exit 2 ;;
esac
mkdir -p "$out"

grain_scale() {  # rock: the factor on the presets' radii under GRAINS=seed, else 1
  [ "${GRAINS:-preset}" = seed ] || { echo 1; return; }
  case $1 in brenna) echo 1.802 ;; radkow) echo 1.473 ;; mucharz) echo 1.123 ;; tumlin) echo 0.746 ;; esac
}

sweep() {  # test rock key values...
  local test=$1 rock=$2 key=$3 f grains=()
  shift 3
  f=$(grain_scale "$rock")
  [ "$f" = 1 ] || grains=(--set "sample.radius_min=$(/usr/bin/python3 -c "print(0.22e-3 * $f)")"
    --set "sample.radius_max=$(/usr/bin/python3 -c "print(0.36e-3 * $f)")"
    --set "sample.bond_gap_tolerance=$(/usr/bin/python3 -c "print(5e-6 * $f)")")
  "$breccia" sweep "$root/examples/$test.toml" --set material.preset="\"$rock\"" \
    --set name="\"$test-$rock\"" --set engine.threads=1 --jobs 1 --output "$out/$test" \
    "${grains[@]}" --over "$key" "$@"
}

rocks=(${ROCKS:-brenna mucharz radkow tumlin})
for rock in "${rocks[@]}"; do
  case $rock in brenna | mucharz | radkow | tumlin) ;; *)
    echo "ROCKS: unknown rock '$rock'; expected brenna, mucharz, radkow or tumlin" >&2
    exit 2 ;;
  esac
done
thicknesses() {  # the test's default thicknesses, or THICKNESSES
  if [ -n "${THICKNESSES:-}" ]; then echo "$THICKNESSES"; else echo "$@"; fi
}

for test in ${tests[*]}; do
  for rock in "${rocks[@]}"; do
    case $test in
      impact) sweep impact $rock sample.slab_thickness $(thicknesses 5e-3 10e-3) ;;
      cantilever) sweep cantilever $rock sample.slab_thickness $(thicknesses 6e-3 10e-3) ;;
      vibration) sweep vibration $rock sample.slab_thickness $(thicknesses 5e-3 10e-3) ;;
      abrasion) sweep abrasion $rock test.normal_stress 2e6 30e6 60e6 ;;
      *) echo "unknown test '$test': impact, cantilever, vibration or abrasion" >&2; exit 2 ;;
    esac
  done
done
