#!/usr/bin/python3
"""Packs the shared GenGeo cylinder for the ESyS-Particle / Breccia brittle-beam comparison.

GenGeo's packer and bonder use absolute tolerances (1e-6 fit, 1e-5 bond gap), so the cylinder is
packed in millimetres, where those tolerances are small against the radii, and then written in
metres: every coordinate, radius and the bounding box are multiplied by 1e-3. Both codes read the
same file. GenGeo's InsertGenerator3D places each grain tangent to its neighbours, so bonded pairs
start at d0 = R1 + R2 (to the packer's tolerance), the case where ESyS's conventions (bond rest
length and arm R1 + R2) and Breccia's (d0) coincide.

    /usr/bin/python3 make_sample.py OUT.geo [--radius-mm 5] [--height-mm 20]
        [--rmin-mm 0.25] [--rmax-mm 1.0] [--fails 1000]
"""
import argparse
import pathlib
import sys

try:
    import gengeo as gg
except ImportError:
    sys.exit("make_sample.py: needs Debian's python3-gengeo under /usr/bin/python3 "
             "(apt-get install python3-gengeo)")


def pack(radius, height, rmin, rmax, fails, out_mm):
    cyl = gg.CylinderVol(origin=gg.Vector3(0, 0, 0), axis=gg.Vector3(0, 0, 1), length=height,
                         radius=radius)
    # The table's box becomes the file's BoundingBox, which ESyS takes as its spatial domain:
    # margins of several grains keep fragments inside it after failure.
    margin = 6.0 * rmax
    table = gg.MNTable3D(minPoint=gg.Vector3(-radius - margin, -radius - margin, -margin),
                         maxPoint=gg.Vector3(radius + margin, radius + margin, height + margin),
                         gridSize=2.5 * rmax)
    packer = gg.InsertGenerator3D(minRadius=rmin, maxRadius=rmax, insertFails=fails,
                                  maxIterations=1000, tolerance=1.0e-6, seed=False)
    packer.generatePacking(volume=cyl, ntable=table)
    table.generateBonds(tolerance=1.0e-5, bondID=0)
    table.write(fileName=str(out_mm), outputStyle=1)


def to_metres(src, dst, scale=1e-3):
    """Rewrites an LSMGeometry 1.2 file with lengths multiplied by `scale`."""
    lines = src.read_text().splitlines()
    out, section = [], None
    for line in lines:
        words = line.split()
        if words and words[0] == "BoundingBox":
            line = "BoundingBox " + " ".join(f"{float(w) * scale:.12g}" for w in words[1:])
        elif words and words[0] in ("BeginParticles", "BeginConnect"):
            section = words[0]
        elif words and words[0] in ("EndParticles", "EndConnect"):
            section = None
        elif section == "BeginParticles" and len(words) == 6:
            x, y, z, r = (float(w) * scale for w in words[:4])
            line = f"{x:.12g} {y:.12g} {z:.12g} {r:.12g} {words[4]} {words[5]}"
        out.append(line)
    dst.write_text("\n".join(out) + "\n")


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("out", type=pathlib.Path)
    ap.add_argument("--radius-mm", type=float, default=5.0)
    ap.add_argument("--height-mm", type=float, default=20.0)
    ap.add_argument("--rmin-mm", type=float, default=0.25)
    ap.add_argument("--rmax-mm", type=float, default=1.0)
    ap.add_argument("--fails", type=int, default=1000)
    a = ap.parse_args()
    mm = a.out.with_suffix(".mm.geo")
    pack(a.radius_mm, a.height_mm, a.rmin_mm, a.rmax_mm, a.fails, mm)
    to_metres(mm, a.out)
    mm.unlink()


if __name__ == "__main__":
    main()
