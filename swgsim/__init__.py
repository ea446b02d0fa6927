"""swgsim: simulation chain of a strain wave gear with strain gauges on the flexspline.

Dynamic input/output model (paper eq. 1-6), the flexspline as a space truss, strain-gauge
bridges in mV/V, the paper's five faults, data-set acquisitions and generation (the
calibration loop against measured data is the separate package :mod:`swgcal`). See
``docs/ARCHITECTURE.md`` for the data flow.

Sub-packages, each a floor above the ones it uses (docs/ARCHITECTURE.md):

* :mod:`swgsim.base` - typed configs, lazy exports, moved module paths;
  :mod:`swgsim.files` - atomic writes, digests, ownership stamps, provenance;
* :mod:`swgsim.gear` - the gear and its physics: dynamics, operating profiles, the
  flexspline truss, gauges, the simulation chain, faults, friction;
* :mod:`swgsim.sensing` - the measurement chain: sensor effects, the bench amplifier,
  angle channels, eq. (10), sensor faults;
* :mod:`swgsim.datasets` - data sets: config and schedules, plan, shard runners, lives,
  the schema on disk, generation.

The public API is listed in ``__all__``; names are imported on first use, so that
``import swgsim`` stays cheap::

    import swgsim
    chain = swgsim.SimulationChain()
    p = swgsim.apply_fault(swgsim.ChainParams(gear=swgsim.rt1_size20()), "eccentric_wg", 0.1)
"""

from __future__ import annotations

from importlib.metadata import PackageNotFoundError, version

from swgsim.base import moved
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

#: Module paths before the sub-packages (release 0.1) -> the modules that now hold their
#: names: they still import, with a DeprecationWarning, until release 0.3.
MOVED = {
    "swgsim.acquisition": ["swgsim.sensing.acquisition"],
    "swgsim.angles": ["swgsim.sensing.angles"],
    "swgsim.chain": ["swgsim.gear.chain"],
    "swgsim.config": ["swgsim.datasets.config", "swgsim.base.typed"],
    "swgsim.data": ["swgsim.datasets.schema", "swgsim.files.atomic", "swgsim.files.digest",
                    "swgsim.files.ownership"],
    "swgsim.disturbance": ["swgsim.sensing.disturbance"],
    "swgsim.dsp": ["swgsim.sensing.dsp"],
    "swgsim.dynamics": ["swgsim.gear.dynamics"],
    "swgsim.faults": ["swgsim.gear.faults"],
    "swgsim.flexspline": ["swgsim.gear.flexspline"],
    "swgsim.friction": ["swgsim.gear.friction"],
    "swgsim.friction.effects": ["swgsim.gear.friction.effects"],
    "swgsim.friction.ripples": ["swgsim.gear.friction.ripples"],
    "swgsim.friction.signals": ["swgsim.gear.friction.signals"],
    "swgsim.friction.simulation": ["swgsim.gear.friction.simulation"],
    "swgsim.generate": ["swgsim.datasets.generate"],
    "swgsim.influence": ["swgsim.gear.influence"],
    "swgsim.lazy": ["swgsim.base.lazy"],
    "swgsim.life": ["swgsim.datasets.life", "swgsim.datasets.records",
                    "swgsim.datasets.schedule"],
    "swgsim.life_profile": ["swgsim.datasets.slots", "swgsim.datasets.records"],
    "swgsim.measurement": ["swgsim.sensing.effects"],
    "swgsim.modes": ["swgsim.gear.modes"],
    "swgsim.outdir": ["swgsim.datasets.outdir", "swgsim.files.provenance"],
    "swgsim.ownership": ["swgsim.files.ownership"],
    "swgsim.plan": ["swgsim.datasets.plan", "swgsim.datasets.gears"],
    "swgsim.profile": ["swgsim.gear.profile"],
    "swgsim.profile_dynamics": ["swgsim.gear.profile_dynamics"],
    "swgsim.resources": ["swgsim.datasets.resources"],
    "swgsim.sensor_faults": ["swgsim.sensing.sensor_faults"],
    "swgsim.sensors": ["swgsim.gear.sensors"],
    "swgsim.shard": ["swgsim.datasets.grid_shard", "swgsim.datasets.generate",
                     "swgsim.datasets.profile_shard", "swgsim.datasets.steps"],
    "swgsim.terms": ["swgsim.gear.terms"],
}
moved.install(MOVED, "0.3")

__all__ = ["__version__", *_EXPORTS]


__getattr__, __dir__ = lazy_exports(__name__, _EXPORTS)
