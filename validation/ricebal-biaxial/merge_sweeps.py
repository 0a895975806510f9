#!/usr/bin/python3
"""Joins confining sweeps of one experiment run in parts (for example 0/15/50 MPa first, the other
confinements later) into one sweep folder that compare.py and `breccia report` read: the run
folders linked, sweep.json with every run in order of sigma_3, and the Mohr-Coulomb envelope
fitted again over all of them by the sweep's own method (least squares of sigma_1 on sigma_3:
sigma_1 = UCS + k sigma_3, phi = asin((k - 1) / (k + 1)), C = UCS / (2 sqrt(k))).

Usage: merge_sweeps.py OUTPUT SWEEP_FOLDER...
"""
import json
import math
import os
import sys

import numpy as np


def main(output, sweeps):
    os.makedirs(output, exist_ok=False)
    runs, experiment = [], None
    for folder in sweeps:
        sweep = json.load(open(os.path.join(folder, "sweep.json")))
        experiment = experiment or sweep["experiment"]
        for r in sweep["runs"]:
            os.symlink(os.path.abspath(os.path.join(folder, r["folder"])),
                       os.path.join(output, r["folder"]))
            runs.append(r)
    runs.sort(key=lambda r: r["confining_stress_pa"])
    done = [r for r in runs if r["status"] == "complete"]
    s3 = np.array([r["confining_stress_pa"] for r in done])
    s1 = np.array([r["sigma1_at_peak_pa"] for r in done])
    k, ucs = np.polyfit(s3, s1, 1)
    fitted = ucs + k * s3
    r2 = 1 - np.sum((s1 - fitted) ** 2) / np.sum((s1 - s1.mean()) ** 2)
    mc = {"method": "least squares of sigma_1 on sigma_3 (principal-stress form), "
                    "merged by merge_sweeps.py",
          "k": k, "ucs_intercept_pa": ucs, "r2": r2,
          "friction_angle_deg": math.degrees(math.asin((k - 1) / (k + 1))),
          "cohesion_pa": ucs / (2 * math.sqrt(k)), "valid": True, "flag": ""}
    merged = {"experiment": experiment, "variable": "confining_stress", "runs": runs,
              "status": "complete" if len(done) == len(runs) else "incomplete",
              "mohr_coulomb": mc, "sources": [os.path.abspath(s) for s in sweeps]}
    with open(os.path.join(output, "sweep.json"), "w") as f:
        json.dump(merged, f, indent=1)
    print(output)


if __name__ == "__main__":
    if len(sys.argv) < 3:
        sys.exit(__doc__)
    main(sys.argv[1], sys.argv[2:])
