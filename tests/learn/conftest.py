"""The tiny real day's fixtures (preset tiny_real_day, gear 3), for the monitor's tests
through it: ``test_real_day.py`` and ``test_temperature_sensor.py``, each building its own
(module scope)."""

from __future__ import annotations

import dataclasses

import pytest
from real_day import growing, repaired

from swgcli import dataset_preset
from swgmon.evaluation.study import MonitorStudyConfig
from swgmon.evaluation.training import train_model
from swgsim.datasets.config import dataset_config
from swgsim.datasets.life import LifeSimulator, life_dataset
from swgsim.datasets.plan import plan
from swgsim.datasets.records import record_bank
from swgsim.datasets.schedule import FaultOnset


@pytest.fixture(scope="module")
def model():
    """The diagnosis model trained on gears 1 and 2 of the tiny bench at the preset's three
    loads, healthy and with an eccentric WG (as the monitor's evaluation trains it)."""
    cfg = dataset_preset("tiny_real_day")
    cfg["gears"] = dataset_preset("tiny_bench")["gears"][:2]
    cfg["life"] = None
    p = plan(dataset_config(cfg))
    study = MonitorStudyConfig(commissioning_h=4.0, train_healthy_h=2.0, train_fault_h=0.5,
                               train_variants=1, faults=["eccentric_wg"], nuisances={},
                               interval_min=2.0)
    return train_model(p, {g: record_bank(p, g) for g in (1, 2)}, [1, 2], study)


@pytest.fixture(scope="module")
def day():
    """The preset's plan and gear 3's records, shared by its healthy and faulty days. The
    records of every fault the two modules' days plant are asked for here, with the
    healthy day's, and simulated together at its first window (a batch costs seconds
    whatever it holds; a record is the same whichever batch simulates it)."""
    p = plan(dataset_preset("tiny_real_day"))
    bank, life = record_bank(p, 3), p.config.life
    for lf in (growing(life), repaired(life),
               *(dataclasses.replace(life, fault=FaultOnset("eccentric_wg", 40.0, s))
                 for s in (0.1, 0.05))):
        LifeSimulator(p, 3, lf, bank)  # asks for its records
    return p, bank


@pytest.fixture(scope="module")
def healthy(day):
    """The preset's healthy gear through its real day, in memory as the generator makes
    its shard (streams read from disk: tests/learn/test_monitor.py)."""
    p, bank = day
    return life_dataset(LifeSimulator(p, 3, p.config.life, bank))
