"""Seed 003's published macro-properties beside run.sh's two UCS runs."""
import glob
import json
import sys

PUBLISHED = {"E": 14.5, "nu": 0.30, "UCS": 105.0}  # seed 003 Table 2 (PFC3D)
print("| contact stiffness | E_t50 | E secant 50 % | nu | UCS |")
print("|---|---|---|---|---|")
print(f"| PFC3D, published | {PUBLISHED['E']} GPa | | {PUBLISHED['nu']} | {PUBLISHED['UCS']} MPa |")
for f in sorted(glob.glob(f"{sys.argv[1]}/ball_stiffness_*/*/summary.json")):
    d = json.load(open(f))
    e = d["youngs_modulus_pa"] / 1e9
    es = d["youngs_modulus_secant50_pa"] / 1e9
    label = "ball 4 R E_c in series" if f.split("/")[-3].endswith("true") else "deformability"
    print(f"| {label} | {e:.2f} GPa ({e / PUBLISHED['E']:.2f}) | {es:.2f} GPa | "
          f"{d['poisson_ratio']:.3f} | {d['peak_deviatoric_stress_mpa']:.1f} MPa |")
