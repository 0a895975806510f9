#!/usr/bin/env python3
"""Cuts a centred window out of a 2D breccia geometry file (the grains whose centres lie in it and
the bonds among them), so that a small sample keeps a large packing's porosity and bonds.

    crop.py IN.geom OUT.geom WIDTH HEIGHT      (metres)
    crop.py --describe FILE.geom ...           (grains, porosity, bonds per grain)

The porosity is read inside the grains' bounding box inset by two largest diameters (a cut
window's edge is ragged), on a raster of 1/20 of the mean radius; bonds per grain is twice the
bonds over the grains (the bonded coordination number).
"""
import sys

import numpy as np


def read(path):
    header, particles, bonds = [], [], []
    section = None
    with open(path) as f:
        for line in f:
            body = line.split("#", 1)[0].split()
            if not body:
                continue
            if body[0] == "particles":
                section = "particles"
                header.append(line)
                continue
            if body[0] == "bonds":
                section = "bonds"
                continue
            if section == "particles":
                particles.append(body)
            elif section == "bonds":
                bonds.append((int(body[0]), int(body[1])))
            else:
                header.append(line)
    return header, particles, bonds


def interior_porosity(xs, ys, rs, box):
    x0, x1, y0, y1 = box
    inset = 4.0 * max(rs)
    x0, x1, y0, y1 = x0 + inset, x1 - inset, y0 + inset, y1 - inset
    h = sum(rs) / len(rs) / 20.0
    nx, ny = int((x1 - x0) / h), int((y1 - y0) / h)
    solid = np.zeros((ny, nx), dtype=bool)
    gx = x0 + (np.arange(nx) + 0.5) * h
    gy = y0 + (np.arange(ny) + 0.5) * h
    for x, y, r in zip(xs, ys, rs):
        i0, i1 = np.searchsorted(gx, x - r), np.searchsorted(gx, x + r)
        j0, j1 = np.searchsorted(gy, y - r), np.searchsorted(gy, y + r)
        if i0 >= i1 or j0 >= j1:
            continue
        dx = gx[i0:i1] - x
        dy = gy[j0:j1, None] - y
        solid[j0:j1, i0:i1] |= dx * dx + dy * dy <= r * r
    return 1.0 - solid.mean()


def describe(path, particles, bonds):
    xs = [float(p[1]) for p in particles]
    ys = [float(p[2]) for p in particles]
    rs = [float(p[4]) for p in particles]
    x0 = min(x - r for x, r in zip(xs, rs))
    x1 = max(x + r for x, r in zip(xs, rs))
    y0 = min(y - r for y, r in zip(ys, rs))
    y1 = max(y + r for y, r in zip(ys, rs))
    porosity = interior_porosity(xs, ys, rs, (x0, x1, y0, y1))
    print(f"{path}: {len(particles)} disks, {(x1 - x0) * 1e3:.2f} x {(y1 - y0) * 1e3:.2f} mm, "
          f"porosity {porosity:.4f}, {len(bonds)} bonds, {2 * len(bonds) / len(particles):.3f} "
          f"bonds per grain, mean radius {sum(rs) / len(rs) * 1e6:.2f} um")


def main(argv):
    if argv[:1] == ["--describe"]:
        for path in argv[1:]:
            _, particles, bonds = read(path)
            describe(path, particles, bonds)
        return 0
    if len(argv) != 4:
        print(__doc__, file=sys.stderr)
        return 2
    src, dst, width, height = argv[0], argv[1], float(argv[2]), float(argv[3])
    header, particles, bonds = read(src)
    if not any(h.split()[:2] == ["dimension", "2"] for h in header):
        print(f"{src}: expected a 2D geometry ('dimension 2')", file=sys.stderr)
        return 2
    xs = [float(p[1]) for p in particles]
    ys = [float(p[2]) for p in particles]
    cx = 0.5 * (min(xs) + max(xs))
    cy = 0.5 * (min(ys) + max(ys))
    if width > max(xs) - min(xs) or height > max(ys) - min(ys):
        print(f"{src}: a {width} x {height} m window does not fit the sample", file=sys.stderr)
        return 2
    kept = [p for p in particles
            if abs(float(p[1]) - cx) <= 0.5 * width and abs(float(p[2]) - cy) <= 0.5 * height]
    tags = {int(p[0]) for p in kept}
    kept_bonds = [b for b in bonds if b[0] in tags and b[1] in tags]
    with open(dst, "w") as f:
        for h in header:
            if h.split()[0] != "particles":
                f.write(h)
        f.write(f"particles {len(kept)}\n# tag x y z radius density motion vx vy vz wx wy wz\n")
        for p in kept:
            f.write(" ".join(p) + "\n")
        f.write(f"bonds {len(kept_bonds)}\n")
        for a, b in kept_bonds:
            f.write(f"{a} {b}\n")
    describe(src, particles, bonds)
    describe(dst, kept, kept_bonds)
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
