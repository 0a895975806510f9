#!/usr/bin/python3
"""Markdown tables of a trained predictor (`breccia predict train ... --output MODEL`): the
data set, the leave-one-test-out errors per fold and pooled, and the input importances (Garson,
in %) beside seed 000's tables S1 and S2.

Usage: table.py MODEL
"""
import json
import os
import sys

import pandas as pd

# Seed 000, tables S1 (stress to failure) and S2 (strain to failure): Garson importance (%).
SEED = {"stress_to_failure_mpa": {"confining_mpa": 12.726, "mc_var": 10.757,
                                  "shear_fraction": 14.453, "d2": 16.585, "ae_var": 24.072,
                                  "b_value": 21.409},
        "strain_to_failure": {"confining_mpa": 8.6543, "mc_var": 30.969, "shear_fraction": 14.93,
                              "d2": 7.3054, "ae_var": 11.955, "b_value": 26.186}}


def main(model_dir):
    model = json.load(open(os.path.join(model_dir, "model.json")))
    data = pd.read_csv(os.path.join(model_dir, "dataset.csv"))
    folds = pd.read_csv(os.path.join(model_dir, "validation.csv"))
    imp = pd.read_csv(os.path.join(model_dir, "importance.csv"))
    print(f"Inputs: {', '.join(model['inputs'])}; {model['windows']} windows from "
          f"{int((data['windows'] > 0).sum())} tests; {int(data['dropped_missing_input'].sum())} "
          "pre-peak windows dropped for a missing input.\n")
    print("| sigma_3 (MPa) | " + " | ".join(f"{v:g}" for v in data["confining_mpa"]) + " |")
    print("|---|" + "---|" * len(data))
    print("| windows | " + " | ".join(str(v) for v in data["windows"]) + " |")
    print("| dropped (an input missing) | " +
          " | ".join(str(v) for v in data["dropped_missing_input"]) + " |")
    print("\n| held-out test sigma_3 (MPa) | stress to failure: RMSE (MPa) | R^2 | "
          "strain to failure: RMSE (%) | R^2 |")
    print("|---|---|---|---|---|")
    if "learner" not in folds:
        folds["learner"] = "network"
    learners = [x for x in ("network", "gradient_boosting") if (folds["learner"] == x).any()]
    for learner in learners:
        f = folds[folds["learner"] == learner]
        s = f[f["target"] == "stress_to_failure_mpa"].set_index("confining_mpa")
        e = f[f["target"] == "strain_to_failure"].set_index("confining_mpa")
        if learner != "network":
            print(f"\n{learner}:\n\n| held-out test sigma_3 (MPa) | stress to failure: RMSE (MPa) "
                  "| R^2 | strain to failure: RMSE (%) | R^2 |")
            print("|---|---|---|---|---|")
        for pc in s.index:
            print(f"| {pc:g} | {s.loc[pc, 'rmse']:.1f} | {s.loc[pc, 'r2']:.2f} | "
                  f"{100 * e.loc[pc, 'rmse']:.3f} | {e.loc[pc, 'r2']:.2f} |")
        ts, te = model["targets"]["stress"], model["targets"]["strain"]
        if learner != "network":
            ts, te = ts[learner], te[learner]
        print(f"| pooled | {ts['loto_rmse_pooled']:.1f} | {ts['loto_r2_pooled']:.2f} | "
              f"{100 * te['loto_rmse_pooled']:.3f} | {te['loto_r2_pooled']:.2f} |")
    boosting = "gradient_boosting" in imp
    print("\n| input | stress to failure: Garson (%) | mean +/- s.d. of 10 networks | "
          "seed 000 (S1) | strain to failure: Garson (%) | mean +/- s.d. | seed 000 (S2) |"
          + (" gradient boosting, stress / strain (%) |" if boosting else ""))
    print("|---|---|---|---|---|---|---|" + ("---|" if boosting else ""))
    for name in model["inputs"]:
        cells = [name]
        for target in ("stress_to_failure_mpa", "strain_to_failure"):
            r = imp[(imp["target"] == target) & (imp["input"] == name)].iloc[0]
            cells += [f"{100 * r['garson']:.1f}",
                      f"{100 * r['garson_mean_of_networks']:.1f} +/- "
                      f"{100 * r['garson_sd_of_networks']:.1f}", f"{SEED[target][name]:.1f}"]
        if boosting:
            gb = [100 * imp[(imp["target"] == t) & (imp["input"] == name)].iloc[0]
                  ["gradient_boosting"] for t in ("stress_to_failure_mpa", "strain_to_failure")]
            cells.append(f"{gb[0]:.1f} / {gb[1]:.1f}")
        print("| " + " | ".join(cells) + " |")


if __name__ == "__main__":
    if len(sys.argv) != 2:
        sys.exit(__doc__)
    main(sys.argv[1])
