"""Mohr-Coulomb envelopes of run.sh's tests: a least-squares line sigma_1 = C0 + N sigma_3 per
case over the confining stresses it has, phi = asin((N - 1) / (N + 1)), C = C0 / (2 sqrt(N));
the angle from the UCS and the 10 MPa test alone beside it (what a two-point calibration reads)."""
import glob
import json
import math
import sys

import numpy as np


def angle(n):
    return math.degrees(math.asin((n - 1) / (n + 1)))


out = sys.argv[1]
points = {}
for f in sorted(glob.glob(f"{out}/*/*/summary.json")):
    d = json.load(open(f))
    case = f.split("/")[-3]
    s3 = d.get("confining_stress_pa", 0.0) / 1e6
    shear = d["cracks_shear"] / max(1, d["cracks_shear"] + d["cracks_tensile"])
    points.setdefault(case, []).append(
        (s3, d["sigma1_at_peak_pa"] / 1e6, shear, d["youngs_modulus_pa"] / 1e9))
print("| case | sigma_1 at 0 / 10 / 30 MPa | E_t50 (UCS) | shear cracks | phi (0-10) | "
      "phi (0-30) | C (0-30) |")
print("|---|---|---|---|---|---|---|")
for case in sorted(points):
    p = sorted(points[case])
    x = np.array([a for a, *_ in p])
    y = np.array([b for _, b, *_ in p])
    by_s3 = {a: b for a, b, *_ in p}
    two = angle((by_s3[10.0] - by_s3[0.0]) / 10) if {0.0, 10.0} <= by_s3.keys() else None
    full = "-", "-"
    if 30.0 in by_s3 and len(p) > 2:
        n, c0 = np.polyfit(x, y, 1)
        full = f"{angle(n):.1f} deg", f"{c0 / (2 * math.sqrt(n)):.1f} MPa"
    print(f"| {case} | {' / '.join(f'{b:.1f}' for _, b, *_ in p)} MPa | {p[0][3]:.1f} GPa | "
          f"{min(s for _, _, s, _ in p) * 100:.0f}-{max(s for _, _, s, _ in p) * 100:.0f} % | "
          f"{'-' if two is None else f'{two:.1f} deg'} | {full[0]} | {full[1]} |")
