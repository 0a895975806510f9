#!/usr/bin/env python3
"""For each biaxial run folder: E_t50 and nu (the summary's), the modulus over fixed bands of the
deviatoric stress (slope of q against the gauge axial strain over the history rows of the band,
before the peak), and the cracks by half the peak: their share of the bonds, and their density
within 0.5 mm of the sample's edges and inside (the sample's box from its geometry file).
README, "Size or packing: windows cut from the 60k sample".

    window_moduli.py RUN_FOLDER...
"""
import csv
import json
import os
import re
import sys

import numpy as np

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import crop  # noqa: E402

BANDS_MPA = ((30.0, 70.0), (68.0, 102.0))
EDGE_M = 0.5e-3


def band_modulus(q_mpa, gauge, lo, hi):
    peak = int(np.argmax(q_mpa))
    m = (q_mpa[:peak] >= lo) & (q_mpa[:peak] <= hi)
    if m.sum() < 2:
        return float("nan"), int(m.sum())
    return np.polyfit(gauge[:peak][m], q_mpa[:peak][m], 1)[0] / 1e3, int(m.sum())


def sample_box(folder):
    text = open(os.path.join(folder, "experiment.toml")).read()
    path = re.search(r'^file\s*=\s*"([^"]+)"', text, re.M).group(1)
    _, particles, _ = crop.read(path)
    xr = [(float(p[1]) - float(p[4]), float(p[1]) + float(p[4])) for p in particles]
    yr = [(float(p[2]) - float(p[4]), float(p[2]) + float(p[4])) for p in particles]
    return min(a for a, _ in xr), max(b for _, b in xr), min(a for a, _ in yr), max(b for _, b in yr)


def describe(folder):
    s = json.load(open(os.path.join(folder, "summary.json")))
    hist = list(csv.DictReader(open(os.path.join(folder, "history.csv"))))
    q = np.array([float(h["deviatoric_stress_pa"]) for h in hist]) / 1e6
    gauge = np.array([float(h["gauge_axial_strain"]) for h in hist])
    bands = []
    for lo, hi in BANDS_MPA:
        e, n = band_modulus(q, gauge, lo, hi)
        bands.append(f"E over q {lo:.0f}-{hi:.0f} MPa {e:.2f} GPa ({n} rows)")
    half = 0.5 * s["peak_deviatoric_stress_pa"] / 1e6
    step_half = next(int(h["step"]) for h, v in zip(hist, q) if v >= half)
    cracks = np.genfromtxt(os.path.join(folder, "cracks.csv"), delimiter=",", names=True,
                           usecols=(0, 8, 9), ndmin=1)
    cracks = cracks[cracks["step"] <= step_half]
    x0, x1, y0, y1 = sample_box(folder)
    w, h = x1 - x0, y1 - y0
    near = ((cracks["x_m"] - x0 < EDGE_M) | (x1 - cracks["x_m"] < EDGE_M)
            | (cracks["y_m"] - y0 < EDGE_M) | (y1 - cracks["y_m"] < EDGE_M))
    edge_area = w * h - (w - 2 * EDGE_M) * (h - 2 * EDGE_M)
    inner_area = (w - 2 * EDGE_M) * (h - 2 * EDGE_M)
    print(f"{s['experiment']}: {s['particles']} disks, E_t50 {s['youngs_modulus_pa'] / 1e9:.2f} "
          f"GPa, nu {s['poisson_ratio']:.3f}, peak q {s['peak_deviatoric_stress_pa'] / 1e6:.1f} "
          f"MPa; " + "; ".join(bands) + f"; by half the peak {len(cracks)} cracks "
          f"({100 * len(cracks) / s['bonds_initial']:.2f} % of the bonds), "
          f"{near.sum() / edge_area / 1e6:.1f} per mm^2 within {EDGE_M * 1e3:g} mm of an edge, "
          f"{(~near).sum() / inner_area / 1e6:.2f} inside; {s['steps']} steps, "
          f"{s['wall_seconds']:.0f} s")


if __name__ == "__main__":
    if len(sys.argv) < 2:
        sys.exit(__doc__)
    for folder in sys.argv[1:]:
        describe(folder)
