#!/usr/bin/env bash
# Seed 003's triaxial tests in the membrane on a sample of over 20,000 grains: the seed's
# cylinder (10 x 20 mm) and joint (radius 6 mm, dip 63 degrees, friction 0.2) with the grains of
# examples/triaxial-smooth-joint.toml scaled by 0.75 (0.165-0.27 mm, 21,580 grains against
# 9,106), so that the sample and the joint are the seed's and 2.4 times as many grains resolve
# them. The joint's stiffness per unit area is a property of the joint, not of the grains, and
# stays as it is. On 2 cores: 40-55 min per jointed test (two side by side, one thread each),
# 37-43 min per intact test alone on two threads.
# Runs two tests at a time, one thread each (THREADS=2: one test at a time on two threads).
#   validation/seed-003-jointed/large.sh OUTPUT_FOLDER TEST...
# where each TEST is jointed-20, jointed-40, intact-0, intact-20, intact-40 (kind and sigma_3
# in MPa). intact-0 is seed 003's unconfined row: a UCS of the same sample (unconfined.toml),
# since a triaxial test needs sigma_3 > 0. PLATEN_FRICTION=0 (or another value) replaces the
# platens' friction of 0.3 (in the membrane the platens are the only walls) and names the run
# after it.
# Then: tables.py and localisation.py on the run folders (README, "Over 20,000 grains").
set -euo pipefail
root="$(cd "$(dirname "${BASH_SOURCE[0]}")/../.." && pwd)"
out="$1"
shift
bin="${BRECCIA:-$root/build/breccia}"
example="$root/examples/triaxial-smooth-joint.toml"
threads="${THREADS:-1}"
friction="${PLATEN_FRICTION:-}"
run_one() {
  local kind="${1%-*}" s3="${1#*-}"
  local file="$example" name="triaxial-$kind-$s3-membrane-large"
  local args=(--set "output.directory=\"$out\"" --set sample.radius_min=0.165e-3
    --set sample.radius_max=0.27e-3)
  if ! [[ "$s3" =~ ^[0-9]+$ ]]; then
    echo "large.sh: test '$1': expected KIND-SIGMA3 with sigma_3 in whole MPa (jointed-20)" >&2
    return 2
  fi
  case "$kind" in
    jointed | intact) ;;
    *) echo "large.sh: test '$1': the kind must be jointed or intact" >&2; return 2 ;;
  esac
  if [ "$s3" -eq 0 ]; then
    if [ "$kind" != intact ]; then
      echo "large.sh: test '$1': seed 003 has no unconfined jointed test" >&2
      return 2
    fi
    file="$root/validation/seed-003-jointed/unconfined.toml"
    name="unconfined-intact-large"
  else
    args+=(--set "test.confining_stress=${s3}e6" --set test.membrane=true)
    if [ "$kind" = intact ]; then args+=(--set 'joint.planes=[]'); fi
  fi
  if [ -n "$friction" ]; then
    args+=(--set "contact.wall_friction=$friction")
    name="$name-platen-friction-$friction"
  fi
  OMP_NUM_THREADS="$threads" "$bin" run "$file" --quiet "${args[@]}" --set "name=\"$name\""
}
while [ $# -gt 0 ]; do
  if [ "$threads" = 1 ] && [ $# -gt 1 ]; then
    run_one "$1" &
    first=$!
    run_one "$2" &
    wait "$first"  # each wait fails the script if its test failed
    wait $!
    shift 2
  else
    run_one "$1"
    shift
  fi
done
