#!/usr/bin/python3
"""The same UCS in ESyS-Particle 2.3.5 and in Breccia with `brittle_beam` (run by hand, not by CI).

1. make_sample.py packs a GenGeo cylinder (10 x 20 mm, radii 0.25-1 mm) and bonds touching grains.
2. esys_ucs.py loads it in ESyS-Particle (mpirun -np 2 esysparticle: one master, one worker).
3. Breccia loads the same file with the same micro-parameters, time step, damping and platen
   motion (the experiment below).
4. Both histories are reduced the same way: stress = mean platen force / (pi R^2) with R the
   cylinder radius given to GenGeo, strain = platen approach / initial platen gap; E is the slope
   of a straight-line fit of the pre-peak curve between 40 and 60 % of the peak (ISRM E_t50).
   The table goes to results.md (pasted into README.md) and the curves to curves.csv.

    /usr/bin/python3 validation/esys-brittle-beam/run.py [--out DIR] [--breccia build/breccia]
        [--platen-speed 0.05] [--cohesion 20e6] [--skip-esys] [--skip-breccia]
Needs Debian's esys-particle, python3-gengeo and openmpi (mpirun).
"""
import argparse
import csv
import json
import math
import pathlib
import shutil
import subprocess
import sys
import time

HERE = pathlib.Path(__file__).resolve().parent
ROOT = HERE.parent.parent

# Shared micro-parameters (SI). ESyS's RotFriction normalK is pi E_c and its wall normalK is E_c
# (see esys_ucs.py); the beam parameters are the same numbers in both codes.
PARAMS = {
    "density": 2650.0,
    "contact_modulus": 20e9,
    "stiffness_ratio": 2.5,
    "friction": 0.6,
    "bond_modulus": 20e9,
    "bond_poisson_ratio": 0.25,
    "bond_cohesion": 20e6,
    "bond_tan_friction": 1.0,
    "local_damping": 0.7,
    "time_step": 1.2e-8,
    "ramp_time": 1e-4,
    "stop_fraction": 0.6,
    "max_strain": 0.02,
    "radius": 0.005,
    "record_interval": 200,
}

EXPERIMENT = """
name = "esys-brittle-beam"
[engine]
threads = 1
time_step = {time_step}
density_scaling = 1
local_damping = {local_damping}
energy_interval = 200
[material]
preset = "custom"
[sample]
source = "gengeo"
file = "{geometry}"
shape = "cylinder"
diameter = {diameter}
height = 0.02
density = {density}
[contact]
law = "linear"
wall_friction = 0.0
modulus = {contact_modulus}
stiffness_ratio = {stiffness_ratio}
friction = {friction}
[bond]
law = "brittle_beam"
modulus = {bond_modulus}
poisson_ratio = {bond_poisson_ratio}
cohesion = {bond_cohesion}
tan_friction = {bond_tan_friction}
tensile_cutoff = 1.0
bending_factor = 0.5
moment_factor = 1.0
twist_factor = 1.0
min_radius = false
contact_while_bonded = false
[test]
kind = "ucs"
platen_speed = {platen_speed}
ramp_time = {ramp_time}
max_strain = {max_strain}
stop_fraction = {stop_fraction}
[output]
plot = false
progress = false
snapshot_strain_interval = 0
history_interval = {record_interval}
directory = "{runs}"
"""


def gap_extent(geo):
    zmin, zmax, section = math.inf, -math.inf, False
    for line in geo.read_text().splitlines():
        w = line.split()
        if w and w[0] == "BeginParticles":
            section = True
        elif w and w[0] == "EndParticles":
            break
        elif section and len(w) == 6:
            z, r = float(w[2]), float(w[3])
            zmin, zmax = min(zmin, z - r), max(zmax, z + r)
    return zmax - zmin


def run_esys(out, geo, p):
    d = out / "esys"
    d.mkdir(parents=True, exist_ok=True)
    gap0 = gap_extent(geo)
    travel = 0.5 * p["max_strain"] * gap0
    steps = int(math.ceil((travel / p["platen_speed"] + 0.5 * p["ramp_time"]) / p["time_step"]))
    steps += p["record_interval"] - steps % p["record_interval"]
    cfg = dict(p, out_dir=str(d), geometry=str(geo), steps=steps)
    (d / "config.json").write_text(json.dumps(cfg, indent=1))
    t0 = time.time()
    with open(d / "esys.log", "w") as log:
        subprocess.run(["mpirun", "--allow-run-as-root", "--oversubscribe", "-np", "2",
                        "esysparticle", str(HERE / "esys_ucs.py"), str(d / "config.json")],
                       check=True, stdout=log, stderr=subprocess.STDOUT, cwd=d)
    (d / "wall_time_s").write_text(f"{time.time() - t0:.1f}\n")
    return read_esys(out, geo, p)


def read_esys(out, geo, p):
    d = out / "esys"
    gap0 = gap_extent(geo)
    wall = float((d / "wall_time_s").read_text())
    rows = list(csv.DictReader(open(d / "history.csv")))
    bonds = [float(line.split()[0]) for line in open(d / "bonds.dat") if line.strip()]
    curve = []
    for k, r in enumerate(rows):
        f = 0.5 * (float(r["force_bottom_n"]) + float(r["force_top_n"]))
        strain = (gap0 - float(r["platen_gap_m"])) / gap0
        intact = bonds[k] if k < len(bonds) else bonds[-1]
        curve.append((int(r["step"]), strain, f / (math.pi * p["radius"] ** 2), intact))
    return curve, wall, int(rows[-1]["step"])


def run_breccia(out, geo, p, binary):
    runs = out / "breccia"
    if runs.exists():
        shutil.rmtree(runs)
    runs.mkdir(parents=True)
    exp = out / "breccia.toml"
    exp.write_text(EXPERIMENT.format(geometry=geo, runs=runs, diameter=2 * p["radius"], **p))
    t0 = time.time()
    with open(out / "breccia.log", "w") as log:
        subprocess.run([str(binary), "run", str(exp)], check=True, stdout=log,
                       stderr=subprocess.STDOUT, env={"OMP_NUM_THREADS": "1", "PATH": "/usr/bin:/bin"})
    (runs / "wall_time_s").write_text(f"{time.time() - t0:.1f}\n")
    return read_breccia(out, p)


def read_breccia(out, p):
    runs = out / "breccia"
    wall = float((runs / "wall_time_s").read_text())
    folder = next(f for f in runs.iterdir() if (f / "history.csv").exists())
    curve = []
    for r in csv.DictReader(open(folder / "history.csv")):
        f = 0.5 * (float(r["platen_force_bottom_n"]) + float(r["platen_force_top_n"]))
        curve.append((int(r["step"]), float(r["axial_strain"]), f / (math.pi * p["radius"] ** 2),
                      float(r["intact_bonds"])))
    return curve, wall, curve[-1][0]


def reduce(curve, bonds0):
    k = max(range(len(curve)), key=lambda i: curve[i][2])
    peak, strain_peak = curve[k][2], curve[k][1]
    pts = [(e, s) for (_, e, s, _) in curve[:k + 1] if 0.4 * peak <= s <= 0.6 * peak]
    n = len(pts)
    mx, my = sum(e for e, _ in pts) / n, sum(s for _, s in pts) / n
    slope = sum((e - mx) * (s - my) for e, s in pts) / sum((e - mx) ** 2 for e, _ in pts)
    return {"ucs_mpa": peak / 1e6, "e_gpa": slope / 1e9, "strain_at_peak_pct": 100 * strain_peak,
            "broken_at_peak": bonds0 - curve[k][3], "broken_at_end": bonds0 - curve[-1][3],
            "end_strain_pct": 100 * curve[-1][1], "points_in_fit": n}


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--out", type=pathlib.Path, default=pathlib.Path("/tmp/breccia-esys-beam"))
    ap.add_argument("--breccia", type=pathlib.Path, default=ROOT / "build" / "breccia")
    ap.add_argument("--platen-speed", type=float, default=0.05)
    ap.add_argument("--cohesion", type=float, default=PARAMS["bond_cohesion"])
    ap.add_argument("--skip-esys", action="store_true")
    ap.add_argument("--skip-breccia", action="store_true")
    a = ap.parse_args()
    p = dict(PARAMS, platen_speed=a.platen_speed, bond_cohesion=a.cohesion)
    a.out.mkdir(parents=True, exist_ok=True)
    geo = a.out / "sample.geo"
    if not geo.exists():
        subprocess.run(["/usr/bin/python3", str(HERE / "make_sample.py"), str(geo)], check=True,
                       stdout=subprocess.DEVNULL)
    lines = geo.read_text().splitlines()
    n_particles = int(lines[lines.index("Simple") + 1])
    bonds0 = int(lines[lines.index("BeginConnect") + 1])
    results = {}
    # A skipped code's earlier results in the same folder are read back.
    if not a.skip_breccia:
        results["Breccia brittle_beam"] = run_breccia(a.out, geo, p, a.breccia)
    elif (a.out / "breccia" / "wall_time_s").exists():
        results["Breccia brittle_beam"] = read_breccia(a.out, p)
    if not a.skip_esys:
        results["ESyS-Particle 2.3.5"] = run_esys(a.out, geo, p)
    elif (a.out / "esys" / "wall_time_s").exists():
        results["ESyS-Particle 2.3.5"] = read_esys(a.out, geo, p)
    with open(a.out / "curves.csv", "w", newline="") as f:
        w = csv.writer(f)
        w.writerow(["code", "step", "axial_strain", "axial_stress_pa", "intact_bonds"])
        for name, (curve, _, _) in results.items():
            w.writerows([name, *row] for row in curve)
    table = [f"GenGeo cylinder: {n_particles} grains, {bonds0} bonds; "
             f"platen speed {p['platen_speed']} m/s each, time step {p['time_step']} s", "",
             "| code | E_t50 (GPa) | UCS (MPa) | strain at peak (%) | broken bonds at peak "
             "| broken bonds at end (strain %) | wall time (s, steps) |",
             "|---|---|---|---|---|---|---|"]
    reduced = {}
    for name, (curve, wall, steps) in results.items():
        r = reduced[name] = reduce(curve, bonds0)
        table.append(f"| {name} | {r['e_gpa']:.2f} | {r['ucs_mpa']:.1f} | "
                     f"{r['strain_at_peak_pct']:.3f} | {r['broken_at_peak']:.0f} | "
                     f"{r['broken_at_end']:.0f} ({r['end_strain_pct']:.3f}) | {wall:.0f} ({steps}) |")
    if len(reduced) == 2:
        b, e = reduced["Breccia brittle_beam"], reduced["ESyS-Particle 2.3.5"]
        table.append(f"| Breccia / ESyS - 1 | {100 * (b['e_gpa'] / e['e_gpa'] - 1):+.1f} % | "
                     f"{100 * (b['ucs_mpa'] / e['ucs_mpa'] - 1):+.1f} % | "
                     f"{100 * (b['strain_at_peak_pct'] / e['strain_at_peak_pct'] - 1):+.1f} % | "
                     f"{100 * (b['broken_at_peak'] / max(e['broken_at_peak'], 1) - 1):+.0f} % | | |")
    (a.out / "results.json").write_text(json.dumps(reduced, indent=1))
    (a.out / "results.md").write_text("\n".join(table) + "\n")
    print("\n".join(table))


if __name__ == "__main__":
    main()
