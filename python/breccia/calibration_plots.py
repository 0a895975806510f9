"""Draws convergence.png of a calibration folder: per target, the value each trial achieved
(coloured by stage) against the lab target and its tolerance band."""
import csv
import json
import os
import sys

import matplotlib

import matplotlib.pyplot as plt

SCALE = {"youngs_modulus": (1e9, "GPa"), "uniaxial_strength": (1e6, "MPa"),
         "tensile_strength": (1e6, "MPa"), "cohesion": (1e6, "MPa"),
         "friction_angle_deg": (1.0, "deg"), "strain_at_peak": (1e-2, "%")}
COLOURS = {"elastic": "tab:blue", "strength": "tab:red", "friction": "tab:green",
           "final": "black"}


def main(folder):
    with open(os.path.join(folder, "convergence.csv")) as f:
        rows = list(csv.DictReader(f))
    record = {}
    if os.path.exists(os.path.join(folder, "record.json")):
        with open(os.path.join(folder, "record.json")) as f:
            record = json.load(f)
    tolerance = {v["target"]: (v["tolerance"], v["relative"]) for v in record.get("verdicts", [])}
    targets = [c[:-len("_target")] for c in rows[0].keys() if c.endswith("_target")] if rows else []
    n = max(1, len(targets))
    fig, axes = plt.subplots(n, 1, figsize=(6.5, 2.1 * n + 0.6), sharex=True, squeeze=False)
    for ax, name in zip(axes[:, 0], targets):
        scale, unit = SCALE.get(name, (1.0, "-"))
        target = float(rows[0][name + "_target"]) / scale
        xs, ys, cs = [], [], []
        for r in rows:
            if r[name + "_achieved"]:
                xs.append(int(r["trial"]))
                ys.append(float(r[name + "_achieved"]) / scale)
                cs.append(COLOURS.get(r["stage"], "grey"))
        # After a size correction the search aims elsewhere than the lab's value (the gap
        # between the calibration sample and the verification's): drawn as a dotted step.
        aims = [float(r[name + "_target"]) / scale for r in rows]
        if any(a != target for a in aims):
            ax.step([int(r["trial"]) for r in rows], aims, where="post", color="k", ls=":",
                    lw=1, label="aim of the search")
        ax.plot(xs, ys, color="0.75", lw=1, zorder=1)
        ax.scatter(xs, ys, c=cs, s=22, zorder=2)
        ax.axhline(target, color="k", ls="--", lw=1)
        if name in tolerance:
            tol, rel = tolerance[name]
            lo, hi = (target * (1 - tol), target * (1 + tol)) if rel else (target - tol / scale,
                                                                          target + tol / scale)
            ax.axhspan(lo, hi, color="0.9", zorder=0)
        ax.set_ylabel(f"{name.replace('_', ' ')}\n({unit})", fontsize=8)
        ax.tick_params(labelsize=8)
    axes[-1, 0].set_xlabel("trial")
    handles = [plt.Line2D([], [], marker="o", ls="", color=c, label=s) for s, c in COLOURS.items()]
    axes[0, 0].legend(handles=handles, fontsize=7, ncol=4, loc="best")
    fig.suptitle(f"Calibration {record.get('name', os.path.basename(folder))}: "
                 "achieved against target (band: tolerance)", fontsize=9)
    fig.tight_layout()
    fig.savefig(os.path.join(folder, "convergence.png"), dpi=120)
    return 0


if __name__ == "__main__":
    matplotlib.use("Agg")  # files only; a notebook importing the module keeps its backend
    sys.exit(main(sys.argv[1]))
