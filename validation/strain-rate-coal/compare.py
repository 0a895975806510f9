#!/usr/bin/python3
"""Seed 004's strain-rate numbers beside a Breccia strain-rate sweep (its rates.csv and
sweep.json). Prints Markdown tables for the README.

Usage: compare.py SWEEP_FOLDER
"""
import csv
import json
import os
import sys

# Seed 004 (section 3, conclusions): UCS 10.06 MPa at 0.05 /s rising to 11.06 MPa at 10 /s,
# 10.1 MPa at 0.1 /s at an axial strain of 0.625 %; a gradual rise below 1 /s and a sharp one
# above; the failure plane grows with the rate (small, at the top, at 0.05-0.1 /s).
SEED_UCS_MPA = {0.05: 10.06, 0.1: 10.1, 10.0: 11.06}


def num(text, spec):
    """A rates.csv cell as printed, or '-' where the sweep has none (a dynamic increase factor
    needs the rate law, which needs at least three rates)."""
    try:
        return format(float(text), spec)
    except ValueError:
        return "-"


def main(folder):
    sweep = json.load(open(os.path.join(folder, "sweep.json")))
    rows = list(csv.DictReader(open(os.path.join(folder, "rates.csv"))))
    runs = {float(r["strain_rate_per_s"]): r for r in sweep["runs"]}
    print("| strain rate (1/s) | UCS (MPa): Breccia | seed 004 | dynamic increase factor | "
          "damage ratio D at the end (%) | failure plane dip (deg) | planarity | "
          "stress oscillation (relative) | quasi-static before the peak | wall time (s) |")
    print("|---|---|---|---|---|---|---|---|---|---|")
    for r in rows:
        rate = float(r["strain_rate_per_s"])
        run = runs.get(rate, {})
        seed = SEED_UCS_MPA.get(rate)
        qs = "-"
        summary_path = os.path.join(folder, run.get("folder", ""), "summary.json")
        if run and os.path.exists(summary_path):
            ok = json.load(open(summary_path)).get("quasi_static", {}).get("ok")
            qs = "yes" if ok else "no"
        print(f"| {rate:g} | {num(r['ucs_mpa'], '.2f')} | {seed if seed else '-'} | "
              f"{num(r['dynamic_increase_factor'], '.3f')} | "
              f"{num(r['damage_ratio_percent'], '.1f')} | {num(r['failure_plane_deg'], '.1f')} | "
              f"{num(r['planarity'], '.2f')} | {num(r['stress_oscillation_relative'], '.4f')} | "
              f"{qs} | {run.get('wall_seconds', float('nan')):.0f} |")
    fit = sweep.get("rate_dependence", {})
    print()
    if fit.get("valid"):
        se = lambda v, scale: "n/a" if v is None else f"{v / scale:.4g}"
        print(f"Fit UCS = a exp(b rate): a = {fit['a_pa'] / 1e6:.3f} +/- "
              f"{se(fit['a_standard_error_pa'], 1e6)} MPa, b = {fit['b_s']:.4f} +/- "
              f"{se(fit['b_standard_error_s'], 1)} s (rms residual "
              f"{fit['rms_residual_pa'] / 1e6:.3f} MPa; log-linear start a = "
              f"{fit['log_linear']['a_pa'] / 1e6:.3f} MPa, b = {fit['log_linear']['b_s']:.4f} s).")
        t = fit.get("three_parameter", {})
        if t.get("valid"):
            print(f"Three-parameter form: c = {t['c_pa'] / 1e6:.3f} MPa, a = {t['a_pa'] / 1e6:.4f} "
                  f"MPa, b = {t['b_s']:.3f} s (rms residual {t['rms_residual_pa'] / 1e6:.4f} MPa).")
    else:
        print(f"No fit: {fit.get('flag', 'n/a')}.")
    print("\nSeed 004: UCS 10.06 MPa at 0.05 /s to 11.06 MPa at 10 /s (+9.9 %), exponential; "
          "gradual below 1 /s, sharp above.")


if __name__ == "__main__":
    if len(sys.argv) != 2:
        sys.exit(__doc__)
    main(sys.argv[1])
