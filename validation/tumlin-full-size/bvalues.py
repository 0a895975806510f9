#!/usr/bin/python3
"""Does the b-value fall toward failure, and from what size on can a run tell? For each run
folder: its grains, AE events, the events above the completeness magnitude M_c, the b-value
windows (100 events above M_c, advanced by 10; docs/analysis.md section 5.4) before and after the
peak, the b-value at the first pre-peak window, at 90 % and 97 % of the peak strain and at the
peak, the median after it, Spearman's rank correlation of b with the strain over the pre-peak
windows (-1: b falls all the way), and the deformation stages with their b-values (section 8).

    /usr/bin/python3 validation/tumlin-full-size/bvalues.py LABEL=RUN_FOLDER ...

Reads summary.json, b_value_windows.csv and events.csv as the run wrote them. It computes
Spearman's rho itself, so that runs made before summary.json carried
`acoustic_emission.b_value_before_peak` can be read too (the two agree: the same windows, the same
rank correlation), and the b-values at given fractions of the peak strain and the median after
it. Prints Markdown.
"""
import json
import sys
from pathlib import Path

import pandas as pd
from scipy.stats import spearmanr


def b_at(windows, strain):
    """The b-value of the last window stamped at or before `strain` (None before the first)."""
    before = windows[windows["axial_strain"] <= strain]
    return None if before.empty else float(before["b_value"].iloc[-1])


def cell(value, fmt="{:.2f}"):
    return "-" if value is None or value != value else fmt.format(value)


def one_run(label, folder):
    s = json.loads((folder / "summary.json").read_text())
    ae = s["acoustic_emission"]
    peak = s["axial_strain_at_peak"]
    windows = pd.read_csv(folder / "b_value_windows.csv")
    windows = windows[windows["b_value"].notna()]
    pre = windows[windows["axial_strain"] <= peak]
    post = windows[windows["axial_strain"] > peak]
    events = pd.read_csv(folder / "events.csv", usecols=["axial_strain_first"])
    rho = spearmanr(pre["axial_strain"], pre["b_value"])[0] if len(pre) >= 5 else None
    first = None if pre.empty else (float(pre["b_value"].iloc[0]),
                                     float(pre["axial_strain"].iloc[0]) / peak)
    stages = {st["stage"].split()[0]: st for st in s["stages"]["by_stage"]}
    two = stages.get("II", {})
    span = None
    if two.get("axial_strain_from") is not None and two.get("axial_strain_to") is not None:
        span = two["axial_strain_to"] - two["axial_strain_from"]
    return {
        "run": label, "grains": s["particles"], "events": ae["events"],
        "above": ae["b_value"].get("events_above_completeness"),
        "pre_events": int((events["axial_strain_first"] <= peak).sum()),
        "pre_windows": len(pre), "post_windows": len(post),
        "first": first, "b90": b_at(pre, 0.90 * peak), "b97": b_at(pre, 0.97 * peak),
        "b_peak": None if pre.empty else float(pre["b_value"].iloc[-1]),
        "b_post": None if post.empty else float(post["b_value"].median()),
        "rho": rho,
        "stage_b": " / ".join(cell(stages.get(k, {}).get("b_value"), "{:.1f}")
                              for k in ("I", "II", "III")),
        "stage_ii": (span, two.get("cracks")),
        "b_all": ae["b_value"].get("b"),
    }


def main(args):
    if not args:
        sys.exit(__doc__)
    rows = []
    for arg in args:
        label, _, folder = arg.partition("=")
        rows.append(one_run(label, Path(folder)))
    print("| run | grains | events | above M_c | events before the peak | windows before / after "
          "the peak | b, first window (at % of the peak strain) | b at 90 % | b at 97 % | "
          "b at the peak | b after the peak (median) | Spearman rho, b vs strain before the peak "
          "| b, whole catalogue | b in stages I / II / III | stage II: strain, cracks |")
    print("|" + "---|" * 15)
    for r in rows:
        first = "-" if r["first"] is None else f"{r['first'][0]:.2f} ({100 * r['first'][1]:.0f} %)"
        span, cracks = r["stage_ii"]
        two = "-" if span is None else f"{100 * span:.3f} %, {cracks:,}"
        print(f"| {r['run']} | {r['grains']:,} | {r['events']:,} | {r['above']:,} | "
              f"{r['pre_events']:,} | {r['pre_windows']} / {r['post_windows']} | {first} | "
              f"{cell(r['b90'])} | {cell(r['b97'])} | {cell(r['b_peak'])} | {cell(r['b_post'])} | "
              f"{cell(r['rho'])} | {cell(r['b_all'])} | {r['stage_b']} | {two} |")
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
