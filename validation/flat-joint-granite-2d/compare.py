"""Mohr-Coulomb envelopes of run.sh's tests: a least-squares line sigma_1 = C0 + N sigma_3 per
case over the confining stresses it has (validation/lib/envelopes.py); the angle from the UCS and
the 10 MPa test alone beside it (what a two-point calibration reads)."""
import pathlib
import sys

import numpy as np

sys.path.insert(0, str(pathlib.Path(__file__).resolve().parents[1] / "lib"))
from envelopes import cohesion, friction_angle_deg, read_points  # noqa: E402

points = read_points(sys.argv[1])
print("| case | sigma_1 at 0 / 10 / 30 MPa | E_t50 (UCS) | shear cracks | phi (0-10) | "
      "phi (0-30) | C (0-30) |")
print("|---|---|---|---|---|---|---|")
for case, p in sorted(points.items()):
    x = np.array([a for a, *_ in p])
    y = np.array([b for _, b, *_ in p])
    by_s3 = {a: b for a, b, *_ in p}
    two = (friction_angle_deg((by_s3[10.0] - by_s3[0.0]) / 10)
           if {0.0, 10.0} <= by_s3.keys() else None)
    full = "-", "-"
    if 30.0 in by_s3 and len(p) > 2:
        n, c0 = np.polyfit(x, y, 1)
        full = f"{friction_angle_deg(n):.1f} deg", f"{cohesion(n, c0):.1f} MPa"
    print(f"| {case} | {' / '.join(f'{b:.1f}' for _, b, *_ in p)} MPa | {p[0][3]:.1f} GPa | "
          f"{min(s for _, _, s, _ in p) * 100:.0f}-{max(s for _, _, s, _ in p) * 100:.0f} % | "
          f"{'-' if two is None else f'{two:.1f} deg'} | {full[0]} | {full[1]} |")
