#!/usr/bin/python3
"""The table of README.md from the run folders run.sh writes.

    /usr/bin/python3 validation/flat-joint-granite-3d/table.py OUT

Each lever has a UCS run (ucs-<lever>) and may have a Brazilian disc (disc-<lever>). For the UCS:
E and nu on the gauges over 5-15 % of the peak (the rock before it cracks), E_t50 and nu at half
the peak (summary.json, what the calibration reads), the UCS, the crack-initiation stress over
it, and the share of the bonds broken
at the peak that have broken by half of it (validation/preset-resolution/elastic.py); for the
disc, the Brazilian strength and UCS/TS.
"""
import glob
import json
import os
import sys

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), "..",
                                "preset-resolution"))
from elastic import bands  # noqa: E402


def latest(out, name):
    found = sorted(glob.glob(os.path.join(out, f"*-{name}")))
    found = [f for f in found if os.path.exists(os.path.join(f, "summary.json"))]
    return found[-1] if found else None


def summary(folder):
    with open(os.path.join(folder, "summary.json")) as f:
        return json.load(f)


def ci_over_ucs(s):
    """The crack-initiation stress (q when the cracks reach 5 % of those at the peak) over the
    peak; the granite's is 0.39 (Eberhardt et al. 1999, from strain gauges and AE)."""
    ci = s.get("crack_initiation_stress_pa")
    return f"{ci / s['peak_deviatoric_stress_pa']:.2f}" if ci else "-"


def main(out):
    levers = []  # in the order run.sh ran them (the folders' time stamps)
    for f in sorted(glob.glob(os.path.join(out, "*-ucs-*"))):
        lever = os.path.basename(f).split("-ucs-", 1)[1]
        if lever not in levers:
            levers.append(lever)
    print("| lever | E, nu at 5-15 % of the peak | E_t50, nu at half the peak | UCS | "
          "sigma_ci / UCS | broken by half the peak | TS | UCS/TS |")
    print("|---|---|---|---|---|---|---|---|")
    for lever in levers:
        ucs = latest(out, "ucs-" + lever)
        if ucs is None:
            continue
        s = summary(ucs)
        table, at_peak, at_half = bands(ucs)
        _, _, e0, nu0, _, _ = table[0]
        disc = latest(out, "disc-" + lever)
        ts = summary(disc)["tensile_strength_mpa"] if disc else None
        ucs_mpa = s["peak_deviatoric_stress_mpa"]
        print(f"| {lever} | {e0 / 1e9:.1f} GPa, {nu0:.3f} | "
              f"{s['youngs_modulus_pa'] / 1e9:.1f} GPa, {s['poisson_ratio']:.3f} | "
              f"{ucs_mpa:.1f} MPa | {ci_over_ucs(s)} | {at_half / max(at_peak, 1):.2f} | "
              + (f"{ts:.2f} MPa | {ucs_mpa / ts:.1f} |" if ts else "- | - |"))


if __name__ == "__main__":
    if len(sys.argv) != 2:
        sys.exit(__doc__)
    main(sys.argv[1])
