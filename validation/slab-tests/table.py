#!/usr/bin/env python3
"""The slab-test validation tables (seed 001, figure 16) from the sweeps in OUT
(validation/slab-tests/run.sh): one table per test found there.

- impact (16B): the cracks at each thickness, scaled by the most any run of that rock had (the
  seed's N_frac / N_frac,max) and by the most of all rocks, the fragments, the deepest
  indentation and the energy released by breaking bonds;
- cantilever (16A): the largest force at each thickness, scaled by the rock's largest and by
  the largest of all, the flexural strength, the initial stiffness, the cracks and the
  quasi-static check;
- vibration (16C): cracks and fragments (with the single grains and the largest piece);
- abrasion (16D): the bulk friction coefficient (mean and spread over the second half of the
  slide) and the mass worn off at each normal stress.

Usage: /usr/bin/python3 validation/slab-tests/table.py OUT
"""
import glob
import json
import os
import sys


def runs_of(out, test):
    """(rock, sweep run, summary) for every complete run of every sweep of `test` in OUT; the
    others (interrupted, failed) are named on standard error and left out."""
    for sweep_file in sorted(glob.glob(os.path.join(out, test, "*-sweep", "sweep.json"))):
        sweep = json.load(open(sweep_file))
        rock = sweep["experiment"].replace(test + "-", "")
        for r in sweep["runs"]:
            if r.get("status") != "complete":
                print(f"left out: {test} {rock} {r.get('value')}: {r.get('status')}",
                      file=sys.stderr)
                continue
            path = os.path.join(os.path.dirname(sweep_file), r["folder"], "summary.json")
            yield rock, r, (json.load(open(path)) if os.path.exists(path) else {})


def fmt(v, spec="{:.3g}"):
    return "n/a" if v is None else spec.format(v)


def impact_table(out):
    rows = list(runs_of(out, "impact"))
    if not rows:
        return
    most = max((r.get("cracks") or 0) for _, r, _ in rows)
    print("## impact\n")
    print("| rock | thickness (mm) | bonds | cracks | N / N_max (rock) | N / N_max (all) "
          "| fragments | indentation (mm) | released by breaks |")
    print("|---|---|---|---|---|---|---|---|---|")
    for rock, r, s in rows:
        im = s.get("impact", {})
        released = im.get("energy_shares_of_impact", {}).get("released_by_breaks")
        print(f"| {rock} | {1e3 * float(r['value']):g} | {r.get('bonds_initial')} | "
              f"{r.get('cracks')} | {r['cracks_scaled']:.2f} | {(r.get('cracks') or 0) / most:.2f} "
              f"| {r.get('fragments')} | {fmt(1e3 * im.get('max_indentation_m', float('nan')), '{:.2f}')} "
              f"| {fmt(100 * released if released is not None else None, '{:.1f}')} % |")
    print()


def cantilever_table(out):
    rows = list(runs_of(out, "cantilever"))
    if not rows:
        return
    force = lambda r: (r.get("metrics") or {}).get("max_force_n") or 0.0
    most = max(force(r) for _, r, _ in rows)
    rock_most = {}
    for rock, r, _ in rows:
        rock_most[rock] = max(rock_most.get(rock, 0.0), force(r))
    print("## cantilever\n")
    print("| rock | thickness (mm) | grains | F_max (N) | F / F_max (rock) | F / F_max (all) "
          "| flexural strength (MPa) | initial stiffness (N/mm) | cracks | near the vice "
          "| force imbalance before the peak |")
    print("|---|---|---|---|---|---|---|---|---|---|---|")
    for rock, r, s in rows:
        c = s.get("cantilever", {})
        qs = c.get("quasi_static", {})
        print(f"| {rock} | {1e3 * float(r['value']):g} | {s.get('particles')} | {force(r):.1f} | "
              f"{force(r) / rock_most[rock]:.2f} | {force(r) / most:.2f} | "
              f"{1e-6 * c.get('flexural_strength_pa', float('nan')):.1f} | "
              f"{1e-3 * c.get('initial_stiffness_n_per_m', float('nan')):.0f} | {r.get('cracks')} | "
              f"{100 * c.get('cracks_near_root_share', float('nan')):.0f} % | "
              f"{100 * qs.get('max_force_imbalance_before_peak', float('nan')):.0f} % |")
    print()


def vibration_table(out):
    rows = list(runs_of(out, "vibration"))
    if not rows:
        return
    print("## vibration\n")
    print("| rock | thickness (mm) | grains | cracks | cracks per cycle | fragments | single grains "
          "| largest piece (share of mass) |")
    print("|---|---|---|---|---|---|---|---|")
    for rock, r, s in rows:
        v = s.get("vibration", {})
        f = s.get("fragments", {})
        print(f"| {rock} | {1e3 * float(r['value']):g} | {s.get('particles')} | {r.get('cracks')} | "
              f"{fmt(v.get('cracks_per_cycle'), '{:.0f}')} | {r.get('fragments')} | "
              f"{f.get('single_particle_debris', 'n/a')} | "
              f"{fmt(r.get('largest_fragment_fraction'), '{:.2f}')} |")
    print()


def abrasion_table(out):
    rows = list(runs_of(out, "abrasion"))
    if not rows:
        return
    print("## abrasion\n")
    print("| rock | normal stress (MPa) | bulk friction (mean) | spread (sd) | cracks "
          "| worn off (mg) | worn pieces | settled |")
    print("|---|---|---|---|---|---|---|---|")
    for rock, r, s in rows:
        a = s.get("abrasion", {})
        print(f"| {rock} | {1e-6 * float(r['value']):g} | "
              f"{fmt(a.get('bulk_friction_mean'), '{:.3f}')} | "
              f"{fmt(a.get('bulk_friction_sd'), '{:.3f}')} | {r.get('cracks')} | "
              f"{fmt(1e6 * a['worn_mass_kg'] if 'worn_mass_kg' in a else None, '{:.2f}')} | "
              f"{a.get('worn_pieces', 'n/a')} | {a.get('settled', 'n/a')} |")
    print()


def main(out):
    impact_table(out)
    cantilever_table(out)
    vibration_table(out)
    abrasion_table(out)


if __name__ == "__main__":
    if len(sys.argv) != 2:
        sys.exit(__doc__)
    main(sys.argv[1])
