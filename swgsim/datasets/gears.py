"""Per-gear parameters of a data set: each gear's dynamic parameters and gauge layout.

The data set's gears (``dataset.gears``, paper Table IV) differ in b1 and k1 and in their
gauges' placement and gain tolerances (``tolerance_seed``); every part of generation
that simulates a gear takes its parameters and layout from here.
"""

from __future__ import annotations

import dataclasses

from swgsim.datasets.config import DatasetConfig, GearConfig
from swgsim.gear.dynamics import gear_with_ke, rt1_size20
from swgsim.gear.faults import ChainParams
from swgsim.gear.sensors import SensorLayout, gear_layout

__all__ = ["gear_params", "layout_for"]


def layout_for(cfg: DatasetConfig, gear: GearConfig) -> SensorLayout:
    """The sensor layout of one gear, with its placement and gain tolerances."""
    return gear_layout(cfg.sensors, cfg.tolerances, gear.tolerance_seed)


def gear_params(cfg: DatasetConfig, gear: GearConfig) -> ChainParams:
    """Healthy ChainParams of one gear (paper Table IV factors on b1 and k1, the data
    set's output inertia, the gear's extra kinematic-error harmonics ``ke_extra``)."""
    p = rt1_size20()
    p = dataclasses.replace(p, b1_nms=p.b1_nms * float(gear.b1_factor),
                            k1_nm_per_rad=p.k1_nm_per_rad * float(gear.k1_factor),
                            j_out_kgm2=float(cfg.load.j_out_kgm2))
    return ChainParams(gear=gear_with_ke(p, gear.ke_extra))
