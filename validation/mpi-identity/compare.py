#!/usr/bin/env python3
"""Compares two run folders file by file: prints "<files compared> | <differing files>" and exits
1 when a file differs or is missing. manifest.json (the launch, the clock) is left out, and so are
summary.json's timings and the experiment's output folder."""
import json
import sys
from pathlib import Path

TIMINGS = ("wall_seconds", "loading_loop", "particle_steps_per_second", "resumed")


def summary(path):
    j = json.loads(path.read_text())
    for key in TIMINGS:
        j.pop(key, None)
    return j


def experiment(path):
    return [l for l in path.read_text().splitlines() if not l.startswith("directory = ")]


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
