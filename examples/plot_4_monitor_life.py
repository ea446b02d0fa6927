"""
A gear's life through the condition monitor
===========================================

A diagnosis model trained on simulated lives of gears 1 and 2 of the tiny bench grid
(:func:`swgmon.evaluation.training.train_model`), then gear 3, never seen in training, lives
8 h (the ``tiny_life`` preset: 4 h of commissioning, then an eccentric wave generator of
severity 0.1 from 6 h on), and the monitor reads its windows in time order
(:func:`swgmon.advisories.stream.monitor_stream`). It commissions on the first 4 h, turns each
window into a conformal p-value against the gear's own normal behaviour, and alarms when a
CUSUM of those p-values crosses the threshold of its design false-alarm rate (one per
1000 h).
"""

import tempfile
from pathlib import Path

import matplotlib.pyplot as plt
import numpy as np

from swgcli import dataset_preset
from swgmon.advisories.stream import monitor_stream
from swgmon.detection.rule import RuleConfig, threshold
from swgmon.evaluation.study import MonitorStudyConfig
from swgmon.evaluation.training import train_model
from swgsim.datasets.config import dataset_config
from swgsim.datasets.generate import generate
from swgsim.datasets.plan import plan
from swgsim.datasets.records import record_bank
from swgsim.datasets.schema import load

bench = plan(dataset_preset("tiny_bench"))
study = MonitorStudyConfig(commissioning_h=4.0, train_healthy_h=2.0, train_variants=2,
                           faults=["eccentric_wg"])
model = train_model(bench, {g: record_bank(bench, g) for g in (1, 2)}, [1, 2], study)

life = dataset_config(dataset_preset("tiny_life"))
life.gears = [g for g in life.gears if g.id == 3]
work = tempfile.TemporaryDirectory(prefix="swg-example-")  # removed at the end
folder = Path(work.name) / "tiny_life"
generate(life, folder, progress=False)
rule = RuleConfig()
result = monitor_stream(load(folder), model, rule)
for alarm in result.alarms:
    print(f"alarm at {alarm.hour:.2f} h: {alarm.fault}, severity {alarm.severity:.3f} "
          f"[{alarm.severity_low:.3f}, {alarm.severity_high:.3f}]")

# %%
# The health indicators over the operating hours after commissioning: each window's
# combined p-value, and the largest CUSUM against the threshold. The true onset is
# dotted, the alarm red.

tr = result.trace
h = threshold(rule, 1.0)  # one window a minute
fig, (ax1, ax2) = plt.subplots(2, 1, figsize=(7, 4.5), sharex=True)
ax1.plot(tr.hour, -np.log10(tr.p), ".", ms=2, color="0.4")
ax1.set_ylabel("−log10 p")
ax2.plot(tr.hour, tr.s, lw=0.8)
ax2.axhline(h, color="r", lw=0.8, ls="--", label=f"threshold h = {h:.1f}")
for ax in (ax1, ax2):
    ax.axvline(result.onset_h, color="k", lw=0.8, ls=":")
    for alarm in result.alarms:
        ax.axvline(alarm.hour, color="r", lw=0.8)
ax2.set_ylabel("CUSUM")
ax2.set_xlabel("operating hours")
ax2.legend(fontsize=8)
fig.tight_layout()

# %%
# The simulated files were only for this page: remove them.
work.cleanup()
