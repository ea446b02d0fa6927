"""The tiny real day's lives shared by its test modules (not a test module):
``tests/learn/test_real_day.py`` and ``tests/learn/test_temperature_sensor.py``, whose
fixtures (``tests/learn/conftest.py``) plant them."""

from __future__ import annotations

import dataclasses

from swgsim.datasets.schedule import FaultOnset
from swgsim.gear.thermal import FrictionLaw


def growing(life):
    """The day to 70 h with an eccentric WG growing linearly from 0 at 26 h to 0.05 40 h
    later, the friction following a linear law."""
    cond = dataclasses.replace(life.conditions, friction_law=FrictionLaw("linear", 0.8))
    return dataclasses.replace(life, hours=70.0, conditions=cond, fault=FaultOnset(
        "eccentric_wg", 26.0, 0.05, growth="linear", growth_h=40.0))


def repaired(life):
    """The day to 72 h with an eccentric WG from 30 h, repaired at 34 h (the fault gone),
    the friction following a linear law."""
    cond = dataclasses.replace(life.conditions, friction_law=FrictionLaw("linear", 0.8))
    fault = FaultOnset("eccentric_wg", 30.0, 0.1, growth="points",
                       points=[[30.0, 0.0], [30.05, 0.1], [34.0, 0.1], [34.05, 0.0]])
    return dataclasses.replace(life, hours=72.0, conditions=cond, fault=fault)
