# %% [markdown]
# # Two library rocks under uniaxial compression, from Python
#
# Runs a small UCS test of the calibrated Berea sandstone and of the calibrated Lac du Bonnet
# granite, plots their stress-strain curves and crack maps, and prints their headline numbers.
# The `# %%` markers make each part a cell in Jupyter (jupytext) or VS Code; as a script:
#
#     PYTHONPATH=build/python /usr/bin/python3 examples/python/compare_presets.py [output] [width_mm]
#
# The samples are half the calibration samples' size (4 x 4 x 8 mm, about 750 grains) so that
# both runs take about a minute and a half on 2 cores: their strengths may differ from the
# presets' calibrated values by the size effect the material library reports
# (docs/materials.md). The tests run it at 3 mm.

# %%
import os
import sys

import matplotlib

if __name__ == "__main__" and not hasattr(sys, "ps1"):
    matplotlib.use("Agg")  # as a script: write the figure to a file
import matplotlib.pyplot as plt
import pandas as pd

import breccia

output = sys.argv[1] if len(sys.argv) > 1 else "runs/python-example"
width = 1e-3 * float(sys.argv[2]) if len(sys.argv) > 2 else 4e-3
small = {"width": width, "depth": width, "height": 2 * width}

# %% Run both rocks (the progress bar shows in a terminal).
runs = {}
for preset in ("berea", "lac_du_bonnet"):
    experiment = breccia.Experiment(name=f"ucs-{preset}", material={"preset": preset}, sample=small,
                                    output={"snapshot_strain_interval": 0, "plot": False})
    runs[preset] = breccia.run(experiment, output=output)

# %% Stress-strain curves and crack maps.
fig, axes = plt.subplots(1, 3, figsize=(13, 4.5))
for preset, run in runs.items():
    run.plot_stress_strain(ax=axes[0], label=preset)
axes[0].legend()
for ax, (preset, run) in zip(axes[1:], runs.items()):
    run.plot_crack_map(ax=ax)
    ax.set_title(f"{preset}: cracks, projected on x-z")
fig.tight_layout()
figure = os.path.join(output, "compare_presets.png")
fig.savefig(figure, dpi=120)

# %% Headline numbers side by side.
rows = []
for preset, run in runs.items():
    s = run.summary
    rows.append({"rock": preset, "grains": s["particles"],
                 "UCS (MPa)": round(s["peak_deviatoric_stress_pa"] / 1e6, 1),
                 "E (GPa)": round(s["youngs_modulus_pa"] / 1e9, 2),
                 "cracks": s["bonds_broken"],
                 "shear cracks (%)": round(100 * s["cracks_shear"] / max(1, s["bonds_broken"]), 1),
                 "run folder": run.path})
print(pd.DataFrame(rows).to_string(index=False))
print(f"figure: {figure}")
