#!/usr/bin/env bash
# Is the 60k-disk sample's stiffness its size or its packing? The 15 MPa biaxial test of the 2D
# Berea preset (examples/biaxial-berea-2d.toml) at the 60k benchmark's inertia (v sqrt(s) =
# 3.35 m/s) on: the benchmark's own sample (bench/biaxial-60k.toml, 59,817 disks), windows of
# 3.8 x 6 and 7.6 x 12 mm cut from its middle (crop.py: its grains and bonds, so its porosity and
# bonds per grain), and samples of those sizes packed on their own the same way. Every run stops
# once q has fallen to 0.7 of its peak. README, "The 60k-disk modulus". Run by hand, not by CI:
# about 45 min on 2 cores (the 60k run alone 31 min of it). Prints the samples' porosity and
# bonds per grain (crop.py --describe) and each run's moduli and cracks (window_moduli.py).
#   validation/preset-resolution/packing-window.sh OUT
set -euo pipefail
root="$(cd "$(dirname "${BASH_SOURCE[0]}")/../.." && pwd)"
out="${1:?usage: packing-window.sh OUT}"
bin="${BRECCIA:-$root/build/breccia}"
py=/usr/bin/python3
example="$root/examples/biaxial-berea-2d.toml"
mkdir -p "$out"

own=(--set sample.compaction=\"homogeneous\" --set sample.radius_min=24e-6
  --set sample.radius_max=72e-6)
[ -f "$out/sample-60k.geom" ] ||
  "$bin" generate "$root/bench/biaxial-60k.toml" --output "$out/sample-60k.geom" > "$out/gen-60k.log" 2>&1
"$py" "$root/validation/preset-resolution/crop.py" "$out/sample-60k.geom" "$out/cut-38.geom" 0.0038 0.006
"$py" "$root/validation/preset-resolution/crop.py" "$out/sample-60k.geom" "$out/cut-76.geom" 0.0076 0.012
[ -f "$out/own-38.geom" ] || "$bin" generate "$example" "${own[@]}" --output "$out/own-38.geom" > "$out/gen-own-38.log" 2>&1
[ -f "$out/own-76.geom" ] || "$bin" generate "$example" "${own[@]}" --set sample.width=0.0076 \
  --set sample.height=0.012 --output "$out/own-76.geom" > "$out/gen-own-76.log" 2>&1

run() {  # name, then --set overrides; platens at 0.03 m/s with density scaling 12,500
  local name=$1
  shift
  [ -f "$out/$name.done" ] && return
  "$bin" run "$example" --set sample.source=\"file\" --set "sample.file=\"$out/$name.geom\"" \
    --set engine.density_scaling=12500 --set engine.threads=1 --set test.stop_fraction=0.7 \
    --set "output.directory=\"$out/runs\"" --set "name=\"$name\"" --quiet "$@" > "$out/$name.log" 2>&1
  touch "$out/$name.done"
}
run cut-38 & run own-38 & wait
run cut-76 & run own-76 & wait
# The benchmark's own loading: platens 0.15 m/s, density scaling 500 (the same v sqrt(s)).
[ -f "$out/full-60k.done" ] || { "$bin" run "$root/bench/biaxial-60k.toml" --set sample.source=\"file\" \
  --set "sample.file=\"$out/sample-60k.geom\"" --set engine.threads=2 --set test.stop_fraction=0.7 \
  --set "output.directory=\"$out/runs\"" --set "name=\"full-60k\"" --quiet > "$out/full-60k.log" 2>&1 &&
  touch "$out/full-60k.done"; }
"$py" "$root/validation/preset-resolution/crop.py" --describe "$out"/sample-60k.geom "$out"/cut-*.geom "$out"/own-*.geom
"$py" "$root/validation/preset-resolution/window_moduli.py" "$out"/runs/*/
