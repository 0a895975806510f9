#!/usr/bin/env python3
"""The slab-test validation table (seed 001, figure 16B): for each rock's impact sweep in OUT
(validation/slab-tests/run.sh), the cracks at each thickness, scaled by the most any run of that
rock had (the seed's N_frac / N_frac,max) and by the most of all rocks, with the fragments, the
deepest indentation and the energy released by breaking bonds.

Usage: /usr/bin/python3 validation/slab-tests/table.py OUT
"""
import glob
import json
import os
import sys


def main(out):
    rows = []
    for sweep_file in sorted(glob.glob(os.path.join(out, "impact", "*-sweep", "sweep.json"))):
        sweep = json.load(open(sweep_file))
        rock = sweep["experiment"].replace("impact-", "")
        for r in sweep["runs"]:
            summary = os.path.join(os.path.dirname(sweep_file), r["folder"], "summary.json")
            s = json.load(open(summary)) if os.path.exists(summary) else {}
            im = s.get("impact", {})
            rows.append({"rock": rock, "thickness_mm": 1e3 * float(r["value"]),
                         "status": r["status"], "bonds": r.get("bonds_initial"),
                         "cracks": r.get("cracks"), "scaled": r.get("cracks_scaled"),
                         "fragments": r.get("fragments"),
                         "indentation_mm": 1e3 * im.get("max_indentation_m", float("nan")),
                         "released": im.get("energy_shares_of_impact", {}).get(
                             "released_by_breaks", float("nan")),
                         "ucs_mpa": None})
    most = max((r["cracks"] or 0) for r in rows) if rows else 0
    print("| rock | thickness (mm) | bonds | cracks | N / N_max (rock) | N / N_max (all) "
          "| fragments | indentation (mm) | released by breaks |")
    print("|---|---|---|---|---|---|---|---|---|")
    for r in rows:
        print(f"| {r['rock']} | {r['thickness_mm']:g} | {r['bonds']} | {r['cracks']} | "
              f"{r['scaled']:.2f} | {(r['cracks'] or 0) / most:.2f} | {r['fragments']} | "
              f"{r['indentation_mm']:.2f} | {100 * r['released']:.1f} % |")


if __name__ == "__main__":
    if len(sys.argv) != 2:
        sys.exit(__doc__)
    main(sys.argv[1])
