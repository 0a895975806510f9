#!/usr/bin/env bash
# Constant-speed against adaptive loading (docs/physics.md §6.1) on the cases whose results must
# not change: the default UCS (5,940 grains), the 3,444-disk biaxial test at 15 MPa to 10.3 %
# strain (examples/biaxial-berea-2d.toml) with an isolating run at four times the constant speed,
# and seed 001's Tumlin quarter-size cylinder (18,041 grains). Run by hand (not CI). On the 2-core
# machine: ucs about 4 min, biaxial about 30 min (the runs two at a time), tumlin about 40 min.
# Usage: validation/adaptive-loading/run.sh OUT [ucs] [biaxial] [tumlin]
# then the tables are printed by compare.py (README.md has them).
set -euo pipefail
here="$(cd "$(dirname "$0")" && pwd)"
root="$(cd "$here/../.." && pwd)"
out="${1:?usage: run.sh OUT [ucs] [biaxial] [tumlin]}"
shift
cases=("${@:-ucs biaxial tumlin}")
breccia="${BRECCIA:-$root/build/breccia}"
mkdir -p "$out"
folder() { dirname "$(ls "$1"/*/summary.json | tail -1)"; }  # the run folder under an output

for c in ${cases[*]}; do
  case $c in
    ucs)
      for r in 1 8; do
        "$breccia" run --quiet --set test.adaptive_speed_ratio=$r --output "$out/ucs-$r" >/dev/null
      done
      /usr/bin/python3 "$here/compare.py" "constant=$(folder "$out/ucs-1")" \
        "adaptive=$(folder "$out/ucs-8")"
      ;;
    biaxial)
      ex="$root/examples/biaxial-berea-2d.toml"
      "$breccia" run "$ex" --quiet --threads 1 --output "$out/biaxial-1" >/dev/null &
      "$breccia" run "$ex" --quiet --threads 1 --set test.adaptive_speed_ratio=8 \
        --output "$out/biaxial-8" >/dev/null &
      wait
      "$breccia" run "$ex" --quiet --threads 1 --set test.platen_speed=0.12 \
        --output "$out/biaxial-4x" >/dev/null
      /usr/bin/python3 "$here/compare.py" "constant=$(folder "$out/biaxial-1")" \
        "adaptive=$(folder "$out/biaxial-8")" "4x constant=$(folder "$out/biaxial-4x")"
      ;;
    tumlin)
      export BRECCIA="$breccia" THREADS=1
      (cd "$root" && validation/tumlin-full-size/run.sh pack 0.25 >/dev/null)
      (cd "$root" && validation/tumlin-full-size/run.sh run 0.25 calibrated --quiet >/dev/null) &
      (cd "$root" && validation/tumlin-full-size/run.sh run 0.25 adaptive --quiet >/dev/null) &
      wait
      /usr/bin/python3 "$here/compare.py" \
        "constant=$(folder "$root/runs/tumlin/0.25-calibrated")" \
        "adaptive=$(folder "$root/runs/tumlin/0.25-adaptive")"
      ;;
    *) echo "unknown case '$c': ucs, biaxial or tumlin" >&2; exit 2 ;;
  esac
done
