#!/bin/bash
# Seed 001's full-size UCS of its four sandstones and geometrically similar smaller cylinders (run
# by hand, not by CI; README.md has the figures). Each step can be run alone:
#
#   validation/tumlin-full-size/run.sh pack  SCALE        # pack and bond the cylinder (SCALE = 1: 75 mm tall)
#   validation/tumlin-full-size/run.sh run   SCALE LOADING [--stop-at-step N]
#   validation/tumlin-full-size/run.sh resume RUN_FOLDER  [--stop-at-step N]
#   validation/tumlin-full-size/run.sh table LABEL=RUN_FOLDER[,TIME_LOG] ...
#
# SCALE shrinks the cylinder (0.25: 9.4 x 18.75 mm, about 18,000 grains; 0.5: 145,000; 1: the
# seed's 1.16 million) with the same grains, so the steps a loading needs grow with SCALE.
# LOADING is "calibrated" (the preset's: platens at a constant 0.03 m/s, safety factor 0.3), "fast"
# (0.24 m/s until 0.1 % of the bonds have broken, then 0.06 m/s; safety factor 0.6) or "adaptive"
# (the calibration's, with adaptive loading up to 8 times its speed: docs/physics.md §6.1).
# ROCK (default tumlin; brenna, mucharz, radkow) picks the preset and the grains: each rock's
# grains are the calibration's 0.22-0.36 mm scaled so that the full cylinder holds the seed's
# count for that rock (Table 2: Brenna 82,266, Mucharz 339,324, Radków 150,653, Tumlin 1,155,851).
# Output goes to runs/ROCK/ (samples, run folders, and `/usr/bin/time -v` logs beside them).
# BRECCIA (default build-bench/breccia, a native build: cmake -S . -B build-bench -G Ninja
# -DCMAKE_BUILD_TYPE=Release -DBRECCIA_NATIVE=ON -DBRECCIA_BUILD_TESTS=OFF) and THREADS
# (default 2) can be set in the environment.
set -euo pipefail
cd "$(dirname "$0")/../.."
BRECCIA=${BRECCIA:-build-bench/breccia}
THREADS=${THREADS:-2}
EXPERIMENT=validation/tumlin-full-size/tumlin-full-size.toml
ROCK=${ROCK:-tumlin}
case "$ROCK" in  # checked here: an exit inside $(rock) below would leave only its subshell
  tumlin | brenna | mucharz | radkow) ;;
  *) echo "ROCK must be tumlin, brenna, mucharz or radkow, not '$ROCK'" >&2; exit 2 ;;
esac
OUT=runs/$ROCK
mkdir -p "$OUT"

# The preset and the grain scale factor on the calibration's 0.22-0.36 mm radii: Tumlin's 0.746
# (the experiment file's) gives 1,160,160 grains in the full cylinder, and the count goes as the
# factor's inverse cube.
rock() {
  local seed_grains
  case "$ROCK" in
    tumlin) return ;;  # the experiment file's own grains (0.164-0.269 mm)
    brenna) seed_grains=82266 ;;
    mucharz) seed_grains=339324 ;;
    radkow) seed_grains=150653 ;;
  esac
  python3 -c "import sys; f = 0.746 * (1160160 / int(sys.argv[2])) ** (1 / 3)
print(f'--set material.preset={sys.argv[1]} --set name={sys.argv[1]}-full-size '
      f'--set sample.radius_min={0.22e-3 * f:.4g} --set sample.radius_max={0.36e-3 * f:.4g} '
      f'--set sample.bond_gap_tolerance={5e-6 * f:.4g}')" "$ROCK" "$seed_grains"
}

timed() {  # /usr/bin/time -v -o FILE COMMAND..., or the bare command where GNU time is missing
  local log=$1
  shift
  if [ -x /usr/bin/time ]; then /usr/bin/time -v -o "$log" "$@"; else "$@"; fi
}

geometry() {  # the cylinder's size at a scale
  python3 -c "import sys; s = float(sys.argv[1]); print(f'--set sample.diameter={0.0375 * s:.6g} --set sample.height={0.075 * s:.6g}')" "$1"
}

loading() {
  case "$1" in
    calibrated) echo "--set test.platen_speed=0.03 --set engine.safety_factor=0.3 --set test.adaptive_speed_ratio=1" ;;
    fast) echo "--set test.platen_speed=0.06 --set test.elastic_speed=0.24 --set test.slow_down_broken_fraction=1e-3 --set engine.safety_factor=0.6" ;;
    adaptive) echo "--set test.platen_speed=0.03 --set engine.safety_factor=0.3 --set test.adaptive_speed_ratio=8" ;;
    *) echo "LOADING must be calibrated, fast or adaptive, not '$1'" >&2; exit 2 ;;
  esac
}

case "${1:-}" in
  pack)
    scale=$2
    # shellcheck disable=SC2046
    timed "$OUT/pack-$scale.time" "$BRECCIA" generate "$EXPERIMENT" \
      $(rock) $(geometry "$scale") --set engine.threads="$THREADS" --output "$OUT/cylinder-$scale.geom"
    ;;
  run)
    scale=$2 load=$3
    shift 3
    loading "$load" > /dev/null || exit 2
    [ -f "$OUT/cylinder-$scale.geom" ] || { echo "pack the sample first: $0 pack $scale" >&2; exit 2; }
    # shellcheck disable=SC2046
    timed "$OUT/run-$scale-$load.time" "$BRECCIA" run "$EXPERIMENT" --threads "$THREADS" \
      $(rock) $(geometry "$scale") $(loading "$load") --set sample.source=file \
      --set sample.file="$PWD/$OUT/cylinder-$scale.geom" --set output.directory="$OUT/$scale-$load" "$@"
    ;;
  resume)
    folder=$2
    shift 2
    timed "$folder.resume-$(date +%s).time" "$BRECCIA" resume "$folder" --threads "$THREADS" "$@"
    ;;
  table)
    shift
    /usr/bin/python3 validation/tumlin-full-size/table.py "$@"
    ;;
  *)
    sed -n '2,22p' "$0"
    exit 2
    ;;
esac
