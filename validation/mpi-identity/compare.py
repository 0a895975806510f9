#!/usr/bin/env python3
"""Compares two run folders file by file: prints "<files compared> | <differing files>" and exits
1 when a file differs or is missing. manifest.json (the launch, the clock) is left out, and so are
summary.json's timings, the sample cache's path, and the output folder and thread count in the
resolved experiment (launch settings that results do not depend on)."""
import json
import sys
from pathlib import Path

# What depends on the clock, the machine or the output folder, at any depth of summary.json.
MACHINE_KEYS = {"wall_seconds", "loading_loop", "particle_steps_per_second", "resumed",
                "packing_seconds", "seconds", "cached_file"}
# Lines of the resolved experiment that name the launch, not the physics.
LAUNCH_LINES = ("directory = ", "threads = ")


def without_machine(v):
    if isinstance(v, dict):
        return {k: without_machine(x) for k, x in v.items() if k not in MACHINE_KEYS}
    if isinstance(v, list):
        return [without_machine(x) for x in v]
    if isinstance(v, str) and "\ndirectory = " in v:
        return "\n".join(l for l in v.split("\n") if not is_launch_line(l))
    return v


def is_launch_line(line):
    return line.startswith(LAUNCH_LINES)


def summary(path):
    return without_machine(json.loads(path.read_text()))


def experiment(path):
    return [l for l in path.read_text().splitlines() if not is_launch_line(l)]


def main(a, b):
    a, b = Path(a), Path(b)
    compared, differing = 0, []
    for fa in sorted(p for p in a.rglob("*") if p.is_file()):
        rel = fa.relative_to(a)
        if rel.name in ("manifest.json", "plot.log"):
            continue
        fb = b / rel
        compared += 1
        if not fb.exists():
            differing.append(f"{rel} (missing)")
        elif rel.name == "summary.json":
            if summary(fa) != summary(fb):
                differing.append(str(rel))
        elif rel.name == "experiment.toml":
            if experiment(fa) != experiment(fb):
                differing.append(str(rel))
        elif fa.read_bytes() != fb.read_bytes():
            differing.append(str(rel))
    print(f"{compared} | {', '.join(differing) if differing else 'none'}")
    return 1 if differing else 0


if __name__ == "__main__":
    sys.exit(main(*sys.argv[1:3]))
