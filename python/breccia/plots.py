"""Stress-strain plot with crack counts for a Breccia run folder: stress_strain.png.

Usage: python3 -m breccia.plots RUN_FOLDER (or breccia.plots.main(folder))
Reads history.csv and summary.json (if present). Needs Debian's python3-matplotlib.
"""
import csv
import json
import os
import sys

import matplotlib

import matplotlib.pyplot as plt


def main(folder):
    rows = list(csv.DictReader(open(os.path.join(folder, "history.csv"))))
    if not rows:
        sys.exit(f"{folder}/history.csv has no rows")
    path = os.path.join(folder, "summary.json")
    summary = json.load(open(path)) if os.path.exists(path) else {}
    if "headline" in summary.get(summary.get("test_kind"), {}):
        return  # a slab or dynamic test: no stress-strain curve (its figures are in the report)
    strain = [float(r["axial_strain"]) * 100 for r in rows]
    q = [float(r["deviatoric_stress_pa"]) * 1e-6 for r in rows]
    lat = [float(r["lateral_strain"]) * 100 for r in rows]
    vol = [float(r["volumetric_strain"]) * 100 for r in rows]
    tens = [int(r["tensile_cracks"]) for r in rows]
    shear = [int(r["shear_cracks"]) for r in rows]
    fig, ax = plt.subplots(figsize=(7.5, 5))
    ax.plot(strain, q, "k-", lw=1.6, label="deviatoric stress q (axial strain)")
    ax.plot(lat, q, "b--", lw=1.0, label="q (lateral strain)")
    ax.plot(vol, q, "g:", lw=1.0, label="q (volumetric strain)")
    ax.set_xlabel("strain (%)  [compression positive]")
    ax.set_ylabel("deviatoric stress q = sigma1 - sigma3 (MPa)")
    ax.grid(alpha=0.3)
    ax2 = ax.twinx()
    ax2.plot(strain, tens, color="tab:orange", lw=1.0, label="tensile cracks")
    ax2.plot(strain, shear, color="tab:red", lw=1.0, label="shear cracks")
    ax2.set_ylabel("cumulative microcracks")
    lines = ax.get_legend_handles_labels()
    lines2 = ax2.get_legend_handles_labels()
    ax.legend(lines[0] + lines2[0], lines[1] + lines2[1], loc="upper left", fontsize=8)
    title = summary.get("experiment", os.path.basename(os.path.normpath(folder)))
    if "peak_deviatoric_stress_mpa" in summary:
        e = summary.get("youngs_modulus_pa")
        title += f"\npeak {summary['peak_deviatoric_stress_mpa']:.1f} MPa"
        if e:
            title += f", E_t50 {e * 1e-9:.2f} GPa"
        title += f", {summary.get('test', '')}, sigma3 {summary.get('confining_stress_pa', 0) * 1e-6:g} MPa"
    ax.set_title(title, fontsize=9)
    fig.tight_layout()
    out = os.path.join(folder, "stress_strain.png")
    fig.savefig(out + ".tmp.png", dpi=120)
    os.replace(out + ".tmp.png", out)


if __name__ == "__main__":
    matplotlib.use("Agg")  # files only; a notebook importing the module keeps its backend
    if len(sys.argv) != 2:
        sys.exit(__doc__)
    main(sys.argv[1])
