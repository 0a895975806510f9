"""Mohr-Coulomb envelopes of run.sh's tests: a least-squares line sigma_1 = C0 + N sigma_3 per
packing and rolling friction, phi = asin((N - 1) / (N + 1)), C = C0 / (2 sqrt(N))."""
import glob
import json
import math
import sys

import numpy as np

out = sys.argv[1]
points = {}
for f in sorted(glob.glob(f"{out}/*/*/summary.json")):
    d = json.load(open(f))
    case = f.split("/")[-3]
    s3 = d.get("confining_stress_pa", 0.0) / 1e6
    shear = d["cracks_shear"] / max(1, d["cracks_shear"] + d["cracks_tensile"])
    points.setdefault(case, []).append((s3, d["sigma1_at_peak_pa"] / 1e6, shear))
print("| packing | mu_r | sigma_1 at 0 / 10 / 30 MPa | shear cracks | phi | C |")
print("|---|---|---|---|---|---|")
for case in sorted(points):
    p = sorted(points[case])
    x = np.array([a for a, _, _ in p])
    y = np.array([b for _, b, _ in p])
    n, c0 = np.polyfit(x, y, 1)
    phi = math.degrees(math.asin((n - 1) / (n + 1)))
    seed, mr = case[1:].split("_mr")
    print(f"| {seed} | {mr} | {' / '.join(f'{b:.1f}' for _, b, _ in p)} MPa | "
          f"{min(s for *_, s in p) * 100:.0f}-{max(s for *_, s in p) * 100:.0f} % | "
          f"{phi:.1f} deg | {c0 / (2 * math.sqrt(n)):.1f} MPa |")
