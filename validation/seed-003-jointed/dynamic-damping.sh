#!/usr/bin/env bash
# Seed 003's unconfined test (unconfined.toml, 9,106 grains) with and without dynamic damping
# (docs/physics.md §2.3), the damping scheme the seed names: local damping 0.7 throughout, and 0
# for the grains within r_d of each fresh crack for a window T_d after it.
#   validation/seed-003-jointed/dynamic-damping.sh OUT [RUN...]
#   /usr/bin/python3 validation/seed-003-jointed/tables.py OUT/*ucs*
# where each RUN is `local` (no dynamic damping), `dynamic` (the defaults: r_d the largest grain
# diameter, T_d = 2 r_d / v_S), or RADIUS:TIME in metres and seconds (the README's scan, whose
# windows 4 r_d / v_S are given in seconds). Two runs at a time, one thread each: 7-9 min per run
# on 2 cores (AMD EPYC). LARGE=1 runs them on large.sh's 21,580 grains (0.165-0.27 mm), one at a
# time on two threads, 16-17 min each.
set -euo pipefail
root="$(cd "$(dirname "${BASH_SOURCE[0]}")/../.." && pwd)"
out="$1"
shift
runs=("$@")
[ ${#runs[@]} -gt 0 ] || runs=(local dynamic)
bin="${BRECCIA:-$root/build/breccia}"
threads=1
size=()
suffix=""
if [ -n "${LARGE:-}" ]; then
  threads=2
  size=(--set sample.radius_min=0.165e-3 --set sample.radius_max=0.27e-3)
  suffix="-large"
fi
run_one() {
  local args=() name="ucs-$1"
  case "$1" in
    local) ;;
    dynamic) args=(--set engine.dynamic_damping=true) ;;
    *:*)
      args=(--set engine.dynamic_damping=true --set "engine.dynamic_damping_radius=${1%%:*}"
        --set "engine.dynamic_damping_time=${1#*:}")
      name="ucs-dynamic-r${1%%:*}-t${1#*:}"
      ;;
    *)
      echo "dynamic-damping.sh: run '$1': expected local, dynamic or RADIUS:TIME" >&2
      return 2
      ;;
  esac
  OMP_NUM_THREADS="$threads" "$bin" run "$root/validation/seed-003-jointed/unconfined.toml" \
    --quiet --set "output.directory=\"$out\"" --set "name=\"$name$suffix\"" "${size[@]}" \
    "${args[@]}"
}
set -- "${runs[@]}"
while [ $# -gt 0 ]; do
  if [ "$threads" = 1 ] && [ $# -gt 1 ]; then
    run_one "$1" &
    first=$!
    run_one "$2" &
    wait "$first"
    wait $!
    shift 2
  else
    run_one "$1"
    shift
  fi
done
