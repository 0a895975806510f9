#!/usr/bin/python3
"""The quasi-static monitors of a stopped compression run, row by row, read from its checkpoint.

    quality_rows.py RUN_FOLDER [--peak-mpa=X] [--from-mpa=A --to-mpa=B]

The run's summary judges the kinetic-energy ratio (E'_kin over the stored strain energy,
docs/physics.md 6.1) and the platen-force imbalance over the rows between a tenth of the peak
and the peak. A stopped run does not know its peak yet, so its interim verdict uses the largest
stress so far; this script gives the per-row series (kept in the checkpoint's loop section, right
after its header) so that the verdict can be taken against the peak expected from a smaller
sample (--peak-mpa). Runs since history.csv's kinetic_fluctuating_j column need no checkpoint:
that column over the strain energy columns is the same ratio.
"""
import csv
import os
import struct
import sys


def read_loop(path):
    with open(path, "rb") as f:
        def u64():
            return struct.unpack("<Q", f.read(8))[0]

        def text():
            return f.read(u64())

        def doubles():
            n = u64()
            return struct.unpack(f"<{n}d", f.read(8 * n))

        if text() != b"breccia-checkpoint":
            sys.exit(f"{path}: not a Breccia checkpoint")
        fmt = struct.unpack("<I", f.read(4))[0]
        version, commit = text().decode(), text().decode()
        text()  # the resolved experiment
        if text() != b"loop":
            sys.exit(f"{path}: format {fmt} has no loop section after its header")
        series = [doubles() for _ in range(7)]
        f.read(8)  # confining stress
        imbalance, ke_ratio = doubles(), doubles()
    return {"format": fmt, "version": version, "commit": commit, "strain": series[0],
            "deviatoric": series[1], "broken": series[6], "imbalance": imbalance,
            "ke_ratio": ke_ratio}


def main(argv):
    opts = dict(a[2:].split("=", 1) for a in argv[1:] if a.startswith("--"))
    folders = [a for a in argv[1:] if not a.startswith("--")]
    if len(folders) != 1:
        sys.exit(__doc__)
    folder = folders[0]
    q = read_loop(os.path.join(folder, "checkpoint.bin"))
    steps = [int(r["step"]) for r in csv.DictReader(open(os.path.join(folder, "history.csv")))]
    dev = q["deviatoric"]
    peak = float(opts.get("peak-mpa", max(dev) / 1e6)) * 1e6
    print(f"checkpoint format {q['format']}, breccia {q['version']} ({q['commit']}), "
          f"{len(dev)} rows; peak taken as {peak / 1e6:.1f} MPa")
    judged = [k for k in range(len(dev)) if dev[k] >= 0.1 * peak and dev[k] <= peak]
    if judged:
        worst = max(judged, key=lambda k: q["ke_ratio"][k])
        print(f"rows above a tenth of the peak: kinetic/strain energy at most "
              f"{q['ke_ratio'][worst]:.3g} (step {steps[worst]}, q {dev[worst] / 1e6:.1f} MPa), "
              f"imbalance at most {max(q['imbalance'][k] for k in judged):.3g}")
        intact = [k for k in judged if q["broken"][k] == 0]
        if intact:
            print(f"  of them before the first crack: kinetic/strain energy at most "
                  f"{max(q['ke_ratio'][k] for k in intact):.3g}")
    lo = float(opts.get("from-mpa", 0)) * 1e6
    hi = float(opts.get("to-mpa", 0)) * 1e6
    if hi > lo:
        print("step, q (MPa), broken bonds, kinetic/strain energy, imbalance")
        for k in range(len(dev)):
            if lo <= dev[k] <= hi:
                print(f"{steps[k]}, {dev[k] / 1e6:.1f}, {q['broken'][k]:.0f}, "
                      f"{q['ke_ratio'][k]:.3g}, {q['imbalance'][k]:.3g}")


if __name__ == "__main__":
    main(sys.argv)
