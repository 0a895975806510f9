#!/usr/bin/python3
"""Writes a GenGeo cylinder as a LAMMPS data file for atom_style bpm/sphere (model units, axis
along y as GenGeo wrote it), with GenGeo's bonds as bond type 1.

    /usr/bin/python3 to_lammps.py IN.geo OUT.data [DENSITY]

Prints the grain and bond counts and the height H that the LAMMPS input needs (-var H).
"""
import sys

src, dst = sys.argv[1], sys.argv[2]
density = float(sys.argv[3]) if len(sys.argv) > 3 else 1.0
lines = open(src).read().split("\n")
radius = -(float(lines[1].split()[1]) + 1.0)  # the bounding box starts one unit outside
height = 4.0 * radius
first = lines.index("BeginParticles") + 2
count = int(lines[first])
grains = []
for line in lines[first + 1:first + 1 + count]:
    x, y, z, r, gid = line.split()[:5]
    grains.append((int(gid), float(x), float(y), float(z), float(r)))
start = lines.index("BeginConnect") + 1
bond_count = int(lines[start])
bonds = [tuple(int(v) for v in line.split()[:2])
         for line in lines[start + 1:start + 1 + bond_count]]
atom_id = {g[0]: k + 1 for k, g in enumerate(grains)}
with open(dst, "w") as f:
    f.write(f"GenGeo cylinder {src}: radius {radius:g}, height {height:g}\n\n")
    f.write(f"{count} atoms\n{bond_count} bonds\n1 atom types\n1 bond types\n\n")
    f.write(f"{-radius - 2:g} {radius + 2:g} xlo xhi\n{-2.0:g} {height + 2:g} ylo yhi\n")
    f.write(f"{-radius - 2:g} {radius + 2:g} zlo zhi\n\nAtoms # bpm/sphere\n\n")
    for k, (_, x, y, z, r) in enumerate(grains):
        f.write(f"{k + 1} 1 1 {2 * r:.10g} {density:g} {x:.10g} {y:.10g} {z:.10g}\n")
    f.write("\nBonds\n\n")
    for k, (a, b) in enumerate(bonds):
        f.write(f"{k + 1} 1 {atom_id[a]} {atom_id[b]}\n")
print(f"{count} grains, {bond_count} bonds, height H = {height:g}")
