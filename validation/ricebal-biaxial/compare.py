#!/usr/bin/python3
"""Seed 002's numbers beside a Breccia confining sweep (the sweep folder's sweep.json and the
trends.csv its report writes). Prints Markdown tables for the README.

Usage: compare.py SWEEP_FOLDER [--rock berea|lac_du_bonnet]
"""
import csv
import json
import math
import os
import subprocess
import sys

import budget

# Seed 002 (Berea sandstone model; text of sections 4.2-4.4 and figure captions 6 and 9).
SEED = {
    "berea": {
        "sigma1_mpa": {0: 85.05, 15: 143.5, 50: 238.82},
        "shear_percent": {0: 4, 15: 18, 50: 45},
        "fracture_percent": {0: 14.9, 15: 10.3, 50: 10.8},
        "strain_energy_percent": {0: 16.0, 15: 5.8, 50: 3.1},
        "friction_percent": {0: 69, 50: 86},
        "damage_index": "positive at 0-10 MPa (text; 0-2 MPa in the figure caption), negative above",
        "cohesion_mpa": 29.3, "friction_angle_deg": 29.0,
        "youngs_modulus_gpa": 4.28, "ucs_mpa": 85.0,
        "stages_15": "I 0-2.3 %, II 2.4-3.8 % (peak), III 3.9-6.2 %, IV 6.3-10.3 %",
    },
    "lac_du_bonnet": {
        "sigma1_mpa": {0: 233.79, 50: 433.63},
        "shear_percent": {15: 2},
        "fracture_percent": {0: 47.4, 50: 16.6},
        "strain_energy_percent": {0: 6.2, 50: 1.6},
        "friction_percent": {0: 46, 50: 81},
        "damage_index": "positive at every confining stress, falling with it",
        "cohesion_mpa": 54.6, "friction_angle_deg": 40.0,
        "youngs_modulus_gpa": 42.47, "ucs_mpa": 234.0,
        "stages_15": "I 0-0.7 %, II 0.8-1.5 % (peak), III 1.6-3.6 %, IV 3.7-10.3 %",
    },
}


def fmt(v, spec="{:.1f}"):
    return "-" if v is None or (isinstance(v, float) and math.isnan(v)) else spec.format(v)


def main(folder, rock):
    seed = SEED[rock]
    sweep = json.load(open(os.path.join(folder, "sweep.json")))
    trends_path = os.path.join(folder, "trends.csv")
    if not os.path.exists(trends_path):
        subprocess.run([os.path.join(os.path.dirname(__file__), "../../build/breccia"), "report",
                        folder], check=True)
    rows = list(csv.DictReader(open(trends_path)))
    num = lambda r, k: float(r[k]) if r.get(k) not in (None, "", "nan") else float("nan")
    print("| sigma_3 (MPa) | sigma_1 at peak (MPa): Breccia | seed 002 | peak strain (%) | "
          "shear cracks (%): Breccia | seed | damage index at peak | fracture / W_ext (%): "
          "Breccia | seed | strain energy / W_ext (%): Breccia | seed | friction / W_ext (%): "
          "Breccia | seed | damping / W_ext (%) | friction + damping (%) | b at peak | D2 at peak |")
    print("|" + "---|" * 17)
    for r in rows:
        s3 = round(num(r, "confining_stress_mpa"))
        print("| " + " | ".join([
            str(s3), fmt(num(r, "sigma1_at_peak_mpa")), fmt(seed["sigma1_mpa"].get(s3)),
            fmt(100 * num(r, "axial_strain_at_peak"), "{:.2f}"),
            fmt(100 * num(r, "shear_fraction_end"), "{:.0f}"), fmt(seed["shear_percent"].get(s3), "{:.0f}"),
            fmt(num(r, "damage_index_at_peak"), "{:+.4f}"),
            fmt(100 * num(r, "fracture_share")), fmt(seed["fracture_percent"].get(s3)),
            fmt(100 * num(r, "strain_energy_share")), fmt(seed["strain_energy_percent"].get(s3)),
            fmt(100 * num(r, "friction_share"), "{:.0f}"), fmt(seed["friction_percent"].get(s3), "{:.0f}"),
            fmt(100 * num(r, "damping_share"), "{:.0f}"),
            fmt(100 * (num(r, "friction_share") + num(r, "damping_share")), "{:.0f}"),
            fmt(num(r, "b_value_at_peak"), "{:.2f}"), fmt(num(r, "d2_at_peak"), "{:.2f}")]) + " |")
    mc = sweep.get("mohr_coulomb", {})
    print()
    print("| envelope | Breccia | seed 002 model |")
    print("|---|---|---|")
    print(f"| cohesion (MPa) | {fmt(mc.get('cohesion_pa', float('nan')) * 1e-6)} | {seed['cohesion_mpa']} |")
    print(f"| friction angle (deg) | {fmt(mc.get('friction_angle_deg'))} | {seed['friction_angle_deg']} |")
    print(f"| R^2 of the fit | {fmt(mc.get('r2'), '{:.3f}')} | - |")
    runs = {round(r["confining_stress_pa"] * 1e-6): r for r in sweep["runs"]}
    if 0 in runs:
        e = runs[0].get("youngs_modulus_pa")
        print(f"| E_t50 at 0 MPa (GPa) | {fmt(e * 1e-9 if e else None, '{:.2f}')} | "
              f"{seed['youngs_modulus_gpa']} |")
    print(f"\nSeed 002's damage index: {seed['damage_index']}. Its stages at 15 MPa: "
          f"{seed['stages_15']}.")
    for r in rows:
        if round(num(r, "confining_stress_mpa")) == 15:
            ends = [100 * num(r, f"stage_{k}_end_strain") for k in ("I", "II", "III")]
            print(f"Breccia's stages at 15 MPa end at {fmt(ends[0], '{:.2f}')} % (I), "
                  f"{fmt(ends[1], '{:.2f}')} % (II, the peak) and {fmt(ends[2], '{:.2f}')} % (III); "
                  "IV runs to 10.3 %.")
    stage_table(folder, sweep)
    seed_budget_table(folder, sweep, seed)


def seed_budget_table(folder, sweep, seed):
    """The work budget read with seed 002's estimators (its section 3.3-3.5 and Eq. 31) beside
    the engine's ledger, over the loading only (from the first history row, as the seed's W_ext
    is the area under its stress-strain curves): W_int the continuum elastic energy of the bulk
    E_t50 and nu at the peak (docs/analysis.md §2.3, deviatoric part), W_frac the energy released
    by bond breaks, and the seed's W_fric the remainder W_ext - W_int - W_frac, which in the
    ledger holds friction, damping, kinetic energy and the grains' stored energy together."""
    print("\n| sigma_3 (MPa) | W_ext since loading (J) | W_int, continuum at the peak / W_ext (%) "
          "| seed | W_frac / W_ext (%) | seed | remainder (seed's W_fric) / W_ext (%) | seed | "
          "ledger since loading: friction / damping / kinetic / stored (%) |")
    print("|" + "---|" * 9)
    for run in sorted(sweep["runs"], key=lambda r: r["confining_stress_pa"]):
        path = os.path.join(folder, run["folder"])
        summary = json.load(open(os.path.join(path, "summary.json")))
        cont = summary.get("energy_budget", {}).get("continuum_estimates")
        hist = list(csv.DictReader(open(os.path.join(path, "history.csv"))))
        if not cont or len(hist) < 2:
            continue
        g = budget.gains(hist[0], hist[-1])
        gain = lambda *keys: sum(g[k] for k in keys)
        w = g["work_j"]  # platens and membranes
        w_int = cont["deviatoric_elastic_energy_at_peak_j"] or float("nan")
        w_frac = gain("released_by_breaks_j")
        stored = gain(*budget.STORED)
        damping = gain("local_damping_j", "viscous_damping_j")
        s3 = round(run["confining_stress_pa"] * 1e-6)
        print(f"| {s3} | {w:.3g} | " + " | ".join([
            fmt(100 * w_int / w), fmt(seed["strain_energy_percent"].get(s3)),
            fmt(100 * w_frac / w), fmt(seed["fracture_percent"].get(s3)),
            fmt(100 * (w - w_int - w_frac) / w, "{:.0f}"),
            fmt(seed["friction_percent"].get(s3), "{:.0f}"),
            " / ".join(f"{100 * v / w:.0f}" for v in (gain("friction_j"), damping,
                                                       gain("kinetic_j"), stored))]) + " |")


def stage_table(folder, sweep):
    """Every test's four stages (docs/analysis.md §8) from its summary.json: where each ends, its
    cracks and b-value, and the trend of b over the windows before the peak (§5.4)."""
    print("\n| sigma_3 (MPa) | I ends (%) | II ends: peak (%) | III ends (%) | stages found | "
          "cracks I / II / III / IV | b in I / II / III / IV | b windows before the peak | "
          "b: first window, at the peak (Spearman rho) |")
    print("|" + "---|" * 9)
    for run in sorted(sweep["runs"], key=lambda r: r["confining_stress_pa"]):
        summary = json.load(open(os.path.join(folder, run["folder"], "summary.json")))
        stages = summary.get("stages", {}).get("by_stage", [])
        if len(stages) != 4:
            continue
        present = [s["axial_strain_from"] is not None and s["axial_strain_to"] is not None and
                   s["axial_strain_to"] > s["axial_strain_from"] for s in stages]
        ends = [fmt(100 * s["axial_strain_to"], "{:.2f}") if ok else "-"
                for s, ok in zip(stages[:3], present[:3])]
        cracks = " / ".join(str(s["cracks"]) if ok else "-" for s, ok in zip(stages, present))
        bees = " / ".join(fmt(s["b_value"], "{:.2f}") if ok else "-"
                          for s, ok in zip(stages, present))
        trend = summary.get("acoustic_emission", {}).get("b_value_before_peak", {})
        windows = trend.get("windows", 0)
        shape = "-"
        if windows:
            shape = (f"{fmt(trend.get('first_b'), '{:.2f}')}, {fmt(trend.get('at_peak_b'), '{:.2f}')}"
                     f" ({fmt(trend.get('spearman_rho'), '{:+.2f}')})")
        print(f"| {round(run['confining_stress_pa'] * 1e-6)} | " + " | ".join(
            ends + [" ".join(n for n, ok in zip(("I", "II", "III", "IV"), present) if ok),
                    cracks, bees, str(windows), shape]) + " |")


if __name__ == "__main__":
    if len(sys.argv) < 2:
        sys.exit(__doc__)
    rock = "berea"
    if "--rock" in sys.argv:
        rock = sys.argv[sys.argv.index("--rock") + 1]
    main(sys.argv[1], rock)
