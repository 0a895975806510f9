#!/usr/bin/python3
"""Do the microcracks of a jointed triaxial run gather on the joint? (run by hand, not by CI)

For each run folder, reads the joint plane from experiment.toml (the first [[joint.planes]]:
centre from the sample's bounding-box centre, dip_deg and dip_direction_deg or normal, radius)
and the sample's grain positions from the cached geometry file named in manifest.json, then
counts the cracks (cracks.csv) and AE events (events.csv) whose position lies within a slab of
half-width w (default one largest grain diameter) of the joint disc, and of the disc's whole
plane (where the rock bridges beyond its rim lie). The expected share for a uniform spread is
the share of grains within the same slab, so the "concentration" is the ratio of the two. An
intact run's
folder can be given with --plane-from JOINTED_FOLDER, to use the same slab as a control.

    /usr/bin/python3 localisation.py RUN_FOLDER... [--plane-from FOLDER] [--half-width-m W]
"""
import argparse
import csv
import json
import math
import pathlib
import tomllib


def plane_of(folder):
    exp = tomllib.loads((folder / "experiment.toml").read_text())
    planes = exp.get("joint", {}).get("planes", [])
    if not planes:
        raise SystemExit(f"{folder}: experiment.toml has no [[joint.planes]]")
    p = planes[0]
    if "normal" in p and any(p["normal"]):
        n = p["normal"]
    else:
        dip = math.radians(p.get("dip_deg", 0.0))
        dd = math.radians(p.get("dip_direction_deg", 90.0))
        # Dip direction clockwise from +y: the plane's downward side faces (sin dd, cos dd, 0).
        n = [math.sin(dip) * math.sin(dd), math.sin(dip) * math.cos(dd), math.cos(dip)]
    norm = math.sqrt(sum(c * c for c in n))
    return [c / norm for c in n], p.get("centre", [0.0, 0.0, 0.0]), p.get("radius", 0.0)


def grains(folder):
    manifest = json.loads((folder / "manifest.json").read_text())
    rows = []
    with open(manifest["sample"]["cached_file"]) as f:
        for line in f:
            w = line.split()
            if len(w) >= 5 and w[0].isdigit():
                rows.append(tuple(float(v) for v in w[1:5]))
    return rows


def near(point, centre, n, radius, half_width):
    rel = [point[k] - centre[k] for k in range(3)]
    dn = sum(rel[k] * n[k] for k in range(3))
    in_plane = math.sqrt(max(0.0, sum(r * r for r in rel) - dn * dn))
    return abs(dn) <= half_width and (radius <= 0 or in_plane <= radius)


def positions(path, xyz=("x_m", "y_m", "z_m")):
    if not path.exists():
        return []
    with open(path) as f:
        return [tuple(float(r[c]) for c in xyz) for r in csv.DictReader(f)]


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("runs", nargs="+", type=pathlib.Path)
    ap.add_argument("--plane-from", type=pathlib.Path)
    ap.add_argument("--half-width-m", type=float, default=0.0)
    a = ap.parse_args()
    print("| run | slab | cracks in it | events in it | grains in it | crack concentration | "
          "event concentration |")
    print("|---|---|---|---|---|---|---|")
    for run in a.runs:
        n, offset, radius = plane_of(a.plane_from or run)
        g = grains(run)
        lo = [min(p[k] - p[3] for p in g) for k in range(3)]
        hi = [max(p[k] + p[3] for p in g) for k in range(3)]
        centre = [0.5 * (lo[k] + hi[k]) + offset[k] for k in range(3)]
        w = a.half_width_m or 2.0 * max(p[3] for p in g)
        cracks = positions(run / "cracks.csv")
        events = positions(run / "events.csv")
        for label, r in (("disc", radius), ("plane", 0.0)):
            share = sum(near(p, centre, n, r, w) for p in g) / len(g)
            c_on = sum(near(p, centre, n, r, w) for p in cracks)
            e_on = sum(near(p, centre, n, r, w) for p in events)
            c_share = c_on / len(cracks) if cracks else float("nan")
            e_share = e_on / len(events) if events else float("nan")
            print(f"| {run.name} | {label} +-{1e3 * w:.2f} mm | {c_on} of {len(cracks)} | "
                  f"{e_on} of {len(events)} | {100 * share:.0f} % | {c_share / share:.2f} | "
                  f"{e_share / share:.2f} |")


if __name__ == "__main__":
    main()
