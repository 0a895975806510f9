#!/usr/bin/python3
"""Packs a random bonded cylinder with GenGeo (Debian's python3-gengeo), the sample the peer
comparison runs in every code. Model units (radii 0.25-0.5 by default), axis along y, height
twice the diameter; bonds join grains closer than 1e-5 (touching).

    /usr/bin/python3 gengeo_cylinder.py RADIUS OUT.geo [RMIN RMAX]

RADIUS 13.25 gives about 110k grains and 255k bonds (GenGeo's insertion packing is random: the
count varies by a few hundred with GenGeo's seed); 7.75 gives about 22k.
"""
import sys
import time

from gengeo import (CylinderVol, InsertGenerator3D, MNTable3D, Vector3)

radius = float(sys.argv[1])
out = sys.argv[2]
r_min = float(sys.argv[3]) if len(sys.argv) > 3 else 0.25
r_max = float(sys.argv[4]) if len(sys.argv) > 4 else 0.5
height = 4.0 * radius
start = time.time()
volume = CylinderVol(origin=Vector3(0, 0, 0), axis=Vector3(0, 1, 0), length=height,
                     radius=radius)
table = MNTable3D(minPoint=Vector3(-radius - 1, -1, -radius - 1),
                  maxPoint=Vector3(radius + 1, height + 1, radius + 1),
                  gridSize=2.5 * r_max, numGroups=1)
packer = InsertGenerator3D(minRadius=r_min, maxRadius=r_max, insertFails=1000,
                           maxIterations=1000, tolerance=1.0e-6, seed=True)
packer.generatePacking(volume=volume, ntable=table, groupID=0, tag=0)
table.generateBonds(groupID=0, tolerance=1.0e-5, bondID=1)
table.write(fileName=out, outputStyle=1)
print(f"{out}: cylinder radius {radius}, height {height}, packed in {time.time() - start:.0f} s")
