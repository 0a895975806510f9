#!/usr/bin/python3
"""Smooth joints against Jaeger's single-plane-of-weakness theory (run by hand, not by CI).

A prism of the calibrated Berea sandstone cut by one unbounded smooth joint through its centre is
loaded in a triaxial test (lubricated platens, sigma_3 held by servo walls). A cohesionless joint
of friction mu whose normal makes the angle beta with sigma_1 slips when

    sigma_1 - sigma_3 = 2 mu sigma_3 / ((1 - mu cot beta) sin 2 beta)      (Jaeger 1960)

long before the intact rock (about 100 MPa and more) fails. The script runs each (beta, mu),
reads the peak differential stress from summary.json, and writes results.csv and the Markdown
table of README.md.

    /usr/bin/python3 validation/smooth-joint-jaeger/run.py [--breccia build/breccia] [--out DIR]
"""
import argparse
import csv
import json
import math
import pathlib
import subprocess
import sys

HERE = pathlib.Path(__file__).resolve().parent
ROOT = HERE.parent.parent
SIGMA3 = 10e6
CASES = [(40, 0.2), (50, 0.2), (60, 0.2), (70, 0.2), (50, 0.5), (60, 0.5), (70, 0.5)]

EXPERIMENT = """
name = "jaeger-{beta}-{mu}"
[material]
preset = "berea"
[sample]
width = 4e-3
depth = 4e-3
height = 16e-3
radius_min = 0.22e-3
radius_max = 0.36e-3
[contact]
wall_friction = 0.0
[joint]
law = "smooth_joint"
normal_stiffness = 2e13
shear_stiffness = 8e12
friction = {mu}
[[joint.planes]]
dip_deg = {beta}
[test]
kind = "triaxial"
confining_stress = {sigma3}
platen_speed = 0.02
max_strain = 0.02
stop_fraction = 0.8
[output]
plot = false
snapshot_strain_interval = 0
directory = "{runs}"
"""


def jaeger(beta_deg, mu, sigma3):
    b = math.radians(beta_deg)
    denominator = (1.0 - mu / math.tan(b)) * math.sin(2.0 * b)
    return 2.0 * mu * sigma3 / denominator if denominator > 0 else math.inf


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--breccia", default=str(ROOT / "build" / "breccia"))
    ap.add_argument("--out", default="/tmp/breccia-jaeger")
    args = ap.parse_args()
    out = pathlib.Path(args.out)
    out.mkdir(parents=True, exist_ok=True)
    rows = []
    for beta, mu in CASES:
        toml = out / f"jaeger-{beta}-{mu}.toml"
        toml.write_text(EXPERIMENT.format(beta=beta, mu=mu, sigma3=SIGMA3, runs=out / "runs"))
        run = subprocess.run([args.breccia, "run", "--quiet", str(toml)], capture_output=True,
                             text=True, check=False)
        if run.returncode != 0:
            sys.exit(f"{toml}: breccia failed:\n{run.stdout}\n{run.stderr}")
        folder = pathlib.Path(run.stdout.strip().splitlines()[-1])
        s = json.loads((folder / "summary.json").read_text())
        peak = s["peak_deviatoric_stress_pa"]
        predicted = jaeger(beta, mu, SIGMA3)
        rows.append({
            "beta_deg": beta, "mu": mu, "predicted_mpa": predicted / 1e6, "breccia_mpa": peak / 1e6,
            "error": peak / predicted - 1.0, "joints": s.get("joints", {}).get("elements", 0),
            "joint_slip_j": s["energy"]["joint_slip_j"], "cracks": s["bonds_broken"],
            "status": s["status"], "folder": str(folder)})
        print(f"beta {beta} mu {mu}: Jaeger {predicted / 1e6:.2f} MPa, Breccia {peak / 1e6:.2f} MPa "
              f"({rows[-1]['error']:+.1%}), {rows[-1]['joints']} joints, {s['bonds_broken']} cracks",
              flush=True)
    with open(HERE / "results.csv", "w", newline="") as f:
        w = csv.DictWriter(f, fieldnames=list(rows[0].keys()))
        w.writeheader()
        w.writerows(rows)
    print("\n| beta (deg) | mu | Jaeger (MPa) | Breccia peak (MPa) | error | joint pairs | cracks |")
    print("|---|---|---|---|---|---|---|")
    for r in rows:
        print(f"| {r['beta_deg']} | {r['mu']} | {r['predicted_mpa']:.2f} | {r['breccia_mpa']:.2f} | "
              f"{r['error']:+.1%} | {r['joints']} | {r['cracks']} |")


if __name__ == "__main__":
    main()
