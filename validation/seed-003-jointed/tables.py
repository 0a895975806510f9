#!/usr/bin/python3
"""Seed 003's Tables 4 and 5 beside Breccia's runs (run by hand, not by CI).

For each run folder (a triaxial test of examples/triaxial-smooth-joint.toml, jointed or with
`joint.planes = []`, or the unconfined test of unconfined.toml), reads summary.json, experiment.toml and events.csv and prints:
- the strength row: peak differential stress, strain at the peak, cracks and their shear share;
- Table 4: the kinetic energy of the events (the rise of the grains' kinetic energy around each
  event, docs/analysis.md §4.4, the seed's "kinetic energy from bond breakages"), the boundary
  work and their ratio, the seed's "brittle failure percentage";
- Table 5: the events, the share of single-bond events, the radiated energy summed over the
  events (Kanamori's relation on each event's moment magnitude, §4.2), its share of the boundary
  work, the b-value, D2 (the summary's: of the crack midpoints, with its own scaling range, §6)
  and, as the seed's D, the correlation dimension of the event centroids over a fixed range
  (from the mean grain diameter to a quarter of the sample's diameter, 8 log-spaced radii; an
  evenly strided 3,000 of them where there are more), and the events' source types
  (Feignier & Young's R);
each beside the seed's row for the same confinement and joint. The seed's numbers are those of
its Tables 3-5 (its 6 mm joint), quoted in this folder's README.

    /usr/bin/python3 tables.py RUN_FOLDER...
"""
import argparse
import csv
import json
import math
import pathlib
import sys
import tomllib

import numpy as np

# Seed 003, keyed by (confining stress in MPa, jointed): peak differential stress (MPa; Table 3's
# absolute peaks less the confinement, the 20 MPa rows from the text), Table 4 (kinetic energy J,
# boundary work J, brittle %) and Table 5 (events, single-bond %, radiated energy J,
# radiated / boundary work %, b, D).
SEED = {
    (0, False): (105.0, 0.0698, 0.7095, 9.84, 1723, 73, 0.000785, 0.1, "2.35 +/- 0.2", "2.73 +/- 0.11"),
    (20, False): (137.8, 0.0761, 1.7287, 4.40, 2868, 66, 0.001433, 0.08, "2.25 +/- 0.08", "2.79 +/- 0.08"),
    (40, False): (160.5, 0.1745, 3.4986, 4.99, 4276, 65, 0.002699, 0.08, "2.14 +/- 0.09", "2.80 +/- 0.09"),
    (20, True): (53.2, 0.0194, 0.4449, 4.36, 600, 71, 0.000282, 0.06, "2.33 +/- 0.13", "1.67 +/- 0.09"),
    (40, True): (35.3, 0.0225, 0.4156, 5.41, 610, 73, 0.000399, 0.08, "1.59 +/- 0.09", "1.54 +/- 0.12"),
}


def fmt(value, spec, unit=""):
    if value is None or (isinstance(value, float) and math.isnan(value)):
        return "n/a"
    return format(value, spec) + unit


def events_of(run):
    path = run / "events.csv"
    if not path.exists():
        return []
    with open(path) as f:
        return list(csv.DictReader(f))


def event_d2(run, events):
    """Slope of log C(r) against log r for the event centroids, r from the mean grain diameter
    to a quarter of the sample's diameter (Grassberger & Procaccia, all pairs)."""
    if len(events) < 50:
        return float("nan")
    manifest = json.loads((run / "manifest.json").read_text())
    sample = json.loads(pathlib.Path(manifest["sample"]["cached_file"] + ".json").read_text())
    points = np.array([[float(e[c]) for c in ("x_m", "y_m", "z_m")] for e in events])
    points = points[:: len(points) // 3000 + 1]  # all pairs of at most 3,000 points
    gaps = np.sqrt(((points[:, None, :] - points[None, :, :]) ** 2).sum(-1))
    gaps = gaps[np.triu_indices(len(points), 1)]
    radii = np.logspace(np.log10(2 * sample["radius_mean_m"]), np.log10(min(sample["size_m"][:2]) / 4), 8)
    c = np.array([(gaps < r).mean() for r in radii])
    return float(np.polyfit(np.log10(radii), np.log10(c), 1)[0])


def read_run(run):
    s = json.loads((run / "summary.json").read_text())
    exp = tomllib.loads((run / "experiment.toml").read_text())
    ae = s["acoustic_emission"]
    events = events_of(run)
    radiated = [float(e["radiated_energy_j"]) for e in events]
    radiated_sum = sum(r for r in radiated if not math.isnan(r))
    work = s["energy"]["boundary_work_j"]
    ke = ae["energy"]["kinetic_energy_events_j"]
    b = ae["b_value"]
    d2 = ae["d2"]
    return {
        "name": run.name,
        "s3_mpa": round((s.get("confining_stress_pa") or 0.0) / 1e6),
        "platen_friction": exp.get("contact", {}).get("wall_friction", 0.0),
        "jointed": bool(exp.get("joint", {}).get("planes")),
        "grains": s.get("particles"),
        "q_mpa": s["peak_deviatoric_stress_mpa"],
        "strain_pct": 100 * s["axial_strain_at_peak"],
        "cracks": s["bonds_broken"],
        "shear_pct": 100 * s["cracks_shear"] / max(1, s["bonds_broken"]),
        "ke": ke,
        "work": work,
        "brittle_pct": 100 * ke / work if work else float("nan"),
        "events": len(events),
        "single_pct": 100 * sum(e["cracks"] == "1" for e in events) / max(1, len(events)),
        "radiated": radiated_sum,
        "radiated_pct": 100 * radiated_sum / work if work else float("nan"),
        "b": f"{fmt(b['b'], '.2f')} +/- {fmt(b['sigma'], '.2f')}" if b["b"] is not None else b["flag"],
        "d2": f"{fmt(d2['d2'], '.2f')} +/- {fmt(d2['standard_error'], '.2f')}"
        if d2["d2"] is not None else str(d2["flags"]),
        "event_d2": event_d2(run, events),
        "types": ae["source_types_by_r_ratio"],
    }


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("runs", nargs="+", type=pathlib.Path)
    runs = ap.parse_args().runs
    for r in runs:
        if not (r / "summary.json").exists():
            print(f"tables.py: {r}: no summary.json (still running, or not a run folder); left out",
                  file=sys.stderr)
    rows = [read_run(r) for r in runs if (r / "summary.json").exists()]
    rows.sort(key=lambda r: (r["jointed"], r["s3_mpa"], -r["platen_friction"], r["name"]))

    def seed_of(r):
        return SEED.get((r["s3_mpa"], r["jointed"]), (None,) * 10)

    def label(r):
        platens = "" if r["platen_friction"] == 0.3 else f", platen friction {r['platen_friction']:g}"
        return f"{r['s3_mpa']} MPa {'jointed' if r['jointed'] else 'no joint'} ({r['grains']} grains{platens})"

    print("| test | peak q, seed | peak q, Breccia | strain at peak | cracks | shear cracks |")
    print("|---|---|---|---|---|---|")
    for r in rows:
        seed = seed_of(r)
        print(f"| {label(r)} | {fmt(seed[0], '.1f', ' MPa')} | {r['q_mpa']:.1f} MPa | "
              f"{r['strain_pct']:.2f} % | {r['cracks']} | {r['shear_pct']:.1f} % |")
    print()
    print("| test (Table 4) | kinetic energy, seed | Breccia | boundary work, seed | Breccia | "
          "brittle %, seed | Breccia |")
    print("|---|---|---|---|---|---|---|")
    for r in rows:
        seed = seed_of(r)
        print(f"| {label(r)} | {fmt(seed[1], '.4f', ' J')} | {r['ke']:.4f} J | {fmt(seed[2], '.4f', ' J')} | "
              f"{r['work']:.4f} J | {fmt(seed[3], '.2f')} | {r['brittle_pct']:.2f} |")
    print()
    print("| test (Table 5) | events, seed | Breccia | single-bond %, seed | Breccia | "
          "radiated / work %, seed | Breccia | b, seed | Breccia | D, seed | Breccia D2 (cracks) | "
          "Breccia D (events) |")
    print("|---|---|---|---|---|---|---|---|---|---|---|---|")
    for r in rows:
        seed = seed_of(r)
        print(f"| {label(r)} | {fmt(seed[4], 'd')} | {r['events']} | {fmt(seed[5], 'd')} | "
              f"{r['single_pct']:.0f} | {fmt(seed[7], '.2f')} | {r['radiated_pct']:.3f} | "
              f"{seed[8] or 'n/a'} | {r['b']} | {seed[9] or 'n/a'} | {r['d2']} | {fmt(r['event_d2'], '.2f')} |")
    print()
    print("| test | radiated energy | events by source type (R ratio): tensile / shear / implosive |")
    print("|---|---|---|")
    for r in rows:
        t = r["types"]
        print(f"| {label(r)} | {r['radiated']:.3g} J | {t.get('tensile', 0)} / {t.get('shear', 0)} / "
              f"{t.get('implosive', 0)} |")


if __name__ == "__main__":
    main()
