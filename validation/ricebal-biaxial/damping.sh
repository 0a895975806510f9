#!/usr/bin/env bash
# Does the local damping take what seed 002 books as friction? Seed 000's stated parameters in
# their mu_b-0 reading (seed-parameters.sh) with the local damping of 0.7 at eight confinements
# (where the damage index changes sign), then at 0, 15 and 50 MPa with dynamic damping added and
# with the local damping lowered to 0.1 and 0.02 at the seed-parameters loading (10 /s), and at
# 0.1 with the platens ten times slower (0 and 50 MPa), or adaptive between that and the usual
# speed (the loading slows wherever the sample is not quasi-static; 0 and 5 MPa to 5 % strain,
# and 0.7 the same way at 0 MPa beside it).
# Prints the peak, the damage index, the quasi-static checks and the work budget, the membranes'
# work included. Run by hand: 26 min on 2 cores for the first two variants (measured), about 15
# more for 0.1 and 0.02 and 25 more for the slow variant; the two adaptive variants about 25 min
# (measured: 8-15 min of running a test).
#   validation/ricebal-biaxial/damping.sh [output folder] [variant names: all when none]
set -euo pipefail
root="$(cd "$(dirname "${BASH_SOURCE[0]}")/../.." && pwd)"
out="${1:-/tmp/breccia-ricebal-damping}"
shift $(( $# > 0 ? 1 : 0 ))
only=" $* "
mkdir -p "$out"
reading=(--set bond.normal_spring_in_compression=false --set bond.moment_factor=0.3
  --set bond.shear_modulus=29e9 --set bond.friction=0)
# name:confining stresses:the --set overrides
variants=(
  "alpha-0.7:0 2 5 10 15 20 30 50:engine.local_damping=0.7"
  "alpha-0.7-dynamic:0 15 50:engine.local_damping=0.7 engine.dynamic_damping=true"
  "alpha-0.1:0 15 50:engine.local_damping=0.1"
  "alpha-0.02:0 15 50:engine.local_damping=0.02"
  "alpha-0.1-slow:0 50:engine.local_damping=0.1 test.platen_speed=0.0015"
  "alpha-0.1-adaptive:0 5:engine.local_damping=0.1 test.platen_speed=0.0015 test.adaptive_speed_ratio=10 test.max_strain=0.05"
  "alpha-0.7-adaptive:0:engine.local_damping=0.7 test.platen_speed=0.0015 test.adaptive_speed_ratio=10 test.max_strain=0.05"
)
for v in "${variants[@]}"; do
  IFS=: read -r name pcs overrides <<<"$v"
  [ "$only" != "  " ] && [[ "$only" != *" $name "* ]] && continue
  [ -d "$out/$name" ] && continue
  sets=()
  for s in $overrides; do sets+=(--set "$s"); done
  # shellcheck disable=SC2086
  "$root/build/breccia" sweep "$root/validation/ricebal-biaxial/seed-parameters.toml" \
    --confining-mpa $pcs --jobs 2 "${reading[@]}" "${sets[@]}" --output "$out/$name" \
    > "$out/$name.log" 2>&1
done
names=()
for v in "${variants[@]}"; do [ -d "$out/${v%%:*}" ] && names+=("${v%%:*}"); done
/usr/bin/python3 "$root/validation/ricebal-biaxial/budget.py" "$out" "${names[@]}"
