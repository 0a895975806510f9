"""Mohr-Coulomb envelopes of run.sh's tests: a least-squares line sigma_1 = C0 + N sigma_3 per
packing and rolling friction (validation/lib/envelopes.py)."""
import pathlib
import sys

import numpy as np

sys.path.insert(0, str(pathlib.Path(__file__).resolve().parents[1] / "lib"))
from envelopes import cohesion, friction_angle_deg, read_points  # noqa: E402

points = read_points(sys.argv[1])
print("| packing | mu_r | sigma_1 at 0 / 10 / 30 MPa | shear cracks | phi | C |")
print("|---|---|---|---|---|---|")
for case, p in sorted(points.items()):
    x = np.array([a for a, *_ in p])
    y = np.array([b for _, b, *_ in p])
    n, c0 = np.polyfit(x, y, 1)
    seed, mr = case[1:].split("_mr")
    print(f"| {seed} | {mr} | {' / '.join(f'{b:.1f}' for _, b, *_ in p)} MPa | "
          f"{min(s for _, _, s, _ in p) * 100:.0f}-{max(s for _, _, s, _ in p) * 100:.0f} % | "
          f"{friction_angle_deg(n):.1f} deg | {cohesion(n, c0):.1f} MPa |")
