"""
What the gauges see of a fault
==============================

Before any classifier: how far does each fault move the gauge signals from the healthy
windows of its gear and operating point? Each window of the tiny bench data set (windows
cut at random times, a bridge ADC's noise) is reduced to the amplitudes of the harmonics of
the wave-generator angle in the five bridges and the efficiency, and its *separation* is
its largest distance from the healthy windows, in their spreads
(:func:`learn.studies.separability.separation_records`). A fault window is *beyond* when
its separation exceeds the healthy windows' 95th percentile
(:func:`learn.observability.study.observability_table`); 5 % is chance. This is the
measure of ``swgsim-observability``, here at one output inertia (the bench's).
"""

import tempfile
from pathlib import Path

import matplotlib.pyplot as plt
import numpy as np

from learn.observability.study import observability_table
from learn.studies.separability import separation_records
from swgcli import dataset_preset
from swgsim.datasets.config import dataset_config
from swgsim.datasets.generate import generate
from swgsim.datasets.schema import load
from swgsim.gear.faults import display_name

preset = dataset_preset("tiny_bench")
preset["variants"]["healthy"]["repeat"] = 12  # more healthy windows for the percentile
work = tempfile.TemporaryDirectory(prefix="swg-example-")  # removed at the end
folder = Path(work.name) / "tiny_bench"
generate(dataset_config(preset), folder, progress=False)
records = separation_records(load(folder), disturbed=False)
table = observability_table(records, j_out=preset["load"]["j_out_kgm2"])
print(table.pivot_table(index="fault", columns="t_out_nm", values="fraction_beyond_p95")
      .mul(100).round(0))

# %%
# Each window's separation per class and load, against the healthy 95th percentile
# (dashed). Eccentric WG and reduced damping stand far out at both loads; a crack changes
# the tooth forces, which the gauges see in proportion to the transmitted torque; reduced
# stiffness sets a ripple that, below the torsional mode, follows the output inertia
# rather than the stiffness, so it hides inside the healthy spread.

faults = ["healthy", "eccentric_wg", "reduced_damping", "root_tooth_crack",
          "tip_tooth_crack", "reduced_stiffness"]
loads = sorted(records.t_out_nm.unique())
fig, axes = plt.subplots(1, len(loads), figsize=(8, 3.8), sharey=True)
rng = np.random.default_rng(0)
for ax, torque in zip(axes, loads, strict=True):
    at = records[records.t_out_nm == torque]
    for i, f in enumerate(faults):
        z = at.loc[at.fault == f, "z"].to_numpy()
        ax.plot(i + rng.uniform(-0.2, 0.2, z.size), z, ".", ms=4, alpha=0.6)
    thr = table[table.t_out_nm == torque].healthy_threshold.iloc[0]
    ax.axhline(thr, color="k", lw=0.8, ls="--")
    ax.set_yscale("log")
    ax.set_xticks(range(len(faults)), [display_name(f) for f in faults], rotation=40,
                  ha="right", fontsize=8)
    ax.set_title(f"{torque:.0f} N m", fontsize=10)
axes[0].set_ylabel("separation [healthy spreads]")
fig.tight_layout()

# %%
# The simulated files were only for this page: remove them.
work.cleanup()
