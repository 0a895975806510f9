"""Seed 003's published macro-properties beside the UCS runs of run.sh and gap.sh.

For each run: the bonds per interior grain, E_t50 and Poisson's ratio as Breccia reports them
(at half the peak, where the sample already cracks and dilates), E and nu fitted on the gauges
over 5-15 % of the peak (elastic), the bulk and shear moduli those imply
(K = E / (3 (1 - 2 nu)), G = E / (2 (1 + nu))), and the UCS.
"""
import glob
import json
import os
import sys
import tomllib

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), "..",
                                "preset-resolution"))
from elastic import bands  # noqa: E402

PUBLISHED = {"E": 14.5, "nu": 0.30, "UCS": 105.0}  # seed 003 Table 2 (PFC3D)


def moduli(e, nu):
    return e / (3 * (1 - 2 * nu)), e / (2 * (1 + nu))


def early_elasticity(folder):
    """E (GPa) and nu on the gauges between 5 and 15 % of the peak deviatoric stress."""
    _, _, e, nu, _, _ = bands(folder)[0][0]
    return (e / 1e9, nu) if e is not None else (float("nan"), float("nan"))


def label(settings):
    """The stiffness convention and bond gap the run used, from its resolved experiment."""
    cfg = tomllib.loads(settings)
    convention = ("ball 4 R E_c in series" if cfg["contact"].get("ball_stiffness")
                  else "deformability")
    return f"{convention}, gap {cfg['sample']['bond_gap_tolerance'] * 1e6:g} um"


def main(root):
    k, g = moduli(PUBLISHED["E"], PUBLISHED["nu"])
    print("| run | bonds per interior grain | E_t50 | nu | E, nu at 5-15 % of peak | K | G | UCS |")
    print("|---|---|---|---|---|---|---|---|")
    print(f"| PFC3D, published | | {PUBLISHED['E']} GPa | {PUBLISHED['nu']} | | {k:.1f} GPa | "
          f"{g:.2f} GPa | {PUBLISHED['UCS']} MPa |")
    runs = [json.load(open(f)) | {"folder": os.path.dirname(f)}
            for f in glob.glob(f"{root}/*/*/summary.json")]
    runs.sort(key=lambda d: (label(d["sample"]["settings"]).split(",")[0],
                             d["sample"]["bonds_per_interior_particle"]))
    for d in runs:
        e, nu = d["youngs_modulus_pa"] / 1e9, d["poisson_ratio"]
        e0, nu0 = early_elasticity(d["folder"])
        k, g = moduli(e0, nu0)
        z = d["sample"]["bonds_per_interior_particle"]
        print(f"| {label(d['sample']['settings'])} | {z:.2f} | {e:.2f} GPa ({e / PUBLISHED['E']:.2f}) | "
              f"{nu:.3f} | {e0:.2f} GPa, {nu0:.3f} | {k:.1f} GPa | {g:.2f} GPa | "
              f"{d['peak_deviatoric_stress_mpa']:.1f} MPa |")


if __name__ == "__main__":
    main(sys.argv[1])
