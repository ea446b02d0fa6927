"""swgsim: simulation chain of a strain wave gear with strain gauges on the flexspline.

Dynamic input/output model (paper eq. 1-6), the flexspline as a space truss, strain-gauge
bridges in mV/V, the paper's five faults, data-set recordings and generation (the
calibration loop against measured data is the separate package :mod:`swgcal`). See
``docs/ARCHITECTURE.md`` for the data flow.

The public API is listed in ``__all__``; names are imported on first use, so that
``import swgsim`` stays cheap::

    import swgsim
    chain = swgsim.SimulationChain()
    p = swgsim.apply_fault(swgsim.ChainParams(gear=swgsim.rt1_size20()), "eccentric_wg", 0.1)
"""

from __future__ import annotations

from importlib.metadata import PackageNotFoundError, version

from .lazy import lazy_exports

try:
    __version__ = version("swg-monitor")
except PackageNotFoundError:  # not installed (source tree on sys.path)
    __version__ = "0+unknown"

_EXPORTS = {
    # dynamic I/O model
    "GearParams": "dynamics", "rt1_size20": "dynamics", "simulate": "dynamics",
    "torsional_mode": "modes",
    # faults and variants
    "ChainParams": "faults", "FAULTS": "faults", "apply_fault": "faults",
    "NO_ROOT_CRACK": "faults",
    # flexspline, gauges, chain
    "FlexsplineGeometry": "flexspline", "Mesh": "flexspline", "TrussModel": "flexspline",
    "SensorLayout": "sensors", "SimulationChain": "chain", "ChainSettings": "chain",
    # joint friction beyond the paper law (a calibration's accepted effects)
    "FrictionEffects": "friction",
    # data sets
    "DatasetConfig": "config", "dataset_config": "config",
    "DatasetPlan": "plan", "load": "data",
    "DataSetError": "data",
}

__all__ = ["__version__", *_EXPORTS]


__getattr__, __dir__ = lazy_exports(__name__, _EXPORTS)
