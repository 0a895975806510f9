#!/usr/bin/python3
"""Does the acoustic-emission catalogue's magnitude range grow with the sample? Per preset and
sample width of the study run.py made: the events, those above the completeness magnitude, M_c,
the b-value and the span from M_c to the largest event, averaged over the packings run.

    validation/preset-resolution/magnitudes.py OUT

The study's runs keep moment tensors off (run.py), so the magnitudes are energy magnitudes,
M_E = 2/3 log10(E) - 3.2 of each event's released bond energy (docs/analysis.md §5.3); M_c is the
maximum curvature of bins 0.1 wide plus 0.2 and b Aki's maximum-likelihood estimate (§5.1-5.2),
as the run's own analysis computes them. A run with fewer than 50 events above M_c is left out.
Prints Markdown.
"""
import csv
import json
import math
import statistics
import sys
from collections import defaultdict
from pathlib import Path

from run import complete, run_folder

MIN_EVENTS = 50


def energy_magnitudes(folder):
    with open(folder / "events.csv") as f:
        energies = [float(row["energy_j"]) for row in csv.DictReader(f)]
    return [2.0 / 3.0 * math.log10(e) - 3.2 for e in energies if e > 0.0]


def catalogue(folder):
    """Events, events above M_c, M_c, b and the span M_max - M_c; None below MIN_EVENTS."""
    m = energy_magnitudes(folder)
    if not m:
        return None
    counts = defaultdict(int)
    for x in m:
        counts[round(x / 0.1)] += 1
    top = max(counts.items(), key=lambda kv: (kv[1], -kv[0]))[0]
    mc = top * 0.1 + 0.2
    above = [x for x in m if x >= mc - 1e-9]
    if len(above) < MIN_EVENTS:
        return None
    b = math.log10(math.e) / (statistics.fmean(above) - mc)
    return len(m), len(above), mc, b, max(m) - mc


def main(out):
    rows = defaultdict(list)
    for where in sorted(out.glob("*/*mm-seed*")):
        folder = run_folder(where)
        if folder is None or not complete(folder):
            continue
        c = catalogue(folder)
        if c is None:
            continue
        particles = json.loads((folder / "summary.json").read_text())["particles"]
        size = float(where.name.split("mm-seed")[0])
        rows[(where.parent.name, size)].append((particles,) + c)
    print("| preset | width | grains | packings | events | above M_c | M_c | b | M_max - M_c |")
    print("|---|---|---|---|---|---|---|---|---|")
    for (preset, size), runs in sorted(rows.items()):
        mean = [statistics.fmean(col) for col in zip(*runs)]
        print(f"| `{preset}` | {size:g} mm | {mean[0]:,.0f} | {len(runs)} | {mean[1]:.0f} | "
              f"{mean[2]:.0f} | {mean[3]:.2f} | {mean[4]:.2f} | {mean[5]:.2f} |")
    return 0


if __name__ == "__main__":
    if len(sys.argv) != 2:
        sys.exit(__doc__)
    sys.exit(main(Path(sys.argv[1])))
