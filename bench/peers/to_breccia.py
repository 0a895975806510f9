#!/usr/bin/python3
"""Rewrites a GenGeo cylinder (axis y, model units) for Breccia: axis along z, lengths in metres
(one model unit = 1 mm). Breccia reads GenGeo files itself (sample.source = "gengeo"); only the
axis and the units change. The particle and bond sections are kept as they are otherwise.

    /usr/bin/python3 to_breccia.py IN.geo OUT.geo
"""
import sys

MM = 1e-3


def swap_yz_scaled(values):
    x, y, z = values
    return x * MM, z * MM, y * MM


src, dst = sys.argv[1], sys.argv[2]
lines = open(src).read().splitlines()
out = []
section = None
header_lines = 0
for line in lines:
    words = line.split()
    if words and words[0] == "BoundingBox":
        lo = swap_yz_scaled(map(float, words[1:4]))
        hi = swap_yz_scaled(map(float, words[4:7]))
        out.append("BoundingBox " + " ".join(f"{v:g}" for v in lo + hi))
        continue
    if words and words[0] == "BeginParticles":
        section, header_lines = "particles", 2  # the "Simple" line and the count follow
    elif words and words[0] == "EndParticles":
        section = None
    elif section == "particles" and header_lines > 0:
        header_lines -= 1
    elif section == "particles" and len(words) >= 6:
        x, y, z = swap_yz_scaled(map(float, words[:3]))
        r = float(words[3]) * MM
        out.append(f"{x:.9g} {y:.9g} {z:.9g} {r:.9g} " + " ".join(words[4:]))
        continue
    out.append(line)
open(dst, "w").write("\n".join(out) + "\n")
