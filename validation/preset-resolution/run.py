#!/usr/bin/python3
"""Resolution table of the presets: E, nu and UCS of each preset's own UCS test on samples of
three sizes with the same grains.

Each run is the calibration file's [experiment] (the test the preset was calibrated and verified
with) with the preset's calibrated [contact], [bond] and density in place of the start values, the
sample scaled to the width (its shape kept) at the calibration's platen speed (as quasi-static as
the calibration), and the packing seed set. The runs are independent processes; a run
folder that is complete is reused and one that was stopped is resumed from its checkpoint, so
the study can be stopped and run again to continue.

    validation/preset-resolution/run.py OUT [--breccia build/breccia] [--jobs 2]
        [--presets berea,coal] [--sizes 4,6,9] [--seeds 4:1,2,3 6:1,2 9:1]

The default presets are the 3D ones (their samples are 6 mm wide or 8 mm, brenna); the 2D ones
want their own widths (--presets berea_2d,... --sizes 1.9,3.8,7.6).

writes OUT/<preset>/<size>mm-seed<n>/ (the experiment file and the run folder) and OUT/results.csv
(one row a run); table.py turns that into the tables of the README.
"""
import argparse
import csv
import fcntl
import json
import subprocess
import sys
import time
import tomllib
from concurrent.futures import ThreadPoolExecutor
from pathlib import Path

ROOT = Path(__file__).resolve().parents[2]


def toml_value(v):
    if isinstance(v, bool):
        return "true" if v else "false"
    if isinstance(v, (int, float)):
        return repr(v)
    if isinstance(v, str):
        return json.dumps(v)
    if isinstance(v, list):
        return "[" + ", ".join(toml_value(x) for x in v) + "]"
    raise TypeError(f"cannot write {v!r} as TOML")


def toml_text(table):
    """A table of scalars and one level of sub-tables, the shape of an experiment file."""
    lines = [f"{k} = {toml_value(v)}" for k, v in table.items() if not isinstance(v, dict)]
    for name, sub in table.items():
        if isinstance(sub, dict):
            lines.append(f"\n[{name}]")
            lines += [f"{k} = {toml_value(v)}" for k, v in sub.items()]
    return "\n".join(lines) + "\n"


def write_toml(table, path):
    path.write_text(toml_text(table))


def presets_3d():
    out = []
    for record in sorted((ROOT / "materials").glob("*/record.json")):
        r = json.loads(record.read_text())
        if r["dimension"] == 3:
            out.append(r["name"])
    return out


def experiment_for(preset, size_mm, seed):
    """The calibration's UCS experiment with the calibrated micro-parameters, its sample scaled
    to a width of size_mm (the same shape and grains). The platen speed stays: the platens'
    speed over the grains' wave speed sets how far a test is from quasi-static (the overstress
    of inertia goes as rho c v, and a test reaches its peak after eps_peak c / v wave transits,
    whatever the height), so every size is as quasi-static as the calibration. The strain rate
    falls as the sample grows, which no rate-independent law feels."""
    record = json.loads((ROOT / "materials" / preset / "record.json").read_text())
    calibration = tomllib.loads((ROOT / record["calibration_file"]).read_text())
    material = tomllib.loads((ROOT / "materials" / preset / "material.toml").read_text())
    e = calibration["experiment"]
    e["name"] = f"{preset}-{size_mm:g}mm-seed{seed}"
    e["material"] = {"preset": "custom"}
    # The experiment's own contact keys (the platen friction) stay; the calibrated ones win.
    e["contact"] = {**e.get("contact", {}), **material["contact"]}
    e["bond"] = material["bond"]
    sample = e["sample"]
    sample["density"] = material["sample"]["density"]
    scale = size_mm * 1e-3 / sample["width"]
    for side in ("width", "depth", "height"):
        if side in sample:
            sample[side] *= scale
    e["engine"]["seed"] = seed
    out = e.setdefault("output", {})
    out.update(plot=False, snapshot_strain_interval=0.0)
    e.setdefault("ae", {})["moment_tensors"] = False
    return e


def run_folder(where):
    folders = sorted(p for p in where.glob("2*") if p.is_dir())
    return folders[-1] if folders else None


def complete(folder):
    try:
        return json.loads((folder / "manifest.json").read_text())["status"] == "complete"
    except (OSError, ValueError, KeyError):
        return False


def claim(where):
    """An open lock on the folder's experiment, or None when another call of the study holds it
    (two calls on one OUT share the runs out). The system lets go of the lock when the holder
    ends, however it ends."""
    lock = open(where / "lock", "w")
    try:
        fcntl.flock(lock, fcntl.LOCK_EX | fcntl.LOCK_NB)
    except BlockingIOError:
        lock.close()
        return None
    return lock


def one_run(breccia, out, preset, size_mm, seed):
    where = out / preset / f"{size_mm:g}mm-seed{seed}"
    where.mkdir(parents=True, exist_ok=True)
    folder = run_folder(where)
    took = None
    if folder is None or not complete(folder):
        lock = claim(where)
        if lock is None:
            print(f"{preset} {size_mm:g} mm seed {seed}: another call is running it",
                  file=sys.stderr)
            return None
        with lock:
            took, folder = run_experiment(breccia, where, preset, size_mm, seed)
        if folder is None:
            return None
    return row(folder, preset, size_mm, seed, took)


def run_experiment(breccia, where, preset, size_mm, seed):
    """Runs the experiment in `where`: its wall time and run folder, or (None, None) when it
    failed. A run an interrupted call left is resumed from its checkpoint; one without a
    checkpoint, or of another experiment, is removed and run again."""
    experiment = where / "experiment.toml"
    wanted = experiment_for(preset, size_mm, seed)
    partial = resumable(where, wanted)
    for stale in where.glob("2*"):
        if stale.is_dir() and stale != partial and not complete(stale):
            subprocess.run(["rm", "-rf", str(stale)], check=True)
    write_toml(wanted, experiment)
    if partial is not None:
        command = [breccia, "resume", str(partial), "--quiet", "--threads", "1"]
    else:
        command = [breccia, "run", str(experiment), "--quiet", "--threads", "1",
                   "--output", str(where)]
    t0 = time.time()
    with open(where / "run.log", "a" if partial else "w") as log:
        rc = subprocess.run(command, stdout=log, stderr=log).returncode
    took = time.time() - t0
    folder = run_folder(where)
    if rc != 0 or folder is None or not complete(folder):
        print(f"{preset} {size_mm:g} mm seed {seed}: run failed (see {where}/run.log)",
              file=sys.stderr)
        return None, None
    return (None if partial else took), folder


def resumable(where, wanted):
    """The incomplete run folder in `where` that a checkpoint can finish, when the experiment
    file beside it is the one this call would write (a study changed since must start over)."""
    folder = run_folder(where)
    experiment = where / "experiment.toml"
    if folder is None or complete(folder) or not (folder / "checkpoint.bin").exists():
        return None
    try:
        if tomllib.loads(experiment.read_text()) != tomllib.loads(toml_text(wanted)):
            return None
    except (OSError, tomllib.TOMLDecodeError):
        return None
    return folder


def row(folder, preset, size_mm, seed, took):
    s = json.loads((folder / "summary.json").read_text())
    m = json.loads((folder / "manifest.json").read_text())
    broken = s.get("bonds_broken") or 0
    return {
        "preset": preset, "size_mm": size_mm, "seed": seed,
        "particles": s.get("particles"),
        "youngs_modulus_pa": s.get("youngs_modulus_pa"),
        "poisson_ratio": s.get("poisson_ratio"),
        "uniaxial_strength_pa": s.get("peak_deviatoric_stress_pa") if s.get("peak_reached") else None,
        "shear_crack_fraction": (s.get("cracks_shear", 0) / broken) if broken else None,
        "largest_end_quarter_share": (s.get("crack_pattern") or {}).get("largest_end_quarter_share"),
        "wall_s": took if took is not None else m.get("wall_seconds"),
        "commit": m.get("commit"),
    }


def parse_seeds(items, sizes):
    seeds = {size: [1] for size in sizes}
    for item in items or []:
        size, _, values = item.partition(":")
        seeds[float(size)] = [int(v) for v in values.split(",")]
    return seeds


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("out", type=Path)
    ap.add_argument("--breccia", default=str(ROOT / "build" / "breccia"))
    ap.add_argument("--jobs", type=int, default=2)
    ap.add_argument("--presets", default="")
    ap.add_argument("--sizes", default="4,6,9", help="sample widths in mm")
    ap.add_argument("--seeds", nargs="*", default=["4:1,2,3", "6:1,2", "9:1"],
                    help="SIZE:SEED,SEED... (a size not named: seed 1)")
    a = ap.parse_args()
    presets = [p for p in a.presets.split(",") if p] or presets_3d()
    sizes = [float(s) for s in a.sizes.split(",")]
    seeds = parse_seeds(a.seeds, sizes)
    # The largest runs first, so that the pool does not end on one long run.
    runs = [(p, size, seed) for size in sorted(sizes, reverse=True) for p in presets
            for seed in seeds[size]]
    with ThreadPoolExecutor(a.jobs) as pool:
        rows = list(pool.map(lambda r: one_run(a.breccia, a.out, *r), runs))
    done = sum(1 for r in rows if r)
    # results.csv holds every complete run under OUT, this call's and earlier calls'.
    every = []
    for where in sorted(a.out.glob("*/*mm-seed*")):
        folder = run_folder(where)
        name = where.name.split("mm-seed")
        if folder is not None and complete(folder) and len(name) == 2:
            every.append(row(folder, where.parent.name, float(name[0]), int(name[1]), None))
    if every:
        with open(a.out / "results.csv", "w", newline="") as f:
            w = csv.DictWriter(f, fieldnames=list(every[0].keys()))
            w.writeheader()
            w.writerows(sorted(every, key=lambda r: (r["preset"], r["size_mm"], r["seed"])))
    print(f"{done} of this call's {len(runs)} runs; {len(every)} in {a.out / 'results.csv'}")
    return 0 if done == len(runs) else 1


if __name__ == "__main__":
    sys.exit(main())
