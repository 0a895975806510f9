"""UCS of a GenGeo cylinder in ESyS-Particle 2.3.5 with BrittleBeamPrms bonds.

Run by run.py as `mpirun -np 2 esysparticle esys_ucs.py CONFIG.json` (one master, one worker).
CONFIG.json gives the geometry file, the micro-parameters, the time step and the loading; the
script writes history.csv (step, time, platen gap, platen forces, intact bonds) beside it.

The set-up mirrors Breccia's `brittle_beam` experiment written by run.py:
- bonds: BrittleBeamPrms on the file's connections (tag 0), beam radius the mean radius;
- contacts of unbonded pairs: RotFrictionPrms with scaled stiffness k_n = normalK r_min^2 / (R1 + R2)
  (meanR_scaling False), which is Breccia's linear law k_n = pi r_min^2 E_c / (R1 + R2) for
  normalK = pi E_c; bonded pairs are excluded from it, as `contact_while_bonded = false`;
- platens: frictionless elastic walls, k = pi R normalK, Breccia's wall contact for normalK = E_c;
- Cundall local damping on forces and moments (LocalDampingPrms, RotLocalDampingPrms);
- both platens move toward each other with a cosine velocity ramp, as Breccia's platens.
"""
import csv
import json
import math
import sys

from esys.lsm import (BrittleBeamPrms, LocalDampingPrms, LsmMpi, NRotElasticWallPrms,
                      RotFrictionPrms, RotLocalDampingPrms, InteractionScalarFieldSaverPrms)
from esys.lsm.util import Vec3, BoundingBox


def read_extent(path):
    """Smallest z - r and largest z + r of the particles, and the largest radius."""
    zmin, zmax, rmax, section = math.inf, -math.inf, 0.0, False
    with open(path) as f:
        for line in f:
            w = line.split()
            if not w:
                continue
            if w[0] == "BeginParticles":
                section = True
            elif w[0] == "EndParticles":
                break
            elif section and len(w) == 6:
                z, r = float(w[2]), float(w[3])
                zmin, zmax, rmax = min(zmin, z - r), max(zmax, z + r), max(rmax, r)
    return zmin, zmax, rmax


def ramp(t, duration):
    if duration <= 0.0 or t >= duration:
        return 1.0
    return 0.5 * (1.0 - math.cos(math.pi * t / duration))


def main():
    cfg_path = sys.argv[1]
    with open(cfg_path) as f:
        cfg = json.load(f)
    out_dir = cfg["out_dir"]
    geo = cfg["geometry"]
    zmin, zmax, rmax = read_extent(geo)
    dt = cfg["time_step"]
    ec, kappa, mu = cfg["contact_modulus"], cfg["stiffness_ratio"], cfg["friction"]

    sim = LsmMpi(numWorkerProcesses=1, mpiDimList=[1, 1, 1])
    sim.initNeighbourSearch(particleType="RotSphere", gridSpacing=2.5 * rmax,
                            verletDist=0.2 * rmax)
    sim.setTimeStepSize(dt)
    sim.readGeometry(geo)
    sim.setParticleDensity(tag=0, mask=-1, Density=cfg["density"])
    sim.createWall(name="bottom", posn=Vec3(0.0, 0.0, zmin), normal=Vec3(0.0, 0.0, 1.0))
    sim.createWall(name="top", posn=Vec3(0.0, 0.0, zmax), normal=Vec3(0.0, 0.0, -1.0))
    sim.createInteractionGroup(
        BrittleBeamPrms(name="bonds", youngsModulus=cfg["bond_modulus"],
                        poissonsRatio=cfg["bond_poisson_ratio"], cohesion=cfg["bond_cohesion"],
                        tanAngle=cfg["bond_tan_friction"], tag=0, meanR_scaling=True,
                        truncated=1.0, beta1=1.0, beta2=1.0))
    sim.createInteractionGroup(
        RotFrictionPrms(name="friction", normalK=math.pi * ec, dynamicMu=mu, staticMu=mu,
                        shearK=math.pi * ec / kappa, scaling=True, rigid=False,
                        meanR_scaling=False))
    sim.createExclusion(interactionName1="bonds", interactionName2="friction")
    for w in ("bottom", "top"):
        sim.createInteractionGroup(NRotElasticWallPrms(name=w + "_contact", wallName=w,
                                                       normalK=ec))
    sim.createInteractionGroup(LocalDampingPrms(name="damping", viscosity=cfg["local_damping"]))
    sim.createInteractionGroup(RotLocalDampingPrms(name="rot_damping",
                                                   viscosity=cfg["local_damping"]))
    steps, every = cfg["steps"], cfg["record_interval"]
    sim.createFieldSaver(InteractionScalarFieldSaverPrms(
        interactionName="bonds", fieldName="count", fileName=out_dir + "/bonds.dat",
        fileFormat="SUM", beginTimeStep=0, endTimeStep=steps, timeStepIncr=every))
    sim.setNumTimeSteps(steps)

    speed, ramp_time = cfg["platen_speed"], cfg["ramp_time"]
    gap0 = zmax - zmin
    rows = []
    peak, stop_fraction = 0.0, cfg["stop_fraction"]
    area = math.pi * cfg["radius"] ** 2
    for n in range(steps):
        step_move = speed * ramp(n * dt, ramp_time) * dt
        sim.moveWallBy("bottom", Vec3(0.0, 0.0, step_move))
        sim.moveWallBy("top", Vec3(0.0, 0.0, -step_move))
        sim.runTimeStep()
        if (n + 1) % every == 0:
            # getWallForce is the force the wall exerts on the particles.
            zb = sim.getWallPosition("bottom")[2]
            zt = sim.getWallPosition("top")[2]
            fb = sim.getWallForce("bottom")[2]
            ft = -sim.getWallForce("top")[2]
            stress = 0.5 * (fb + ft) / area
            rows.append((n + 1, (n + 1) * dt, zt - zb, fb, ft))
            peak = max(peak, stress)
            strain = (gap0 - (zt - zb)) / gap0
            if strain >= cfg["max_strain"] or (peak > 0 and stress < stop_fraction * peak
                                               and strain > 0.001):
                break
    with open(out_dir + "/history.csv", "w", newline="") as f:
        wr = csv.writer(f)
        wr.writerow(["step", "time_s", "platen_gap_m", "force_bottom_n", "force_top_n"])
        wr.writerows(rows)
    sim.exit()


if __name__ == "__main__":
    main()
