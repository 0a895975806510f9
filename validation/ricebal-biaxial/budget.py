#!/usr/bin/python3
"""One row per test of the sweeps OUT/NAME/<sweep>/<test>: the peak, E_t50, the shear-crack
share, the damage index at the peak, the quasi-static checks (kinetic over strain energy and the
platen-force imbalance before the peak) and the work budget over the loading (from the first
history row), the membranes' work included: friction, damping, kinetic, stored, and the
remainder W_ext - W_int - W_frac that seed 002 books as friction (compare.py's estimators).

Usage: budget.py [--to-strain X | --split-at-peak] OUT NAME...
  --to-strain X: the budget from the first history row to the last at or below axial strain X
  (runs that went on further are compared over the same strain); by default to the last row.
  --split-at-peak: where the work goes up to the peak row and after it, each as a share of the
  whole test's work (the stored energy after the peak is what the failure released).
"""
import csv
import glob
import json
import os
import sys

STORED = ("bond_tension_j", "bond_compression_j", "bond_shear_j", "bond_bending_j",
          "bond_twisting_j", "contact_strain_j")


DISSIPATED = ("friction_j", "local_damping_j", "viscous_damping_j", "deleted_springs_j",
              "released_by_breaks_j")


def gains(first, last):
    """The change of every ledger column from one history row to another, and the work done on
    the sample (platens and membranes). A run recorded before history.csv had the membranes'
    column gives their work from its residual column, which the engine takes with it:
    W_loads = R + dU + D - W_platens, exact to the rounding of the printed digits."""
    gain = lambda *keys: sum(float(last[k]) - float(first[k]) for k in keys)
    g = {k: gain(k) for k in first if k.endswith("_j")}
    if "external_load_work_j" not in first:
        g["external_load_work_j"] = (gain("energy_residual_j", "kinetic_j", *STORED, *DISSIPATED)
                                     - gain("boundary_work_j"))
    g["work_j"] = g["boundary_work_j"] + g["external_load_work_j"]
    return g


def damage_index_at_peak(path, peak_strain):
    """The last indicator window ending at or before the peak, as the report's trends read it."""
    rows = list(csv.DictReader(open(os.path.join(path, "indicators.csv"))))
    rows = [r for r in rows if float(r["axial_strain"]) <= peak_strain + 1e-12]
    if not rows or rows[-1]["damage_index"] in ("", "nan"):
        return float("nan")
    return float(rows[-1]["damage_index"])


def row(name, path, to_strain=None):
    s = json.load(open(os.path.join(path, "summary.json")))
    hist = list(csv.DictReader(open(os.path.join(path, "history.csv"))))
    if to_strain is not None:
        hist = [h for h in hist if float(h["axial_strain"]) <= to_strain] or hist[:1]
    g = gains(hist[0], hist[-1])
    gain = lambda *keys: sum(g[k] for k in keys)
    w = g["work_j"]
    cont = s["energy_budget"]["continuum_estimates"]
    w_int = cont["deviatoric_elastic_energy_at_peak_j"] or float("nan")
    w_frac = gain("released_by_breaks_j")
    q = s["quasi_static"]
    ke = q["max_kinetic_to_strain_energy_before_peak"]
    shares = [gain("friction_j"), gain("local_damping_j", "viscous_damping_j"), gain("kinetic_j"),
              gain(*STORED), w - w_int - w_frac]
    cracks = max(1, s["bonds_broken"])
    return (f"| {name} | {round(s['confining_stress_pa'] / 1e6)} | "
            f"{s['peak_deviatoric_stress_mpa']:.1f} | {s['youngs_modulus_pa'] / 1e9:.2f} | "
            f"{100 * s['cracks_shear'] / cracks:.1f} | "
            f"{damage_index_at_peak(path, s['axial_strain_at_peak']):+.4f} | "
            f"{ke:.4f} | {q['max_platen_force_imbalance_before_peak']:.3f} | "
            + " | ".join(f"{100 * v / w:.0f}" for v in shares) + " |")


def tests_of(out, name):
    """The run folders of sweep NAME in OUT, by confining stress."""
    summaries = glob.glob(os.path.join(out, name, "*", "*", "summary.json"))
    summaries.sort(key=lambda p: json.load(open(p))["confining_stress_pa"])
    return [os.path.dirname(p) for p in summaries]


def split_row(name, path):
    s = json.load(open(os.path.join(path, "summary.json")))
    hist = list(csv.DictReader(open(os.path.join(path, "history.csv"))))
    q = [float(h["deviatoric_stress_pa"]) for h in hist]
    peak = max(range(len(q)), key=q.__getitem__)
    before, after = gains(hist[0], hist[peak]), gains(hist[peak], hist[-1])
    total = before["work_j"] + after["work_j"]
    pc = lambda g, *keys: f"{100 * sum(g[k] for k in keys) / total:.0f}"
    damping = ("local_damping_j", "viscous_damping_j")
    return (f"| {name} | {round(s['confining_stress_pa'] / 1e6)} | "
            f"{pc(before, 'work_j')} / {pc(before, *STORED)} / {pc(before, 'friction_j')} / "
            f"{pc(before, *damping)} | {pc(after, 'work_j')} / "
            f"{100 * -sum(after[k] for k in STORED) / total:.0f} / {pc(after, 'friction_j')} / "
            f"{pc(after, *damping)} / {pc(after, 'released_by_breaks_j')} |")


def main_split(out, names):
    print("| run | sigma_3 (MPa) | to the peak: work / stored / friction / damping (%) "
          "| after the peak: work / stored released / friction / damping / breaks (%) |")
    print("|" + "---|" * 4)
    for name in names:
        for path in tests_of(out, name):
            print(split_row(name, path))


def main(out, names, to_strain=None):
    print("| run | sigma_3 (MPa) | peak q (MPa) | E_t50 (GPa) | shear (%) | damage index at peak "
          "| kinetic / strain energy before the peak (limit 0.001) | platen imbalance before "
          "the peak (limit 0.05) | friction / W_ext (%) | damping (%) | kinetic (%) | stored (%) "
          "| remainder W_ext - W_int - W_frac (%) |")
    print("|" + "---|" * 13)
    for name in names:
        for path in tests_of(out, name):
            print(row(name, path, to_strain))


if __name__ == "__main__":
    args = sys.argv[1:]
    to_strain = None
    if args[:1] == ["--split-at-peak"]:
        if len(args) < 3:
            sys.exit(__doc__)
        main_split(args[1], args[2:])
        sys.exit(0)
    if args[:1] == ["--to-strain"]:
        if len(args) < 2:
            sys.exit(__doc__)
        to_strain = float(args[1])
        args = args[2:]
    if len(args) < 2:
        sys.exit(__doc__)
    main(args[0], args[1:], to_strain)
