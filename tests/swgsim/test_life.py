"""Gear lives (swgsim.datasets.life): schedules, state labels, determinism, sensor faults, the
shortcut the evaluation takes (a fault life equals the healthy life before its onset),
and lives written by swgsim-generate."""

import dataclasses

import numpy as np
import pytest

from swgcli import dataset_preset
from swgsim.base.typed import check_tree
from swgsim.datasets.config import dataset_config
from swgsim.datasets.life import LifeSimulator
from swgsim.datasets.plan import plan
from swgsim.datasets.records import RecordBank
from swgsim.datasets.schedule import (
    DutyPoint,
    FaultOnset,
    LifeConfig,
    schedule,
    severity_at,
)


@pytest.fixture(scope="module")
def tiny():
    cfg = dataset_config(dataset_preset("tiny_bench"))
    cfg.gears = cfg.gears[:1]
    return plan(cfg)


OPS = ([2000.0, 4000.0], [7.0, 70.0])


def test_schedule_step_labels_and_duty_cycle():
    life = LifeConfig(hours=3, commissioning_h=1,
                      fault=FaultOnset("eccentric_wg", 2.0, 0.1))
    s = schedule(life, *OPS)
    assert len(s.hour) == 180 and np.all(np.diff(s.hour) > 0)
    assert np.array_equal(s.commissioning, s.hour < 1.0)
    assert np.all(s.fault[s.hour < 2.0] == "healthy") and np.all(s.severity[s.hour < 2.0] == 0)
    assert np.all(s.fault[s.hour >= 2.0] == "eccentric_wg")
    assert np.all(s.severity[s.hour >= 2.0] == 0.1)
    # four duty points, 10 min each, in turn
    assert list(s.duty_index[:41:10]) == [0, 1, 2, 3, 0]
    assert np.all(s.duty_index[:10] == 0)


def test_growth_is_a_staircase_of_the_schedule():
    f = FaultOnset("reduced_damping", 10.0, 0.4, growth="linear", growth_h=4.0)
    h = np.array([9.9, 10.0, 11.0, 12.0, 13.9, 14.0, 20.0])
    sev = severity_at(f, h, levels=4)
    assert sev.tolist() == pytest.approx([0.0, 0.1, 0.1, 0.2, 0.3, 0.4, 0.4])
    pts = FaultOnset("root_tooth_crack", 5.0, 0.9, growth="points",
                     points=[[5.0, 0.5], [7.0, 0.7], [9.0, 0.9]])
    sev = severity_at(pts, np.array([4.0, 5.0, 6.0, 7.0, 9.0]), levels=9)
    assert sev.tolist() == pytest.approx([0.0, 0.5, 0.6, 0.7, 0.9])


@pytest.mark.parametrize("change, key", [
    ({"commissioning_h": 5.0, "hours": 4.0}, "commissioning_h"),
    ({"fault": FaultOnset("eccentric_wg", 0.5, 0.1)}, "onset_h"),
    ({"fault": FaultOnset("eccentric_wg", 2.0, 0.9)}, "outside the allowed range"),
    ({"fault": FaultOnset("bent_shaft", 2.0, 0.1)}, "unknown fault"),
    ({"fault": FaultOnset("sensor_offset_step", 2.0, 0.01, sensor=7)}, "fault.sensor"),
    ({"interval_min": 0.0}, "interval_min"),
])
def test_check_life_refuses_bad_values(change, key):
    life = dataclasses.replace(LifeConfig(hours=4, commissioning_h=1), **change)
    with pytest.raises(ValueError, match=key):
        check_tree(life, "dataset.life")


def test_windows_deterministic_and_slice_independent(tiny):
    life = LifeConfig(hours=1.5, commissioning_h=1.0,
                      fault=FaultOnset("root_tooth_crack", 1.2, 0.9))
    a = LifeSimulator(tiny, 1, life)
    s_all, m_all = a.windows(0, len(a))
    b = LifeSimulator(tiny, 1, life)
    s_part, m_part = b.windows(50, 80)
    assert np.array_equal(s_part, s_all[50:80])
    assert np.array_equal(m_part["hour"], m_all["hour"][50:80])
    # the state labels follow the schedule
    sch = a.schedule
    assert np.array_equal(m_all["fault"], sch.fault.astype(str))
    assert np.array_equal(m_all["severity"], sch.severity)
    assert np.all(np.isfinite(m_all["position_deg"][m_all["fault"] != "healthy"]))
    assert np.all(np.isnan(m_all["position_deg"][m_all["fault"] == "healthy"]))


def test_fault_life_equals_healthy_life_before_onset(tiny):
    """The evaluation starts a fault life at its onset from the healthy life's state."""
    healthy = LifeConfig(hours=1.5, commissioning_h=1.0)
    bank = RecordBank(tiny, 1)
    h = LifeSimulator(tiny, 1, healthy, bank)
    f = LifeSimulator(tiny, 1, dataclasses.replace(
        healthy, fault=FaultOnset("tip_tooth_crack", 1.25, 1.0)), bank)
    sh, _ = h.windows(0, len(h))
    sf, mf = f.windows(0, len(f))
    pre = mf["hour"] < 1.25
    assert np.array_equal(sh[pre], sf[pre])
    assert not np.allclose(sh[~pre], sf[~pre])


def test_a_record_is_the_same_whichever_batch_simulates_it(tiny):
    """Records are simulated in batches (RecordBank.simulate); the evaluation's parts of
    one held-out gear share a bank, so a record must not depend on what else was asked
    for with it: the same bits alone and in a batch of other states and loads."""
    keys = [("eccentric_wg", 0.1, 90.0), ("healthy", 0.0, 0.0), ("eccentric_wg", 0.02, 12.0)]
    batch = [RecordBank.key(DutyPoint(4000.0, t), f, s, x) for t in (7.0, 70.0)
             for f, s, x in keys]
    alone, together = RecordBank(tiny, 1), RecordBank(tiny, 1)
    together.want(batch)
    a, b = alone.get(batch[0]), together.get(batch[0])
    assert a.keys() == b.keys()
    assert all(np.array_equal(a[n], b[n]) for n in a)


def test_sensor_fault_on_one_bridge_after_onset(tiny):
    """(One bank for both lives: a sensor fault's records are the healthy gear's; that a
    life does not depend on its bank is test_windows_deterministic_and_slice_independent's.)"""
    healthy = LifeConfig(hours=1.2, commissioning_h=1.0)
    bank = RecordBank(tiny, 1)
    h = LifeSimulator(tiny, 1, healthy, bank)
    f = LifeSimulator(tiny, 1, dataclasses.replace(
        healthy, fault=FaultOnset("sensor_offset_step", 1.1, 0.05, sensor=2)), bank)
    sh, _ = h.windows(0, len(h))
    sf, mf = f.windows(0, len(f))
    on = mf["fault"] == "sensor_offset_step"
    assert on.any() and np.array_equal(sh[~on], sf[~on])
    d = (sf[on] - sh[on]).astype(float)
    lsb = tiny.config.acquisition.amplifier.lsb_mvv
    assert np.allclose(d[:, 2], 0.05, atol=2 * lsb)
    assert np.allclose(d[:, [0, 1, 3, 4]], 0.0, atol=2 * lsb)


def test_a_gain_drift_scales_the_bridges_strain_not_its_zero_offset(tiny):
    """A gauge that debonds passes less strain, not less imbalance: the faulty bridge reads
    z + (1 - severity)(s - z) (docs/PHYSICS.md sec. 8.2), within the converter's noise
    (without eq. (10), which the fault would scale too)."""
    healthy = LifeConfig(hours=1.2, commissioning_h=1.0, disturbed=False)
    bank = RecordBank(tiny, 1)
    h = LifeSimulator(tiny, 1, healthy, bank)
    f = LifeSimulator(tiny, 1, dataclasses.replace(
        healthy, fault=FaultOnset("sensor_gain_drift", 1.1, 0.1, sensor=2)), bank)
    z = h.zero_offsets_mvv[2]
    assert abs(z) > 0.05  # the gear's s2 is far from balanced
    sh, _ = h.windows(0, len(h))
    sf, mf = f.windows(0, len(f))
    on = mf["fault"] == "sensor_gain_drift"
    err = sf[on][:, 2] - (z + 0.9 * (sh[on][:, 2].astype(float) - z))
    amp = tiny.config.acquisition.amplifier  # what differs is 0.1 of the noise, and the LSB
    assert np.abs(err).max() < 6 * 0.1 * amp.noise_mvv + 2 * amp.lsb_mvv
    assert abs(err.mean()) < 0.01 * abs(z)  # scaling z too would leave 0.1 z


def test_generate_writes_and_resumes_a_life(tmp_path):
    from swgsim.datasets.generate import generate
    from swgsim.datasets.schema import load

    cfg = dataset_config(dataset_preset("tiny_life"))
    cfg.gears = cfg.gears[:1]
    cfg.life.hours, cfg.life.commissioning_h = 1.0, 0.5
    cfg.life.fault = FaultOnset("eccentric_wg", 0.75, 0.1)
    out = generate(cfg, tmp_path / "life", progress=False)
    assert out["complete"] and out["windows"] == 60
    ds = load(tmp_path / "life")
    assert ds["hour"].attrs["units"] == "h"
    assert ds["commissioning"].values.sum() == 30
    assert set(ds["fault"].values[ds["hour"].values >= 0.75]) == {"eccentric_wg"}
    again = generate(cfg, tmp_path / "life", progress=False)
    assert again["computed"] == [] and again["content_sha256"] == out["content_sha256"]
