"""Mohr-Coulomb envelopes from run folders laid out as OUT/<case>/<run>/summary.json: the peak
axial stress of each run against its confining stress, grouped by case, and the friction angle
and cohesion of a line sigma_1 = C0 + N sigma_3."""
import glob
import json
import math


def read_points(out):
    """{case: sorted [(sigma_3 MPa, sigma_1 at peak MPa, shear crack share, E GPa)]}."""
    points = {}
    for f in sorted(glob.glob(f"{out}/*/*/summary.json")):
        d = json.load(open(f))
        case = f.split("/")[-3]
        s3 = d.get("confining_stress_pa", 0.0) / 1e6
        shear = d["cracks_shear"] / max(1, d["cracks_shear"] + d["cracks_tensile"])
        points.setdefault(case, []).append(
            (s3, d["sigma1_at_peak_pa"] / 1e6, shear, d["youngs_modulus_pa"] / 1e9))
    return {case: sorted(p) for case, p in points.items()}


def friction_angle_deg(n):
    """phi = asin((N - 1) / (N + 1)) for the slope N of sigma_1 against sigma_3."""
    return math.degrees(math.asin((n - 1) / (n + 1)))


def cohesion(n, c0):
    """C = C0 / (2 sqrt(N)) for the intercept C0 and slope N."""
    return c0 / (2 * math.sqrt(n))
