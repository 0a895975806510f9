#!/usr/bin/env bash
# Seed 001's slab tests with the four calibrated sandstones (brenna, mucharz, radkow, tumlin): one
# sweep per rock and test, at the examples' settings. Run by hand (not CI). On one core each:
# impact at 5 and 10 mm about 80 min per rock, cantilever at 6 and 10 mm 30-50 min per rock,
# vibration at 5 and 10 mm about 35 and 75 min per rock, abrasion at 2, 30 and 60 MPa about 6
# min per rock. A sweep that stops (Ctrl-C, a time limit) is finished by `breccia resume FOLDER`.
# Usage: validation/slab-tests/run.sh [OUT [TEST...]]   (TEST: impact cantilever vibration abrasion)
# then:  /usr/bin/python3 validation/slab-tests/table.py OUT
set -euo pipefail
here="$(cd "$(dirname "$0")" && pwd)"
root="$(cd "$here/../.." && pwd)"
out="${1:-$root/build/validation-slab-tests}"
shift || true
tests=("${@:-impact cantilever vibration abrasion}")
breccia="${BRECCIA:-$root/build/breccia}"
mkdir -p "$out"

sweep() {  # test rock key values...
  local test=$1 rock=$2 key=$3
  shift 3
  "$breccia" sweep "$root/examples/$test.toml" --set material.preset="\"$rock\"" \
    --set name="\"$test-$rock\"" --set engine.threads=1 --jobs 1 --output "$out/$test" \
    --over "$key" "$@"
}

for test in ${tests[*]}; do
  for rock in brenna mucharz radkow tumlin; do
    case $test in
      impact) sweep impact $rock sample.slab_thickness 5e-3 10e-3 ;;
      cantilever) sweep cantilever $rock sample.slab_thickness 6e-3 10e-3 ;;
      vibration) sweep vibration $rock sample.slab_thickness 5e-3 10e-3 ;;
      abrasion) sweep abrasion $rock test.normal_stress 2e6 30e6 60e6 ;;
      *) echo "unknown test '$test': impact, cantilever, vibration or abrasion" >&2; exit 2 ;;
    esac
  done
done
