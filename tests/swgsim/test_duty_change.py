"""A new program in service (swgsim.datasets.conditions.DutyChange, issue 83's "duty
changes"): off, the schedule and the config hash as before; on, the windows from its hour
follow the cycle again with the new dwells; refusals in one line naming the key."""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest

from swgcli import dataset_preset
from swgsim.base.typed import check_tree
from swgsim.datasets.conditions import LOAD_SHIFT_BASE, ConditionsConfig, DutyChange
from swgsim.datasets.config import dataset_config
from swgsim.datasets.life import LifeSimulator
from swgsim.datasets.plan import config_hash, plain_config, plan
from swgsim.datasets.schedule import DutyPoint, LifeConfig, n_windows, schedule

OPS = ([2000.0, 4000.0], [7.0, 39.0, 70.0])
#: Nothing changes but the duty: no temperature, friction law, drift or reading.
STILL = ConditionsConfig(thermal=None, viscosity=False, bridge_drift=None,
                         temperature_sensor=None)


def _with(life: LifeConfig, change: DutyChange | None) -> LifeConfig:
    return dataclasses.replace(life, conditions=dataclasses.replace(STILL, duty_change=change))


def _old_index(life: LifeConfig, duty: list[DutyPoint]) -> np.ndarray:
    """The schedule's duty index as written before duty changes."""
    minutes = np.arange(n_windows(life)) * float(life.interval_min)
    edges = np.cumsum([d.dwell_min for d in duty])
    return np.searchsorted(edges, minutes % edges[-1], side="right")


@pytest.mark.parametrize("life", [
    LifeConfig(hours=30.0, commissioning_h=1.0),
    LifeConfig(hours=7.3, commissioning_h=1.0, interval_min=0.7,
               duty=[DutyPoint(2000.0, 7.0, 3.3), DutyPoint(4000.0, 70.0, 11.9),
                     DutyPoint(3000.0, 39.0, 0.4)]),
])
def test_without_a_change_the_schedule_is_as_before(life):
    want = _old_index(life, schedule(life, *OPS).duty)
    for lived in (life, _with(life, None)):
        s = schedule(lived, *OPS)
        assert s.duty_index.dtype == np.int64 and np.array_equal(s.duty_index, want)
    # neutral factors at a cycle's boundary (60 min of six 10-min points): the same windows
    if not life.duty:
        same = _with(life, DutyChange(5.0, [1.0] * 6))
        assert np.array_equal(schedule(same, *OPS).duty_index, want)


@pytest.mark.parametrize("change", [DutyChange(40.0, load_shift=1.0),
                                    DutyChange(40.0, load_shift=-0.5),
                                    DutyChange(40.0, [1.0, 0.2, 3.0, 1.0, 0.2, 3.0])])
def test_from_the_change_on_the_windows_follow_the_new_dwells(change):
    """Shares of the windows at each torque before and after the change: a third each
    before (six 10-min points), the new dwells' shares after; the cycle restarts at the
    change's hour."""
    life = _with(LifeConfig(hours=100.0, commissioning_h=1.0), change)
    s = schedule(life, *OPS)
    t = np.array([d.t_out_nm for d in s.duty])[s.duty_index]
    before, after = s.hour < change.hour_h, s.hour >= change.hour_h
    assert np.array_equal(s.duty_index[before],
                          schedule(dataclasses.replace(life, conditions=None),
                                   *OPS).duty_index[before])
    f = change.factors([d.t_out_nm for d in s.duty], "c")
    for torque in OPS[1]:
        at = np.array([d.t_out_nm == torque for d in s.duty])
        assert np.mean(t[before] == torque) == pytest.approx(1 / 3, abs=0.01)
        assert np.mean(t[after] == torque) == pytest.approx(f[at].sum() / f.sum(), abs=0.01)
    assert s.duty_index[np.argmax(after)] == 0  # the new program starts its cycle
    high = np.mean(t[after] == 70.0)
    assert high > 1 / 3 + 0.05 if f[2] > 1 else high < 1 / 3 - 0.05


def test_a_load_shift_puts_its_factors_on_the_torques():
    c = DutyChange(1.0, load_shift=1.0)
    assert c.factors([7.0, 39.0, 70.0], "c") == pytest.approx(
        [1 / LOAD_SHIFT_BASE, LOAD_SHIFT_BASE ** ((78 - 77) / 63), LOAD_SHIFT_BASE])
    assert np.all(c.factors([39.0, 39.0], "c") == 1.0)  # one torque: no shift
    assert DutyChange(1.0, load_shift=0.0).factors([7.0, 70.0], "c").tolist() == [1.0, 1.0]


def test_a_wrong_number_of_factors_is_refused_in_one_line_naming_the_key():
    life = _with(LifeConfig(hours=3.0, commissioning_h=1.0), DutyChange(2.0, [1.0, 2.0]))
    with pytest.raises(ValueError, match=r"^life\.conditions\.duty_change\.dwell_factors must "
                                         r"hold 6 factors, one per duty point of the cycle, "
                                         r"got 2$"):
        schedule(life, *OPS)
    cfg = dataset_preset("tiny_life")
    cfg["life"]["conditions"] = {"duty_change": {"hour_h": 5.0, "dwell_factors": [1.0] * 3}}
    with pytest.raises(ValueError, match=r"^dataset\.life\.conditions\.duty_change\."
                                         r"dwell_factors must hold 2 factors") as e:
        plan(dataset_config(cfg))
    assert "\n" not in str(e.value)


@pytest.mark.parametrize(("change", "key"), [
    ({"hour_h": 5.0}, r"^dataset\.life\.conditions\.duty_change: give dwell_factors or "
                      r"load_shift, one of them"),
    ({"hour_h": 5.0, "dwell_factors": [1.0, 1.0], "load_shift": 0.5},
     r"^dataset\.life\.conditions\.duty_change: give dwell_factors or load_shift"),
    ({"hour_h": 5.0, "dwell_factors": [1.0, 30.0]},
     r"^dataset\.life\.conditions\.duty_change\.dwell_factors\[1\] must lie in \[0\.05, 20\]"),
    ({"hour_h": 5.0, "load_shift": 1.5},
     r"^dataset\.life\.conditions\.duty_change\.load_shift must lie in \[-1, 1\]"),
    ({"hour_h": 9.0, "load_shift": 0.5},
     r"^dataset\.life\.conditions\.duty_change\.hour_h must lie in \[0, 8\] h \(an operating "
     r"hour inside the life\), got 9\.0$"),
    ({"load_shift": 0.5}, r"dataset\.life\.conditions\.duty_change\.hour_h: missing"),
])
def test_a_bad_duty_change_is_refused_naming_the_key(change, key):
    cfg = dataset_preset("tiny_life")
    cfg["life"]["conditions"] = {"duty_change": change}
    with pytest.raises(ValueError, match=key):
        plan(dataset_config(cfg))


def test_a_duty_change_on_a_profile_is_refused():
    cfg = dataset_preset("tiny_motion_life")
    cfg["life"]["conditions"] = {"duty_change": {"hour_h": 1.0, "load_shift": 0.5}}
    with pytest.raises(ValueError, match=r"duty_change: duty changes are for lives at steady"):
        plan(dataset_config(cfg))


def test_a_duty_change_is_left_out_of_the_hash_until_set():
    cfg = dataset_config(dataset_preset("tiny_real_day"))
    assert "duty_change" not in plain_config(cfg)["life"]["conditions"]
    changed = dataclasses.replace(cfg, life=dataclasses.replace(cfg.life, conditions=(
        dataclasses.replace(cfg.life.conditions, duty_change=DutyChange(2.0, load_shift=0.5)))))
    check_tree(changed, "dataset")
    assert plain_config(changed)["life"]["conditions"]["duty_change"] == {
        "hour_h": 2.0, "dwell_factors": [], "load_shift": 0.5}
    assert config_hash(changed) != config_hash(cfg)


def test_a_lifes_windows_follow_its_new_program(tiny_bench):
    """Gear 3 of the tiny bench, 3 h at two points, more time at 70 N m from 2 h on: the
    windows before the change are those of the life without it, bit for bit; after it, each
    is cut at its new duty point, and where that is the old one the window is the old one."""
    p, banks = tiny_bench
    base = LifeConfig(hours=3.0, commissioning_h=1.0, interval_min=2.0,
                      duty=[DutyPoint(4000.0, 7.0, 10.0), DutyPoint(4000.0, 70.0, 10.0)])
    old = LifeSimulator(p, 3, _with(base, None), banks[3])
    new = LifeSimulator(p, 3, _with(base, DutyChange(2.0, load_shift=1.0)), banks[3])
    s0, m0 = old.windows(0, len(old))
    s1, m1 = new.windows(0, len(new))
    before = m1["hour"] < 2.0
    same = old.schedule.duty_index == new.schedule.duty_index
    assert np.all(same[before]) and not np.all(same)
    assert np.array_equal(s0[same], s1[same])
    torque = np.array([d.t_out_nm for d in base.duty])[new.schedule.duty_index]
    assert np.array_equal(m1["t_out_nm"], torque)
    assert np.mean(torque[~before] == 70.0) > 0.8  # 40 of every 42.5 min at 70 N m
