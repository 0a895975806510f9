#!/usr/bin/python3
"""Tables of seed 001's sandstone UCS runs beside the seed's (run by hand, not by CI).

    /usr/bin/python3 validation/tumlin-full-size/table.py [--peak-mpa=X] LABEL=RUN_FOLDER[,TIME_LOG] ...

Each argument names a run folder (finished or stopped with a checkpoint) and, optionally, the
output of `/usr/bin/time -v` for the process that ran it (its peak resident memory). Prints two
Markdown tables: the runs' loading, size, speed and memory, and their results beside seed 001's
Tables 4 and 5, each rock's runs beside its own model (E, UCS, critical strain, Poisson's ratio,
broken bonds, fragments and their mass classes, the bond energy at the peak by component and the
kinetic energy). A run stopped after its peak (below 0.9 of it) gives its results so far; one
stopped before it shows how far it went (strain, stress, cracks) and its throughput so far, and
with --peak-mpa its gauge modulus over 40-60 % of that expected peak once it has passed 60 % of it.
"""
import csv
import json
import pathlib
import re
import sys
import tomllib

# Seed 001, Tables 2, 4 and 5 and its text: each sandstone's model (simulation and laboratory).
# The largest fragment's share is its mass over the sample's (the text's grams); the bonds lost
# are read from Fig. 9, for Tumlin alone. Classes: smallest (< 10 % of the largest), middle,
# biggest (> 90 %).
SEEDS = {
    "brenna": {
        "name": "Brenna (BR2)", "grains": 82_266,
        "youngs_modulus_gpa": (20.8, 20.5), "ucs_mpa": (98.0, 99.0),
        "critical_strain_pct": (0.51, 0.52), "poisson_ratio": (0.21, 0.25),
        "fragments": 19_888, "classes": (19_879, 8, 1),
        "largest_fragment_pct": 100.0 * 79.0 / 153.0, "bonds_lost_pct": None,
    },
    "mucharz": {
        "name": "Mucharz (MU1)", "grains": 339_324,
        "youngs_modulus_gpa": (29.2, 31.8), "ucs_mpa": (136.0, 138.0),
        "critical_strain_pct": (0.47, 0.49), "poisson_ratio": (0.19, 0.23),
        "fragments": 23_384, "classes": (23_377, 4, 3),
        "largest_fragment_pct": 100.0 * 48.0 / 113.0, "bonds_lost_pct": None,
    },
    "radkow": {
        "name": "Radków (RAD1)", "grains": 150_653,
        "youngs_modulus_gpa": (23.4, 22.8), "ucs_mpa": (61.0, 60.0),
        "critical_strain_pct": (0.28, 0.29), "poisson_ratio": (0.21, 0.20),
        "fragments": 33_790, "classes": (33_764, 14, 12),
        "largest_fragment_pct": 100.0 * 21.0 / 118.0, "bonds_lost_pct": None,
    },
    "tumlin": {
        "name": "Tumlin (TU2)", "grains": 1_155_851,
        "youngs_modulus_gpa": (27.4, 26.2), "ucs_mpa": (118.0, 115.0),
        "critical_strain_pct": (0.46, 0.51), "poisson_ratio": (0.26, 0.22),
        "fragments": 152_953, "classes": (152_944, 8, 1),
        "largest_fragment_pct": 100.0 * 75.0 / 135.0,
        "bonds_lost_pct": 30.0,  # "almost 30 %" decrease of the bond count (Fig. 9)
    },
}


# --peak-mpa=X: the peak a stopped run is expected to reach; its gauge E is fitted over 40-60 %
# of it, the window of E_t50.
PEAK_MPA = None


def read_json(path):
    try:
        return json.loads(path.read_text())
    except (OSError, ValueError):
        return None


def peak_rss_bytes(time_log):
    if not time_log:
        return None
    m = re.search(r"Maximum resident set size \(kbytes\): (\d+)", pathlib.Path(time_log).read_text())
    return 1024 * int(m.group(1)) if m else None


def history(folder):
    with open(folder / "history.csv", newline="") as f:
        return list(csv.DictReader(f))


def gauge_modulus(rows, low_pa, high_pa):
    """Least-squares slope of q against the gauge's axial strain over rows with q in [low, high]
    (the E_t50 of a run that has not reached its peak yet, for a peak given by hand)."""
    pts = [(float(r["gauge_axial_strain"]), float(r["deviatoric_stress_pa"])) for r in rows
           if low_pa <= float(r["deviatoric_stress_pa"]) <= high_pa]
    if len(pts) < 5:
        return None
    mx = sum(x for x, _ in pts) / len(pts)
    my = sum(y for _, y in pts) / len(pts)
    sxx = sum((x - mx) ** 2 for x, _ in pts)
    return sum((x - mx) * (y - my) for x, y in pts) / sxx if sxx > 0 else None


def past_peak(summary, last_row):
    if not summary or not summary.get("peak_reached"):
        return False
    peak = summary.get("peak_deviatoric_stress_pa") or 0.0
    return peak > 0 and float(last_row["deviatoric_stress_pa"]) < 0.9 * peak


def fmt(v, f="{:.3g}"):
    return "-" if v is None else f.format(v)


def run_record(label, folder, time_log, peak_mpa):
    folder = pathlib.Path(folder)
    manifest = read_json(folder / "manifest.json") or {}
    # An interrupted run's summary analyses the curve so far: its "peak" is where it stopped
    # unless the stress had clearly fallen from a peak before (below 0.9 of it), and its broken
    # bonds and fragments are those at the stop.
    summary = read_json(folder / "summary.json")
    if manifest.get("status") != "complete" and not past_peak(summary, history(folder)[-1]):
        summary = None
    spec = tomllib.loads((folder / "experiment.toml").read_text())
    test, engine = spec.get("test", {}), spec.get("engine", {})
    rows = history(folder)
    row = rows[-1]
    particles = manifest.get("particles") or (summary or {}).get("particles")
    steps = (summary or {}).get("steps") or int(float(row["step"]))
    wall = (summary or {}).get("wall_seconds") or manifest.get("wall_seconds")
    rss = peak_rss_bytes(time_log)
    r = {
        "label": label,
        "rock": spec.get("material", {}).get("preset", "tumlin"),
        "status": manifest.get("status", "?"),
        "grains": particles,
        "bonds": manifest.get("bonds"),
        "height_mm": 1e3 * float(spec.get("sample", {}).get("height", 0.0)),
        "platen_speed": test.get("platen_speed"),
        "elastic_speed": test.get("elastic_speed") or None,
        "slow_down_fraction": test.get("slow_down_broken_fraction"),
        "safety_factor": engine.get("safety_factor"),
        "steps": steps,
        "wall_s": wall,
        "rate": particles * steps / wall if particles and wall else None,
        "bytes_per_grain": rss / particles if rss and particles else None,
        "strain_pct": 100.0 * float(row["axial_strain"]),
        "stress_mpa": 1e-6 * float(row["deviatoric_stress_pa"]),
        "cracks": int(float(row["broken_bonds"])),
        "summary": summary,
        "e_stopped": None if summary or not peak_mpa else
        gauge_modulus(rows, 0.4e6 * peak_mpa, 0.6e6 * peak_mpa),
    }
    return r


def loading_text(r):
    text = f"{r['platen_speed']:g} m/s"
    if r["elastic_speed"]:
        f = r["slow_down_fraction"] or 0.0
        text += f" ({r['elastic_speed']:g} m/s until {100 * f:g} % of the bonds broke)"
    return text + f", S = {r['safety_factor']:g}"


def runs_table(runs):
    out = ["| run | status | grains | bonds | height (mm) | loading | steps | wall time (s) | "
           "particle-steps/s | peak memory (B/grain) | reached: strain (%), q (MPa), cracks |",
           "|---|---|---|---|---|---|---|---|---|---|---|"]
    for r in runs:
        out.append(
            f"| {r['label']} | {r['status']} | {r['grains']:,} | {fmt(r['bonds'], '{:,}')} | "
            f"{r['height_mm']:.2f} | {loading_text(r)} | {r['steps']:,} | {fmt(r['wall_s'], '{:.0f}')} | "
            f"{fmt(r['rate'] and r['rate'] / 1e6, '{:.2f} M')} | {fmt(r['bytes_per_grain'], '{:,.0f}')} | "
            f"{r['strain_pct']:.3f}, {r['stress_mpa']:.1f}, {r['cracks']:,} |")
    return "\n".join(out)


def energy_shares(s):
    peak = (s.get("energy_budget") or {}).get("at_peak") or {}
    bond = peak.get("bond_strain_j") or {}
    total = bond.get("total")
    if not total:
        return "-"
    parts = [(k, bond.get(k, 0.0)) for k in ("tension", "compression", "shear", "bending", "twisting")]
    return ", ".join(f"{k} {100 * v / total:.0f} %" for k, v in parts)


def seed_row(rock):
    sd = SEEDS[rock]
    lost = f"about {sd['bonds_lost_pct']:.0f}" if sd["bonds_lost_pct"] else "-"
    return (
        f"| seed 001, {sd['name']}, {sd['grains']:,} grains, simulation (lab) | "
        f"{sd['youngs_modulus_gpa'][0]} ({sd['youngs_modulus_gpa'][1]}) | "
        f"{sd['ucs_mpa'][0]:.0f} ({sd['ucs_mpa'][1]:.0f}) | {sd['critical_strain_pct'][0]} "
        f"({sd['critical_strain_pct'][1]}) | {sd['poisson_ratio'][0]} ({sd['poisson_ratio'][1]}) | "
        f"{lost} | {sd['fragments']:,} | "
        f"{' / '.join(f'{c:,}' for c in sd['classes'])} | {sd['largest_fragment_pct']:.0f} | "
        "(tension, shear, bending, torsion: Fig. 11) | small (Fig. 11B) |")


def results_table(runs):
    out = ["| run | E_t50 (GPa) | UCS (MPa) | critical strain (%) | Poisson's ratio | broken bonds at "
           "the end (%) | fragments | smallest / middle / biggest | largest fragment (% of mass) | "
           "bond energy at the peak | kinetic / bond energy at the peak |",
           "|---|---|---|---|---|---|---|---|---|---|---|"]
    for rock in sorted({r["rock"] for r in runs}):
        out.append(seed_row(rock))
    for r in runs:
        s = r["summary"]
        if not s:
            e = r["e_stopped"]
            e_text = f"{e / 1e9:.2f} (gauge, 40-60 % of {PEAK_MPA:g} MPa)" if e else "-"
            out.append(f"| {r['label']} | {e_text} | (stopped at {r['strain_pct']:.3f} % strain, "
                       f"q {r['stress_mpa']:.1f} MPa) |" + " |" * 9)
            continue
        fr = s.get("fragments") or {}
        cl = fr.get("classes") or {}
        classes = " / ".join(
            f"{(cl.get(k) or {}).get('count', 0):,}"
            for k in ("smallest_below_0.1_of_largest", "intermediate",
                      "biggest_above_0.9_of_largest"))
        peak = (s.get("energy_budget") or {}).get("at_peak") or {}
        bond_total = ((peak.get("bond_strain_j") or {}).get("total")) or None
        kin = peak.get("kinetic_j")
        label = r["label"]
        if r["status"] != "complete":
            label += (f" (stopped after the peak at {r['stress_mpa']:.1f} MPa; bonds and "
                      "fragments at the stop)")
        out.append(
            f"| {label} | {fmt(s.get('youngs_modulus_pa') and s['youngs_modulus_pa'] / 1e9, '{:.2f}')} | "
            f"{fmt(s.get('peak_deviatoric_stress_mpa'), '{:.1f}')} | "
            f"{fmt(s.get('axial_strain_at_peak') and 100 * s['axial_strain_at_peak'], '{:.3f}')} | "
            f"{fmt(s.get('poisson_ratio'), '{:.3f}')} | "
            f"{fmt(100 * s['bonds_broken'] / s['bonds_initial'], '{:.1f}')} | "
            f"{fmt(fr.get('count'), '{:,}')} | {classes} | "
            f"{fmt(fr.get('largest_fraction_of_total') and 100 * fr['largest_fraction_of_total'], '{:.0f}')} | "
            f"{energy_shares(s)} | {fmt(kin / bond_total if kin is not None and bond_total else None, '{:.2g}')} |")
    return "\n".join(out)


def main(argv):
    if not argv or any("=" not in a for a in argv):
        print(__doc__)
        return 2
    global PEAK_MPA
    if argv and argv[0].startswith("--peak-mpa="):
        PEAK_MPA = float(argv.pop(0).split("=", 1)[1])
    runs = []
    for a in argv:
        label, rest = a.split("=", 1)
        folder, _, time_log = rest.partition(",")
        runs.append(run_record(label, folder, time_log or None, PEAK_MPA))
    print(runs_table(runs))
    print()
    print(results_table(runs))
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
