#!/bin/bash
# Itasca's SS_ParallelBonded (PFC 5, fistPkg21) entered as published (itasca-sandstone.toml):
# on three packings, a UCS with the platens at 0.005 m/s and a direct tension test with the grips
# (PFC's default thickness, a tenth of the height) at 0.0025 m/s; then the loading-rate points
# (UCS at 0.01 m/s, tension at 0.01 and 0.001 m/s) on the first packing. About 1.5-4 min a run
# on one thread of this VM. LARGE=1 adds a 15 x 15 x 30 cm prism (UCS at 0.005 and 0.01 m/s,
# tension at 0.00375 m/s, the 20 cm prism's strain rates): 3-9 min a run.
#   validation/pfc-published/itasca.sh OUT
#   /usr/bin/python3 validation/pfc-published/itasca.py OUT/*/
set -euo pipefail
here=$(cd "$(dirname "$0")" && pwd)
breccia=${BRECCIA:-$here/../../build/breccia}
out=${1:?usage: itasca.sh OUT}
run() { "$breccia" run "$here/itasca-sandstone.toml" --quiet --output "$out" "$@"; }
tension=(--set 'test.kind="direct_tension"' --set test.grip_length=0.02 --set test.max_strain=0.01
  --set test.stop_fraction=0.5)
for seed in 1 2 3; do
  run --set engine.seed=$seed --set test.platen_speed=0.005 --set "name=\"ucs-seed$seed\""
  run "${tension[@]}" --set engine.seed=$seed --set test.platen_speed=0.0025 \
    --set "name=\"tension-seed$seed\""
done
run --set test.platen_speed=0.01 --set 'name="ucs-seed1-fast"'
for v in 0.01 0.001; do
  run "${tension[@]}" --set test.platen_speed=$v --set "name=\"tension-seed1-v$v\""
done
if [ "${LARGE:-0}" = 1 ]; then
  large=(--set sample.width=0.15 --set sample.depth=0.15 --set sample.height=0.30)
  run "${large[@]}" --set 'name="ucs-15x30cm-slow"'
  run "${large[@]}" --set test.platen_speed=0.01 --set 'name="ucs-15x30cm"'
  run "${large[@]}" "${tension[@]}" --set test.grip_length=0.03 --set test.platen_speed=0.00375 \
    --set 'name="tension-15x30cm"'
fi
