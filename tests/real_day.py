"""The tiny real day's lives shared by its test modules (not a test module):
``tests/learn/test_real_day.py`` and ``tests/learn/test_temperature_sensor.py``, whose
fixtures (``tests/learn/conftest.py``) plant them."""

from __future__ import annotations

import dataclasses

from swgmon.assessment.gear_monitor import GearMonitor
from swgmon.detection.normal import Conditions
from swgmon.detection.rule import RuleConfig
from swgmon.evaluation.training import features_of
from swgsim.datasets.life import LifeSimulator
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


def commissioned(model, day):
    """The healthy day's monitor commissioned on its first ``commissioning_h``:
    ``(monitor, simulator, commissioning's window count, its features, points,
    conditions)``."""
    p, bank = day
    life = p.config.life
    sim = LifeSimulator(p, 3, life, bank)
    n_comm = int(round(life.commissioning_h * 60 / life.interval_min))
    f, pts, meta = features_of(sim, 0, n_comm)
    cond = Conditions.of(meta)
    mon = GearMonitor(model, RuleConfig(), life.interval_min)
    mon.commission(f, pts, cond)
    return mon, sim, n_comm, f, pts, cond
