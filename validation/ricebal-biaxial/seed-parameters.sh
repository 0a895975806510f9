#!/usr/bin/env bash
# Seed 000's stated RICEBAL micro-parameters (seed-parameters.toml) under the readings of the law
# the seeds leave open, one reading added at a time, at 0, 15 and 50 MPa: the peak, E_t50, the
# shear-crack share and the energy shares beside seed 002's. Run by hand (about 25 min on 2
# cores), not by CI.
#   validation/ricebal-biaxial/seed-parameters.sh [output folder]
set -euo pipefail
root="$(cd "$(dirname "${BASH_SOURCE[0]}")/../.." && pwd)"
out="${1:-/tmp/breccia-ricebal-seed-parameters}"
mkdir -p "$out"
# name: the --set overrides, cumulative from left to right
variants=(
  "as-shipped-law:"
  "tension-spring:bond.normal_spring_in_compression=false"
  "beta-0.3:bond.normal_spring_in_compression=false bond.moment_factor=0.3"
  "Gb-29GPa:bond.normal_spring_in_compression=false bond.moment_factor=0.3 bond.shear_modulus=29e9"
  "mu_b-0:bond.normal_spring_in_compression=false bond.moment_factor=0.3 bond.shear_modulus=29e9 bond.friction=0"
)
for v in "${variants[@]}"; do
  name="${v%%:*}"
  sets=()
  for s in ${v#*:}; do sets+=(--set "$s"); done
  [ -d "$out/$name" ] && continue
  "$root/build/breccia" sweep "$root/validation/ricebal-biaxial/seed-parameters.toml" \
    --confining-mpa 0 15 50 --jobs 2 "${sets[@]}" --output "$out/$name" > "$out/$name.log" 2>&1
done
names=()
for v in "${variants[@]}"; do names+=("${v%%:*}"); done
/usr/bin/python3 - "$out" "${names[@]}" <<'PY'
import glob, json, os, sys
seed = {0: (85.0, 4, "69", "16.0"), 15: (128.5, 18, "-", "5.8"), 50: (188.8, 45, "86", "3.1")}
print("| reading | sigma_3 (MPa) | peak q (MPa): Breccia | seed 002 | E_t50 (GPa) | cracks "
      "| shear (%): Breccia | seed | friction / W_ext (%) | damping / W_ext (%) | seed's friction "
      "(%) | strain energy / W_ext (%) | seed (%) |")
print("|---|---|---|---|---|---|---|---|---|---|---|---|---|")
for v in sys.argv[2:]:
    runs = [json.load(open(f)) for f in glob.glob(os.path.join(sys.argv[1], v, "*", "*", "summary.json"))]
    for s in sorted(runs, key=lambda s: s.get("confining_stress_pa") or 0):
        e = s["energy"]
        w = e["boundary_work_j"] + e.get("external_load_work_j", 0.0)  # platens + membranes
        strain = e["contact_strain_j"] + sum(e["bond_strain_j"].values())
        p = round((s.get("confining_stress_pa") or 0) / 1e6)
        q, sh, fr, se = seed[p]
        print(f"| {v} | {p} | {s['peak_deviatoric_stress_mpa']:.1f} | {q} | "
              f"{s['youngs_modulus_pa'] / 1e9:.2f} | {s['bonds_broken']} | "
              f"{100 * s['cracks_shear'] / max(1, s['bonds_broken']):.1f} | {sh} | "
              f"{100 * e['friction_j'] / w:.0f} | {100 * e['local_damping_j'] / w:.0f} | {fr} | "
              f"{100 * strain / w:.1f} | {se} |")
PY
