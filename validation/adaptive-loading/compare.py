#!/usr/bin/python3
"""Constant-speed against adaptive loading: one table row per run folder (LABEL=FOLDER ...), with
the steps, the results that must not change and the energy partition at the peak and at the end.
Shares are of the boundary work (platens and membranes) done by then."""
import json
import sys

import pandas as pd

STORED = ["bond_tension_j", "bond_compression_j", "bond_shear_j", "bond_bending_j",
          "bond_twisting_j", "contact_strain_j"]


def partition(row):
    work = row["boundary_work_j"] + row["external_load_work_j"]
    parts = {"friction": row["friction_j"], "damping": row["local_damping_j"] + row["viscous_damping_j"],
             "strain": sum(row[c] for c in STORED), "kinetic": row["kinetic_j"]}
    return " / ".join(f"{100 * v / work:.1f}" for v in parts.values())


def main(args):
    print("| run | steps | loop time (s) | E_t50 (GPa) | peak q (MPa) | strain at peak (%) | cracks at peak | "
          "end: strain (%), cracks, shear (%) | friction / damping / strain / kinetic at the peak (% of work) | "
          "the same at the end | b | kinetic/strain before the peak | fastest (m/s) |")
    print("|" + "---|" * 13)
    for arg in args:
        label, folder = arg.split("=", 1)
        s = json.load(open(f"{folder}/summary.json"))
        h = pd.read_csv(f"{folder}/history.csv")
        ip = h["deviatoric_stress_pa"].idxmax()
        end = h.iloc[-1]
        ae = s["acoustic_emission"]
        b = ae.get("b_value")
        b_text = "-" if not b or b.get("b") is None else f"{b['b']:.2f} +/- {b['sigma']:.2f}"
        fastest = s.get("adaptive_loading", {}).get("largest_speed_m_per_s", s["platen_speed_m_per_s"])
        shear = 100 * s["cracks_shear"] / max(1, s["bonds_broken"])
        e = s["youngs_modulus_pa"]
        print(f"| {label} | {s['steps']:,} | {s['loading_loop']['seconds']:.0f} | "
              f"{'-' if e is None else f'{e / 1e9:.2f}'} | {s['peak_deviatoric_stress_pa'] / 1e6:.2f} | "
              f"{100 * s['axial_strain_at_peak']:.3f} | {int(h['broken_bonds'][ip]):,} | "
              f"{100 * end['axial_strain']:.2f}, {int(end['broken_bonds']):,}, {shear:.1f} | "
              f"{partition(h.iloc[ip])} | {partition(end)} | {b_text} | "
              f"{s['quasi_static']['max_kinetic_to_strain_energy_before_peak']:.2g} | {fastest:.3g} |")


if __name__ == "__main__":
    main(sys.argv[1:])
