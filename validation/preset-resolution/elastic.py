#!/usr/bin/python3
"""E and Poisson's ratio of UCS runs over bands of the peak, read on the gauges.

    /usr/bin/python3 validation/preset-resolution/elastic.py RUN_FOLDER...

For each band of the deviatoric stress before the peak (5-15 %, 15-25 %, ... 65-75 % of it),
the least-squares slopes of q and of the gauges' lateral strain against the gauges' axial
strain (history.csv: gauge_axial_strain, gauge_lateral_strain) and the bonds broken by the
band's top; and the share of the bonds broken at the peak that have broken by half of it. The
first band is the rock before it cracks; E_t50 and nu of summary.json are the 45-55 % band's
neighbourhood, read where the sample may already be cracking.
"""
import csv
import json
import os
import sys

import numpy as np

BANDS = [(0.05 + 0.1 * i, 0.15 + 0.1 * i) for i in range(7)]


def bands(folder):
    with open(os.path.join(folder, "history.csv")) as f:
        rows = list(csv.DictReader(f))
    q = np.array([float(r["deviatoric_stress_pa"]) for r in rows])
    axial = np.array([float(r["gauge_axial_strain"]) for r in rows])
    lateral = np.array([float(r["gauge_lateral_strain"]) for r in rows])
    broken = np.array([int(r["broken_bonds"]) for r in rows])
    peak = int(np.argmax(q))
    out = []
    for lo, hi in BANDS:
        pick = [i for i in range(peak) if lo * q[peak] <= q[i] <= hi * q[peak]]
        if len(pick) < 3:
            out.append((lo, hi, None, None, len(pick), None))
            continue
        e = np.polyfit(axial[pick], q[pick], 1)[0]
        nu = -np.polyfit(axial[pick], lateral[pick], 1)[0]
        below = [i for i in range(peak) if q[i] <= hi * q[peak]]
        out.append((lo, hi, e, nu, len(pick), int(broken[below[-1]]) if below else 0))
    half = [i for i in range(peak) if q[i] <= 0.5 * q[peak]]
    return out, int(broken[peak]), int(broken[half[-1]]) if half else 0


def main(folders):
    if not folders:
        sys.exit(__doc__)
    for folder in folders:
        with open(os.path.join(folder, "summary.json")) as f:
            s = json.load(f)
        table, at_peak, at_half = bands(folder)
        print(f"{folder}: {s['particles']} grains, E_t50 {s['youngs_modulus_pa'] / 1e9:.1f} GPa, "
              f"nu {s['poisson_ratio']:.3f}, peak q {s['peak_deviatoric_stress_mpa']:.1f} MPa, "
              f"{at_peak} bonds broken at the peak, {at_half} by half of it "
              f"({at_half / max(at_peak, 1):.2f})")
        for lo, hi, e, nu, n, broken in table:
            if e is None:
                print(f"  {lo:.0%}-{hi:.0%} of the peak: {n} rows, too few")
            else:
                print(f"  {lo:.0%}-{hi:.0%} of the peak: E {e / 1e9:.1f} GPa, nu {nu:.3f} "
                      f"({n} rows), {broken} bonds broken by {hi:.0%}")


if __name__ == "__main__":
    main(sys.argv[1:])
