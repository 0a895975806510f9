#!/usr/bin/env bash
# Isolates candidate causes of the shear-crack share against confinement in the RICEBAL envelope:
# the default; the bond's own loads instead of the interface totals (bond.interface_totals =
# false); and the tensile check without the bending term (bond.moment_factor = 0). The
# small Berea sample at 0, 15 and 50 MPa each way, then the shear share, the strength and the
# energy shares side by side. Run by hand (about 15 min on 2 cores), not by CI.
#   validation/ricebal-biaxial/envelope.sh [output folder]
set -euo pipefail
root="$(cd "$(dirname "${BASH_SOURCE[0]}")/../.." && pwd)"
out="${1:-/tmp/breccia-ricebal-envelope}"
mkdir -p "$out"
for v in default bond.interface_totals=false bond.moment_factor=0; do
  set_variant=()
  [ "$v" = default ] || set_variant=(--set "$v")
  "$root/build/breccia" sweep "$root/validation/ricebal-biaxial/berea-2d-small.toml" \
    --confining-mpa 0 15 50 --jobs 2 "${set_variant[@]}" --set output.plot=false \
    --set output.snapshot_strain_interval=0 --output "$out/$v" > "$out/$v.log" 2>&1
done
/usr/bin/python3 - "$out" <<'PY'
import glob, json, os, sys
print("| variant | sigma_3 (MPa) | peak q (MPa) | cracks | shear (%) | friction / W_ext (%) | damping / W_ext (%) | strain energy / W_ext (%) |")
print("|---|---|---|---|---|---|---|---|")
for v in ("default", "bond.interface_totals=false", "bond.moment_factor=0"):
    for f in sorted(glob.glob(os.path.join(sys.argv[1], v, "*", "*", "summary.json")),
                    key=lambda p: json.load(open(p)).get("confining_stress_pa") or 0):
        s = json.load(open(f))
        e = s["energy"]
        w = e["boundary_work_j"] + e.get("external_load_work_j", 0.0)  # platens + membranes
        strain = e["contact_strain_j"] + sum(e["bond_strain_j"].values())
        print(f"| {v} | {(s.get('confining_stress_pa') or 0) / 1e6:.0f} | "
              f"{s['peak_deviatoric_stress_mpa']:.1f} | {s['bonds_broken']} | "
              f"{100 * s['cracks_shear'] / max(1, s['bonds_broken']):.1f} | "
              f"{100 * e['friction_j'] / w:.0f} | {100 * e['local_damping_j'] / w:.0f} | "
              f"{100 * strain / w:.1f} |")
PY
