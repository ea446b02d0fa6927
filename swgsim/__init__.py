"""swgsim: simulation chain of a strain wave gear with strain gauges on the flexspline.

Dynamic input/output model (paper eq. 1-6), the flexspline as a space truss, strain-gauge
bridges in mV/V, the paper's five faults, data-set acquisitions and generation (the
calibration loop against measured data is the separate package :mod:`swgcal`). See
``docs/ARCHITECTURE.md`` for the data flow.

Sub-packages, each a floor above the ones it uses: :mod:`swgsim.base` and
:mod:`swgsim.files`, :mod:`swgsim.gear`, :mod:`swgsim.sensing`, :mod:`swgsim.datasets`
(docs/ARCHITECTURE.md, "Floors" and "Layout").

The public API is listed in ``__all__``; names are imported on first use, so that
``import swgsim`` stays cheap::

    import swgsim
    chain = swgsim.SimulationChain()
    p = swgsim.apply_fault(swgsim.ChainParams(gear=swgsim.rt1_size20()), "eccentric_wg", 0.1)
"""

from __future__ import annotations

from importlib.metadata import PackageNotFoundError, version

from swgsim.base.lazy import lazy_exports

try:
    __version__ = version("swg-monitor")
except PackageNotFoundError:  # not installed (source tree on sys.path)
    __version__ = "0+unknown"

_EXPORTS = {
    # dynamic I/O model
    "GearParams": "gear.dynamics", "rt1_size20": "gear.dynamics", "simulate": "gear.dynamics",
    "torsional_mode": "gear.modes",
    # faults and variants
    "ChainParams": "gear.faults", "FAULTS": "gear.faults", "apply_fault": "gear.faults",
    "NO_ROOT_CRACK": "gear.faults",
    # flexspline, gauges, chain
    "FlexsplineGeometry": "gear.flexspline", "Mesh": "gear.flexspline",
    "TrussModel": "gear.flexspline", "SensorLayout": "gear.sensors",
    "SimulationChain": "gear.chain", "ChainSettings": "gear.chain",
    # joint friction beyond the paper law (a calibration's accepted effects)
    "FrictionEffects": "gear.friction",
    # data sets
    "DatasetConfig": "datasets.config", "dataset_config": "datasets.config",
    "DatasetPlan": "datasets.plan", "load": "datasets.schema", "DataSetError": "datasets.schema",
}

__all__ = ["__version__", *_EXPORTS]


__getattr__, __dir__ = lazy_exports(__name__, _EXPORTS)
