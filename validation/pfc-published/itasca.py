#!/usr/bin/python3
"""Itasca's SS_ParallelBonded (fistPkg21, Furtney 2016) beside its published macro-properties.

Reads the run folders of itasca.sh (a UCS and a direct tension test of itasca-sandstone.toml)
and prints E (Breccia's E_t50 on the gauges, and on the platen approach as PFC's walls read
it), Poisson's ratio, the UCS and the direct tensile strength against the memo's values, with
the sample's porosity and bonds per interior grain.

    /usr/bin/python3 itasca.py RUN_FOLDER...
"""
import json
import pathlib
import sys

PUBLISHED = {"E_gpa": 1.82, "ucs_mpa": 3.4, "ts_mpa": 0.74}  # Furtney (2016), Itasca memo 8528-03


def ratio(value, published):
    return f"{value:.3g} ({value / published - 1:+.1%})"


def main(folders):
    rows = []
    for folder in map(pathlib.Path, folders):
        if not (folder / "summary.json").exists():
            print(f"itasca.py: {folder}: no summary.json (still running?); left out", file=sys.stderr)
            continue
        s = json.loads((folder / "summary.json").read_text())
        sample = s["sample"]
        kind = s["test_kind"]  # ucs or direct_tension
        e = (s.get("youngs_modulus_pa") or float("nan")) / 1e9
        e_platen = (s.get("youngs_modulus_platen_pa") or float("nan")) / 1e9
        strength = s["peak_deviatoric_stress_mpa"]
        published = PUBLISHED["ts_mpa"] if kind == "direct_tension" else PUBLISHED["ucs_mpa"]
        label = f"{s['experiment']} ({kind}, {s['platen_speed_m_per_s']:g} m/s)"
        rows.append((label, s["particles"], sample.get("porosity"), sample.get("bonds_per_interior_particle"),
                     ratio(e, PUBLISHED["E_gpa"]), (ratio(e_platen, PUBLISHED["E_gpa"]) if kind == "ucs" else "-"),
                     s.get("poisson_ratio"), ratio(strength, published), s["cracks_shear"] / max(1, s["bonds_broken"]),
                     s["wall_seconds"], s["quasi_static"]["ok"]))
    print("| run | grains | porosity | bonds per interior grain | E_t50, GPa | E on the platens, GPa | "
          "Poisson | strength, MPa | shear cracks | wall time | quasi-static |")
    print("|---|---|---|---|---|---|---|---|---|---|---|")
    print(f"| published (PFC3D 5.0) | | | | {PUBLISHED['E_gpa']} | | | UCS {PUBLISHED['ucs_mpa']}, "
          f"direct tension {PUBLISHED['ts_mpa']} | | | |")
    for r in rows:
        print(f"| {r[0]} | {r[1]} | {r[2]:.3f} | {r[3]:.2f} | {r[4]} | {r[5]} | {r[6]:.3f} | {r[7]} | "
              f"{100 * r[8]:.1f} % | {r[9]:.0f} s | {'yes' if r[10] else 'no'} |")


if __name__ == "__main__":
    main(sys.argv[1:])
