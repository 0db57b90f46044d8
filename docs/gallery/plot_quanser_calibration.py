"""
A real arm calibrated: the Quanser flexible link's first stage
==============================================================

:func:`flexarm.calibrate` on the example ``examples/quanser_2dsfl/stage1_steps.toml``: the
measured hub angle of two LQ step runs prescribed, the strip's root strain gauge (in the
vendor's tip-angle form) predicted. Four numbers are fitted: the strip's rigidity, the
inertia of the second stage at its tip, the strip's damping ratio and the strain channel's
lag. The fitted arm then predicts two steps of another run (the full-state-feedback run's
big stage-1 steps) that the fit never saw.

The rig's files are not part of flexarm: set ``FLEXARM_QUANSER`` to their directory
(default ``../shared/data/quanser_2dsfl`` beside the repository). Without them the figure
says so.
"""

import os
from pathlib import Path

import matplotlib.pyplot as plt

import flexarm as fa
from flexarm.calibration.config import load_config

try:
    HERE = Path(__file__).resolve().parent
except NameError:  # run by sphinx-gallery from the gallery's folder
    HERE = Path.cwd()
ROOT = HERE.parents[1]
DATA = Path(os.environ.get("FLEXARM_QUANSER", ROOT.parent / "shared" / "data" / "quanser_2dsfl"))
CONFIG = ROOT / "examples" / "quanser_2dsfl" / "stage1_steps.toml"

if (DATA / "lqg_step_10deg_run01.mat").is_file():
    cal = fa.calibrate(load_config(CONFIG).with_data(DATA))
    print(cal.text())
else:
    cal = None
    print(f"the rig's files are not in {DATA}")

# %%
# Each record's strain channel, measured and predicted by the arm before (the data sheet's
# numbers) and after the fit. The first two were fitted; the last two are the steps the fit
# did not see.

if cal is None:
    fig, ax = plt.subplots(figsize=(6, 1.5))
    ax.axis("off")
    ax.text(0.5, 0.5, f"the rig's files are not in {DATA}", ha="center", va="center")
else:
    fig, axes = plt.subplots(len(cal.records), 1, figsize=(7, 2.2 * len(cal.records)))
    for ax, rec in zip(axes, cal.records, strict=True):
        c = rec.channels["th12"]
        ax.plot(rec.t, rec.measured["th12"], "k", lw=1.2, label="measured")
        ax.plot(rec.t, rec.predicted["th12"], lw=1.0, label=f"fitted ({c.fit_percent:.1f} %)")
        ax.plot(
            rec.t,
            rec.predicted_initial["th12"],
            "--",
            color="0.5",
            lw=0.8,
            label=f"data sheet ({c.fit_percent_initial:.1f} %)",
        )
        ax.set_title(f"{rec.role}: {rec.name}", fontsize=9)
        ax.set_ylabel("th12 (rad)")
        ax.legend(fontsize=7, loc="upper right")
    axes[-1].set_xlabel("t (s)")
    fig.tight_layout()
plt.show()
