"""
A data set and one of its windows
=================================

Simulate the tiny data set (the paper's preset on a small grid: three gears, every fault
class, one speed and two loads; ``conf/dataset/tiny.yaml``) with
:func:`swgsim.datasets.generate.generate`, load it with its integrity checks
(:func:`swgsim.datasets.schema.load`) and plot one window of the five bridges, healthy
and with an eccentric wave generator. The data set is a folder of NetCDF4 shards and a
manifest (docs/DATASET.md), readable without this project.
"""

import tempfile
from pathlib import Path

import matplotlib.pyplot as plt
import numpy as np

from swgcli import dataset_preset
from swgsim.datasets.config import dataset_config
from swgsim.datasets.generate import generate
from swgsim.datasets.schema import load

work = tempfile.TemporaryDirectory(prefix="swg-example-")  # removed at the end
folder = Path(work.name) / "tiny"
cfg = dataset_config(dataset_preset("tiny"))
cfg.gears = [g for g in cfg.gears if g.id == 1]  # one gear is enough for a look
generate(cfg, folder, progress=False)
ds = load(folder)
print(f"{ds.sizes['sample']} windows of {ds.sizes['time']} samples at "
      f"{ds.attrs['sample_rate_hz']:.0f} Hz; classes: {sorted(map(str, set(ds.fault.values)))}")

# %%
# One window per class at the rated load, clean (no eq. (10) disturbance): the bridges
# s0..s4 in mV/V over the window's four input revolutions. The eccentric wave generator
# adds an order-1 bending that the WG-bending bridges s1 and s3 read with opposite signs.


def window(fault: str, severity: float | None = None) -> np.ndarray:
    """The first clean window of a class at 70 N m, shape (5, n_t) [mV/V]."""
    pick = ((ds.fault == fault) & (ds.t_out_nm == 70.0) & ~ds.disturbed & ~ds.reference)
    if severity is not None:
        pick &= np.isclose(ds.severity, severity)
    return ds.strain_signal[np.flatnonzero(pick.values)[0]].values


t_ms = ds.time.values * 1e3
fig, axes = plt.subplots(5, 1, figsize=(7, 7), sharex=True)
for ax, s, healthy, faulty in zip(axes, ds.sensor.values, window("healthy"),
                                  window("eccentric_wg", 0.1), strict=True):
    ax.plot(t_ms, healthy, lw=0.8, label="healthy")
    ax.plot(t_ms, faulty, lw=0.8, label="eccentric WG, severity 0.1")
    ax.set_ylabel(f"{s} [mV/V]")
axes[0].legend(fontsize=8, loc="upper right")
axes[-1].set_xlabel("time in the window [ms]")
fig.suptitle("Gear 1 at 4000 rpm and 70 N m, clean windows", fontsize=10)
fig.tight_layout()

# %%
# The simulated files were only for this page: remove them.
work.cleanup()
