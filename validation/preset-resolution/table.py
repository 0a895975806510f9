#!/usr/bin/python3
"""The resolution tables of the study run.py made: per preset and sample width, the mean E, nu and
UCS over the packings run, and how far E and the UCS move from their values on the width the
preset was calibrated on (6 mm for the 3D presets, 8 mm for brenna, 1.9 or 3.8 mm in 2D).

    validation/preset-resolution/table.py OUT/results.csv [--tolerance 0.10]

prints Markdown: one summary table (the largest move of E and the UCS over the sizes, and the
verdict against the tolerance) and one table a preset.
"""
import argparse
import csv
import json
import statistics
import sys
import tomllib
from collections import defaultdict
from pathlib import Path

ROOT = Path(__file__).resolve().parents[2]


def calibration_size_mm(preset):
    record = json.loads((ROOT / "materials" / preset / "record.json").read_text())
    c = tomllib.loads((ROOT / record["calibration_file"]).read_text())
    return c["experiment"]["sample"]["width"] * 1e3


def number(v):
    return float(v) if v not in ("", None) else None


def mean_sd(values):
    values = [v for v in values if v is not None]
    if not values:
        return None, None, 0
    return statistics.fmean(values), (statistics.stdev(values) if len(values) > 1 else None), len(values)


def fmt(m, sd, n, scale, digits):
    if m is None:
        return "-"
    text = f"{m / scale:.{digits}f}"
    if sd is not None:
        text += f" +/- {sd / scale:.{digits}f}"
    return text + f" ({n})"


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("results", type=Path)
    ap.add_argument("--tolerance", type=float, default=0.10)
    a = ap.parse_args()
    runs = defaultdict(list)
    with open(a.results) as f:
        for r in csv.DictReader(f):
            runs[(r["preset"], float(r["size_mm"]))].append(r)
    presets = sorted({p for p, _ in runs})
    summary = ["| preset | grains | E move | UCS move | within 10 % |", "|---|---|---|---|---|"]
    detail = []
    for p in presets:
        sizes = sorted(s for q, s in runs if q == p)
        ref = calibration_size_mm(p)
        stats = {}
        for s in sizes:
            rs = runs[(p, s)]
            stats[s] = {k: mean_sd([number(r[k]) for r in rs])
                        for k in ("particles", "youngs_modulus_pa", "poisson_ratio",
                                  "uniaxial_strength_pa", "shear_crack_fraction", "wall_s")}
        if ref not in stats:
            print(f"{p}: no run on its calibration size ({ref:g} mm)", file=sys.stderr)
            continue
        moves = {}
        for k in ("youngs_modulus_pa", "uniaxial_strength_pa"):
            r0 = stats[ref][k][0]
            moves[k] = [(stats[s][k][0] - r0) / r0 for s in sizes
                        if s != ref and stats[s][k][0] is not None and r0]
        worst = {k: max(v, key=abs) if v else None for k, v in moves.items()}
        ok = all(w is not None and abs(w) <= a.tolerance for w in worst.values())
        grains = " / ".join(f"{stats[s]['particles'][0]:,.0f}" for s in sizes)
        summary.append(
            f"| `{p}` | {grains} | {worst['youngs_modulus_pa']:+.1%} | "
            f"{worst['uniaxial_strength_pa']:+.1%} | {'yes' if ok else '**no**'} |")
        detail += [f"\n`{p}` (calibrated on {ref:g} mm):\n",
                   "| width | grains | E (GPa) | nu | UCS (MPa) | shear cracks | wall (s, 1 thread) |",
                   "|---|---|---|---|---|---|---|"]
        for s in sizes:
            st = stats[s]
            detail.append(
                f"| {s:g} mm | {st['particles'][0]:,.0f} | "
                f"{fmt(*st['youngs_modulus_pa'], 1e9, 2)} | {fmt(*st['poisson_ratio'], 1, 3)} | "
                f"{fmt(*st['uniaxial_strength_pa'], 1e6, 1)} | "
                f"{fmt(*st['shear_crack_fraction'], 0.01, 1)} % | {st['wall_s'][0]:.0f} |")
    print("\n".join(summary))
    print("\n".join(detail))
    return 0


if __name__ == "__main__":
    sys.exit(main())
