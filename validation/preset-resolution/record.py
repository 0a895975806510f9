#!/usr/bin/python3
"""Writes the study's runs into the presets' records: materials/<preset>/record.json gets a
"resolution" block (each sample size with its packings' E, nu, UCS, shear share, grains and wall
time), which `breccia materials` turns into the resolution tables of docs/materials.md.

    validation/preset-resolution/record.py OUT [--presets berea,coal]

Only complete run folders count; a preset whose calibration size has no complete run is left
as it is. Rebuild and regenerate the docs afterwards:
    ninja -C build breccia && build/breccia materials --output docs/materials.md
"""
import argparse
import json
import re
import sys
import tomllib
from collections import defaultdict
from pathlib import Path

from run import complete, run_folder

ROOT = Path(__file__).resolve().parents[2]
FOLDER = re.compile(r"^([0-9.]+)mm-seed([0-9]+)$")


def complete_runs(out, preset):
    """(width in mm, seed, summary, manifest) of every complete run of the preset."""
    for where in sorted((out / preset).glob("*mm-seed*")):
        m = FOLDER.match(where.name)
        folder = run_folder(where)
        if not m or folder is None or not complete(folder):
            continue
        summary = json.loads((folder / "summary.json").read_text())
        manifest = json.loads((folder / "manifest.json").read_text())
        yield float(m.group(1)), int(m.group(2)), summary, manifest


def resolution_block(out, preset):
    record = json.loads((ROOT / "materials" / preset / "record.json").read_text())
    calibration = tomllib.loads((ROOT / record["calibration_file"]).read_text())
    cal = calibration["experiment"]["sample"]
    sizes = defaultdict(list)
    commits, machines = set(), set()
    for width_mm, seed, s, m in complete_runs(out, preset):
        sizes[width_mm].append((seed, s, m))
        commits.add(m.get("commit"))
        machines.add(m.get("machine"))
    reference = cal["width"]
    if not any(abs(w * 1e-3 - reference) < 1e-9 for w in sizes):
        return None
    samples = []
    for width_mm in sorted(sizes):
        runs = sorted(sizes[width_mm], key=lambda r: r[0])
        scale = width_mm * 1e-3 / cal["width"]
        entry = {"width_m": width_mm * 1e-3, "height_m": cal["height"] * scale}
        if "depth" in cal:
            entry["depth_m"] = cal["depth"] * scale
        entry["seeds"] = [seed for seed, _, _ in runs]
        entry["particles"] = [s["particles"] for _, s, _ in runs]
        entry["youngs_modulus"] = [s.get("youngs_modulus_pa") for _, s, _ in runs]
        entry["poisson_ratio"] = [s.get("poisson_ratio") for _, s, _ in runs]
        entry["uniaxial_strength"] = [
            s["peak_deviatoric_stress_pa"] if s.get("peak_reached") else None for _, s, _ in runs]
        entry["shear_crack_fraction"] = [
            s.get("cracks_shear", 0) / s["bonds_broken"] if s.get("bonds_broken") else None
            for _, s, _ in runs]
        entry["wall_seconds"] = [m.get("wall_seconds") for _, _, m in runs]
        samples.append(entry)
    return {
        "study": "validation/preset-resolution/run.py",
        "commits": sorted(c for c in commits if c),
        "machines": sorted(x for x in machines if x),
        "reference_width_m": reference,
        "loading": "the calibration's platen speed and density scaling at every size",
        "samples": samples,
    }


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("out", type=Path)
    ap.add_argument("--presets", default="")
    a = ap.parse_args()
    presets = [p for p in a.presets.split(",") if p] or sorted(
        p.name for p in a.out.iterdir() if (ROOT / "materials" / p.name / "record.json").exists())
    for preset in presets:
        block = resolution_block(a.out, preset)
        if block is None:
            print(f"{preset}: no complete run on its calibration size; record unchanged",
                  file=sys.stderr)
            continue
        path = ROOT / "materials" / preset / "record.json"
        record = json.loads(path.read_text())
        record["resolution"] = block
        path.write_text(json.dumps(record, indent=2, sort_keys=True, ensure_ascii=False) + "\n")
        n = sum(len(s["seeds"]) for s in block["samples"])
        print(f"{preset}: {len(block['samples'])} sizes, {n} runs -> {path.relative_to(ROOT)}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
