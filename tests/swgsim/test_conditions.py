"""A gear life's changing conditions (swgsim/datasets/conditions.py): neutral conditions
change nothing, each effect does what its model says, and bad settings are refused
naming the key; the presets leave the conditions off."""

from __future__ import annotations

import dataclasses
import os
from pathlib import Path

import numpy as np
import pytest
from data_sets import PRESET_HASHES
from omegaconf import OmegaConf

from swgcli import compose_app, dataset_preset
from swgcli.app import one_line
from swgsim.base.typed import LATER, without_later_defaults
from swgsim.datasets import conditions
from swgsim.datasets.conditions import (
    ConditionsConfig,
    Regrease,
    RunInConfig,
    TemperatureTrace,
    trace_rise,
    trace_table,
)
from swgsim.datasets.config import dataset_config
from swgsim.datasets.generate import generate
from swgsim.datasets.life import LifeSimulator, ladder_weights
from swgsim.datasets.plan import config_hash, plain_config, plan
from swgsim.datasets.schedule import DutyPoint, LifeConfig
from swgsim.gear.thermal import (
    FRICTION_FORMS,
    FrictionLaw,
    JointThermal,
    ThermalNetwork,
    friction_scale,
    run_in_factor,
)
from swgsim.sensing.bridge_drift import (
    TEMPERATURE_SENSOR_FAULTS,
    BridgeDrift,
    TemperatureSensor,
)

NEUTRAL = ConditionsConfig(thermal=None, viscosity=False, run_in=None, payload=[],
                           bridge_drift=None, temperature_sensor=None)


#: A 10 % heavier tool from 2 h on.
HEAVY = dataclasses.replace(NEUTRAL, payload=[[2.0, 1.1]])


@pytest.fixture(scope="module")
def tiny(tiny_bench):
    """The tiny bench's plan with gear 3's records, shared by every life of this module and
    the worker's other tests of the bench (tests/conftest.py; a record is simulated once,
    at its first window); the heavier tool's loads asked for with the first life's."""
    p, banks = tiny_bench
    LifeSimulator(p, 3, _life(HEAVY), banks[3])  # asks for its records
    return p, banks[3]


def _life(conditions, hours: float = 3.0) -> LifeConfig:
    return LifeConfig(hours=hours, commissioning_h=1.0, interval_min=2.0,
                      duty=[DutyPoint(4000.0, 7.0, 10.0), DutyPoint(4000.0, 70.0, 10.0)],
                      conditions=conditions)


def _sim(tiny, conditions, hours: float = 3.0) -> LifeSimulator:
    return LifeSimulator(tiny[0], 3, _life(conditions, hours), tiny[1])


def _windows(tiny, conditions, hours: float = 3.0):
    sim = _sim(tiny, conditions, hours)
    return sim.windows(0, len(sim))


def test_neutral_conditions_change_no_window(tiny):
    s0, m0 = _windows(tiny, None)
    s1, m1 = _windows(tiny, NEUTRAL)
    assert np.array_equal(s0, s1) and sorted(m0) == sorted(m1)
    for k in m0:
        np.testing.assert_array_equal(m0[k], m1[k])  # NaN positions equal too


def test_the_bridges_drift_by_their_gain_and_zero_at_the_temperature(tiny):
    thermal = ConditionsConfig(thermal=JointThermal(), viscosity=False, bridge_drift=None,
                               temperature_sensor=TemperatureSensor(0.0, 0.0))
    drift = dataclasses.replace(thermal, bridge_drift=BridgeDrift())
    base = _sim(tiny, thermal)
    sim = _sim(tiny, drift)
    rows = np.arange(len(sim))
    gain, _ = sim.conditions.bridge_gain_offset(rows)
    drift = sim.conditions.zero_mvv_per_k * (sim.conditions.temperature_c[rows, None]
                                             - sim.conditions.drift_ref_c)
    z = sim.zero_offsets_mvv  # the bridges' zero offsets: the span drift leaves them
    assert np.all(np.abs(z) > 0)
    # the windows go through the converter after the drift: compare before it, by the
    # converter-free acquisition of the same windows
    s0, m0 = base._cut(rows, [np.random.default_rng(0) for _ in rows])[:2]
    s1, _ = sim._cut(rows, [np.random.default_rng(0) for _ in rows])[:2]
    sim._condition(rows, m0, s1, np.ones(len(rows)))
    want = gain[:, :, None] * (s0 - z[None, :, None]) + z[None, :, None] + drift[:, :, None]
    np.testing.assert_allclose(s1, want, rtol=0, atol=1e-12)
    temp = sim.conditions.temperature_c
    assert temp[0] == pytest.approx(20.0) and temp.max() > 30.0  # a cold start, warming


def test_warmth_and_run_in_move_the_efficiency_as_the_friction_law_says(tiny):
    still = dataclasses.replace(NEUTRAL, temperature_sensor=TemperatureSensor(0.0, 0.0))
    warm = dataclasses.replace(still, thermal=JointThermal(ambient_swing_k=0.0),
                               viscosity=True)
    new = dataclasses.replace(still, run_in=RunInConfig())
    _, m0 = _windows(tiny, still)
    _, mw = _windows(tiny, warm)
    _, mn = _windows(tiny, new)
    later = m0["hour"] > 1.0
    assert np.all(mw["efficiency"][later] > m0["efficiency"][later])  # thinner grease
    assert np.all(mn["efficiency"] < m0["efficiency"])  # a new gear's extra friction


def test_the_friction_follows_the_law_drawn_for_the_joint(tiny):
    warm = dataclasses.replace(NEUTRAL, thermal=JointThermal(ambient_swing_k=0.0),
                               viscosity=True)
    default = _sim(tiny, warm).conditions
    temp = default.temperature_c
    np.testing.assert_array_equal(default.friction, friction_scale(temp))  # as before
    for form in FRICTION_FORMS:
        law = FrictionLaw(form, 0.8)
        c = _sim(tiny, dataclasses.replace(warm, friction_law=law)).conditions
        np.testing.assert_array_equal(c.temperature_c, temp)
        np.testing.assert_allclose(c.friction, law.factor(temp), rtol=1e-15)


def test_viscous_and_coulomb_friction_follow_their_own_laws_and_run_in_apart(tiny):
    """Issue 83: the Coulomb term (b0, and mu in run-in) follows its own temperature law
    and runs in by its own drop and time; unset, one factor on every term as before."""
    warm = dataclasses.replace(NEUTRAL, thermal=JointThermal(ambient_swing_k=0.0),
                               viscosity=True, run_in=RunInConfig(0.2, 10.0))
    one = _sim(tiny, warm).conditions
    assert one.coulomb is None
    law = FrictionLaw("u_shaped", 0.6, 45.0)
    split = dataclasses.replace(warm, coulomb_law=law,
                                run_in=RunInConfig(0.2, 10.0, coulomb_drop=0.05,
                                                   coulomb_tau_h=0.5))
    c = _sim(tiny, split).conditions
    h, temp = _sim(tiny, split).schedule.hour, c.temperature_c
    np.testing.assert_array_equal(c.friction, one.friction)  # the viscous terms as before
    np.testing.assert_allclose(c.mu_factor, 1.0 + 0.05 * np.exp(-h / 0.5), rtol=1e-14)
    np.testing.assert_allclose(c.coulomb, law.factor(temp) * c.mu_factor, rtol=1e-14)
    assert np.all(c.mu_factor[h > 2.0] < one.mu_factor[h > 2.0])  # run in sooner
    _, m1 = _windows(tiny, warm)
    _, m2 = _windows(tiny, split)
    assert not np.allclose(m1["efficiency"], m2["efficiency"])


def test_ladder_weights_are_quadratic_and_exact_on_their_rungs():
    f = np.array([0.3, 0.62, 1.0, 1.3, 2.9])
    rungs, w = ladder_weights(f)
    np.testing.assert_allclose(w.sum(axis=1), 1.0, rtol=0, atol=1e-12)
    np.testing.assert_allclose((w * (3 * rungs**2 - rungs + 2)).sum(axis=1),
                               3 * f**2 - f + 2, rtol=1e-12)  # a quadratic exactly
    assert np.array_equal(w[2], [0.0, 1.0, 0.0]) and rungs[2, 1] == 1.0
    with pytest.raises(ValueError, match=r"viscous friction factor of 5 lies outside"):
        ladder_weights(np.array([5.0]))


def test_a_joint_whose_friction_acts_in_its_dynamics_damps_as_its_grease_says(tiny, tmp_path):
    """Issue 83: with conditions.viscous_in_dynamics a warm joint's windows are those of
    the gear with b1, b2 times its factor (a warm grease damps less, as a reduced damping
    does), within 3 % of their change from the nominal gear; at factor 1 the same windows
    as without it."""
    warm = TemperatureTrace(str(_hours_table(tmp_path / "warm.csv", ((0.0, 40.0),))),
                            mode="hours")
    base = dataclasses.replace(NEUTRAL, viscosity=True, temperature_trace=warm)
    sim = _sim(tiny, dataclasses.replace(base, viscous_in_dynamics=True))
    nominal = _sim(tiny, base)
    f = float(friction_scale(40.0))
    assert np.all(sim.conditions.friction == f)
    rows = np.arange(len(sim))
    rngs = lambda: [np.random.default_rng(0) for _ in rows]  # noqa: E731
    got, keys = sim._cut(rows, rngs())[:2]
    before = nominal._cut(rows, rngs())[0]
    o0 = [int(np.random.default_rng(0).uniform() * tiny[1].get(k)["n_period"]) for k in keys]
    exact = np.stack([tiny[1].get(k[:5] + (f,))["signal"][:, o:o + got.shape[-1]]
                      for k, o in zip(keys, o0, strict=True)])

    def rms(x):
        return float(np.sqrt(np.mean(x**2)))
    change = rms(exact - before)
    assert change > 1e-5  # the damping shows in the bridges
    assert rms(got - exact) < 0.02 * change, (rms(got - exact), change)
    cold = dataclasses.replace(NEUTRAL, viscous_in_dynamics=True)  # factor 1 throughout
    a, b = (_sim(tiny, c) for c in (cold, NEUTRAL))
    sa, ma = a.windows(0, len(a))
    sb, mb = b.windows(0, len(b))
    assert np.array_equal(sa, sb)
    np.testing.assert_allclose(ma["efficiency"], mb["efficiency"], rtol=1e-13)


def test_a_heavier_tool_acts_at_its_load_while_the_commanded_point_stays(tiny):
    _, m0 = _windows(tiny, NEUTRAL)
    _, m1 = _windows(tiny, HEAVY)
    after = m1["hour"] >= 2.0
    assert np.array_equal(m1["t_out_nm"], m0["t_out_nm"])
    np.testing.assert_allclose(m1["t_out_mean_nm"][after], 1.1 * m0["t_out_mean_nm"][after],
                               rtol=2e-3)
    assert np.array_equal(m1["t_out_mean_nm"][~after], m0["t_out_mean_nm"][~after])


@pytest.mark.parametrize("edit, key", [
    ({"payload": [[5.0, 1.1]]}, r"dataset.life.conditions.payload\[0\]\[0\] must lie in "
                                r"\[0, 3\] h"),
    ({"payload": [[1.0, 0.0]]}, r"payload\[0\]\[1\] must lie in \(0, 10\]"),
    ({"payload": [[2.0, 1.1], [1.5, 1.2]]}, "hours must increase"),
    ({"run_in": {"drop": 2.0}}, r"dataset.life.conditions.run_in.drop must lie in \[0, 1\]"),
    ({"regrease": {"hours": [1.0, 4.0]}},
     r"^dataset.life.conditions.regrease.hours\[1\] must lie in \[0, 3\] h \(an operating "
     r"hour inside the life\), got 4.0$"),
    ({"regrease": {"hours": [2.0, 1.0]}},
     r"^dataset.life.conditions.regrease.hours must increase, got \[2.0, 1.0\]$"),
    ({"regrease": {"hours": []}}, r"dataset.life.conditions.regrease.hours must name at least"),
    ({"regrease": {"hours": [1.0], "drop": 1.2}},
     r"^dataset.life.conditions.regrease.drop must lie in \[0, 1\], got 1.2$"),
    ({"regrease": {"hours": [1.0], "tau_h": 0.0}},
     r"^dataset.life.conditions.regrease.tau_h must lie in \(0, 100000\] h, got 0.0$"),
    ({"regrease": {"drop": 0.2}}, r"dataset.life.conditions.regrease.hours: missing key"),
    ({"thermal": {"tau_min": -1.0}}, "dataset.life.conditions.thermal.tau_min"),
    ({"temperature_sensor": {"noise_sd_k": -1.0}},
     "dataset.life.conditions.temperature_sensor.noise_sd_k"),
    ({"temperature_sensor": {"fault": "frozen"}},
     r"^dataset.life.conditions.temperature_sensor.fault: 'frozen'; allowed: none, stuck, "
     r"drift, dropout$"),
    ({"temperature_sensor": {"fault": "stuck", "fault_hour": -2.0}},
     r"dataset.life.conditions.temperature_sensor.fault_hour must lie in \[0, inf\) h"),
])
def test_bad_conditions_are_refused_naming_the_key(edit, key):
    cfg = dataset_preset("tiny_life")
    cfg["life"]["hours"] = 3.0
    cfg["life"]["commissioning_h"] = 1.0
    cfg["life"]["fault"] = {"fault": "healthy"}
    cfg["life"]["conditions"] = edit
    with pytest.raises(ValueError, match=key):
        plan(dataset_config(cfg))


def test_payload_changes_on_a_profile_are_refused():
    cfg = dataset_preset("tiny_motion_life")
    cfg["life"]["conditions"] = {"payload": [[1.0, 1.1]]}
    with pytest.raises(ValueError, match="payload changes are for lives at steady operating "
                                         "points"):
        plan(dataset_config(cfg))


@pytest.mark.parametrize("preset", ["tiny", "tiny_life"])
def test_the_presets_leave_the_conditions_off(preset):
    """The presets set no conditions, so their windows are those of a life without them
    (:func:`test_neutral_conditions_change_no_window`, two runs in one environment); the
    config their data sets store (``plan.plain``, what every shard and the manifest
    write) names none. Across machines the arrays agree to the tolerance of
    ``test_reproducibility.py`` (a content hash is the bytes' identity, and the bytes
    depend on the processor's BLAS kernel)."""
    cfg = dataset_config(dataset_preset(preset))
    assert cfg.life is None or cfg.life.conditions is None
    assert "conditions" not in (plan(cfg).plain.get("life") or {})


def test_a_joint_heated_beyond_the_viscosity_laws_range_is_refused_naming_the_cause(tiny):
    hot = dataclasses.replace(NEUTRAL, thermal=JointThermal(r_th_k_per_w=50.0))
    with pytest.raises(ValueError, match=r"conditions.thermal: the joint reaches .* °C at "
                                         r"operating hour .*r_th_k_per_w 50 K/W.*\[-40, 150\]"):
        _sim(tiny, hot)


@dataclasses.dataclass
class _Leaf:
    old: float = 1.0
    new: float = dataclasses.field(default=0.0, metadata={LATER: "a test"})


@dataclasses.dataclass
class _Root:
    leaf: _Leaf = dataclasses.field(default_factory=_Leaf)
    leaves: list[_Leaf] = dataclasses.field(default_factory=lambda: [_Leaf(), _Leaf(new=2.0)])
    maybe: _Leaf | None = dataclasses.field(default=None, metadata={LATER: "a test"})


def test_later_fields_at_their_defaults_are_left_out_at_every_depth():
    """One rule for every option added after data sets were made (plain_config): a field
    marked LATER is left out while it holds its default, in nested, listed and optional
    parts; set, it stays, and so does every field not marked."""
    out = without_later_defaults(dataclasses.asdict(_Root()), _Root)
    assert out == {"leaf": {"old": 1.0}, "leaves": [{"old": 1.0}, {"old": 1.0, "new": 2.0}]}
    out = without_later_defaults(dataclasses.asdict(_Root(maybe=_Leaf(new=3.0))), _Root)
    assert out["maybe"] == {"old": 1.0, "new": 3.0}


def test_the_default_friction_law_keeps_a_data_sets_config_hash():
    cfg = dataset_config(dataset_preset("tiny_real_day"))
    assert "friction_law" not in plain_config(cfg)["life"]["conditions"]
    drawn = dataclasses.replace(cfg, life=dataclasses.replace(cfg.life, conditions=(
        dataclasses.replace(cfg.life.conditions, friction_law=FrictionLaw("linear", 0.7)))))
    assert plain_config(drawn)["life"]["conditions"]["friction_law"] == \
        {"form": "linear", "ratio_40c": 0.7}
    assert config_hash(drawn) != config_hash(cfg)


def test_a_faulty_temperature_sensor_changes_the_reading_alone(tiny):
    warm = dataclasses.replace(NEUTRAL, thermal=JointThermal(), viscosity=True,
                               temperature_sensor=TemperatureSensor())
    good = _sim(tiny, warm).conditions
    hour = _sim(tiny, warm).schedule.hour
    before = hour < 2.0
    for fault in TEMPERATURE_SENSOR_FAULTS[1:]:
        sensor = TemperatureSensor(fault=fault, fault_hour=2.0, drift_k_per_h=0.5)
        c = _sim(tiny, dataclasses.replace(warm, temperature_sensor=sensor)).conditions
        np.testing.assert_array_equal(c.temperature_c, good.temperature_c)
        np.testing.assert_array_equal(c.friction, good.friction)
        np.testing.assert_array_equal(c.reading_c[before], good.reading_c[before])
        assert not np.array_equal(c.reading_c[~before], good.reading_c[~before],
                                  equal_nan=True)


def test_a_lagging_sensor_lags_the_warm_ups_and_cools_with_the_joint_over_a_stop(tiny):
    """Issue 83: a reading 20 min behind the grease (TemperatureSensor.lag_min) stays
    behind it through each warm-up and is cold again after the night's stop (the lag runs
    in wall-clock time, the 8-h stop included), as the joint."""
    base = ConditionsConfig(thermal=JointThermal(run_h_per_day=16.0), viscosity=False,
                            bridge_drift=None)
    exact = dataclasses.replace(base, temperature_sensor=TemperatureSensor(0.0, 0.0))
    lagged = dataclasses.replace(base, temperature_sensor=TemperatureSensor(0.0, 0.0,
                                                                            lag_min=20.0))
    a, b = (_sim(tiny, c, hours=20.0).conditions for c in (exact, lagged))
    np.testing.assert_array_equal(a.reading_c, a.temperature_c)
    hours = _sim(tiny, exact, hours=20.0).schedule.hour
    warming = (hours > 0.1) & (hours < 1.0)  # the first warm-up, before the steady state
    assert np.all(b.reading_c[warming] < a.reading_c[warming] - 0.5)
    after = int(np.searchsorted(hours, 16.0))  # the first window after the stop
    assert a.temperature_c[after] < a.temperature_c[after - 1] - 5.0  # a cold start
    assert b.reading_c[after] == pytest.approx(a.temperature_c[after], abs=0.01)


def test_bridges_that_lag_the_joint_drift_apart_in_a_warm_up_and_together_after(tiny):
    """Issue 83: a temperature difference across the collar during a warm-up, so the
    bridges do not drift together: each bridge's temperature lags the joint's by its own
    time constant (BridgeDrift.lag_spread_min); apart by kelvins while the joint warms,
    together again at its steady state (within the lagged swings of its duty). Off, no
    bridge temperature at all (the windows of before, bit for bit:
    test_neutral_conditions_change_no_window and the hashes)."""
    base = ConditionsConfig(thermal=JointThermal(run_h_per_day=24.0), viscosity=False,
                            bridge_drift=BridgeDrift(), temperature_sensor=None)
    assert _sim(tiny, base, hours=6.0).conditions.bridge_temperature_c is None
    lag = dataclasses.replace(base, bridge_drift=BridgeDrift(lag_spread_min=30.0))
    sim = _sim(tiny, lag, hours=6.0)
    c, hours = sim.conditions, sim.schedule.hour
    tb = c.bridge_temperature_c  # (W, 5)
    assert tb.shape == (hours.size, 5)
    warming, steady = (hours > 0.2) & (hours < 0.6), hours > 5.0
    apart = np.ptp(tb[warming], axis=1).max()
    assert apart > 1.0  # apart by kelvins while it warms
    # together again in the steady state, but for the duty's own swings (10-min blocks)
    assert np.ptp(tb[steady], axis=1).max() < 0.25 * apart
    gain, _ = c.bridge_gain_offset(np.flatnonzero(warming))
    assert np.ptp(gain, axis=1).max() > 0  # so the bridges' spans drift apart too
    cfg = dataset_config(dataset_preset("tiny_real_day"))
    assert "lag_spread_min" not in plain_config(cfg)["life"]["conditions"]["bridge_drift"]


def test_a_two_node_joint_drives_friction_by_the_grease_and_the_reading_by_the_housing(tiny):
    """Issue 83: with JointThermal.network the friction follows the grease, the sensor
    reads the housing (lagging it and heated by the motor), and each bridge sits at its
    own place between the two, so the bridges drift apart while the grease leads."""
    net = JointThermal(ambient_swing_k=0.0, run_h_per_day=24.0, network=ThermalNetwork())
    cfg = ConditionsConfig(thermal=net, viscosity=True, bridge_drift=BridgeDrift(),
                           temperature_sensor=TemperatureSensor(0.0, 0.0))
    sim = _sim(tiny, cfg, hours=3.0)
    c = sim.conditions
    assert c.housing_c is not None and np.all(c.temperature_c[1:] > c.housing_c[1:])
    np.testing.assert_array_equal(c.reading_c, c.housing_c)
    np.testing.assert_allclose(c.friction, friction_scale(c.temperature_c), rtol=1e-15)
    span = c.temperature_c - c.housing_c
    w = (c.bridge_temperature_c[-1] - c.housing_c[-1]) / span[-1]  # each bridge's place
    assert np.all((w >= 0.2) & (w <= 0.8)) and np.ptp(w) > 0.05
    np.testing.assert_allclose(c.bridge_temperature_c, c.housing_c[:, None]
                               + w[None, :] * span[:, None], rtol=0, atol=1e-12)
    one = _sim(tiny, dataclasses.replace(cfg, thermal=dataclasses.replace(net, network=None)),
               hours=3.0).conditions
    assert one.housing_c is None and one.bridge_temperature_c is None


def test_a_faultless_sensor_keeps_a_data_sets_config_hash():
    """The faultless sensor's fields are left out of the config: tiny_real_day keeps its
    hash (tests/data_sets.py, as every preset's)."""
    cfg = dataset_config(dataset_preset("tiny_real_day"))
    assert config_hash(cfg) == PRESET_HASHES["tiny_real_day"]
    assert plain_config(cfg)["life"]["conditions"]["temperature_sensor"] == \
        {"resolution_k": 0.1, "noise_sd_k": 0.05}
    stuck = dataclasses.replace(cfg, life=dataclasses.replace(cfg.life, conditions=(
        dataclasses.replace(cfg.life.conditions, temperature_sensor=TemperatureSensor(
            fault="stuck", fault_hour=30.0)))))
    assert plain_config(stuck)["life"]["conditions"]["temperature_sensor"] == \
        {"resolution_k": 0.1, "noise_sd_k": 0.05, "fault": "stuck", "fault_hour": 30.0}
    assert config_hash(stuck) != config_hash(cfg)


def test_a_life_whose_sensor_drops_out_is_written_and_read_back_with_nan(tmp_path):
    from swgsim.datasets.schema import load

    cfg = dataset_config(dataset_preset("tiny_life"))
    cfg.gears = cfg.gears[:1]
    cfg.life.hours, cfg.life.commissioning_h = 1.0, 0.5
    cfg.life.conditions = ConditionsConfig(temperature_sensor=TemperatureSensor(
        fault="dropout", fault_hour=0.6))
    out = generate(cfg, tmp_path / "life", progress=False)
    assert out["complete"] and out["windows"] == 60
    ds = load(tmp_path / "life")
    hour, temp = ds["hour"].values, ds["temperature_c"].values
    assert np.all(np.isnan(temp[hour >= 0.6])) and np.all(np.isfinite(temp[hour < 0.6]))
    assert np.all(np.isfinite(ds["strain_signal"].values))


def test_regreasing_steps_the_friction_up_and_it_runs_in_again(tiny):
    rg = dataclasses.replace(NEUTRAL, regrease=Regrease([1.5], drop=0.3, tau_h=0.5))
    sim = _sim(tiny, rg)
    c, hour = sim.conditions, sim.schedule.hour
    after = hour >= 1.5
    np.testing.assert_array_equal(c.friction[~after], 1.0)
    np.testing.assert_allclose(c.friction[after], 1.0 + 0.3 * np.exp(-(hour[after] - 1.5) / 0.5),
                               rtol=1e-14)
    np.testing.assert_array_equal(c.mu_factor, c.friction)  # the mesh's μ too, as a run-in
    assert c.friction[after][0] == pytest.approx(1.3, abs=0.3 * 2 / 60 / 0.5 + 1e-12)
    _, m0 = _windows(tiny, NEUTRAL)
    _, m1 = _windows(tiny, rg)
    assert np.all(m1["efficiency"][after] < m0["efficiency"][after])  # more friction
    np.testing.assert_array_equal(m1["efficiency"][~after], m0["efficiency"][~after])
    both = dataclasses.replace(rg, run_in=RunInConfig())  # a new gear re-greased: the product
    c2 = _sim(tiny, both).conditions
    np.testing.assert_allclose(c2.friction, c.friction * run_in_factor(hour), rtol=1e-14)


def test_no_regreasing_keeps_a_data_sets_config_hash():
    cfg = dataset_config(dataset_preset("tiny_real_day"))
    assert "regrease" not in plain_config(cfg)["life"]["conditions"]
    greased = dataclasses.replace(cfg, life=dataclasses.replace(cfg.life, conditions=(
        dataclasses.replace(cfg.life.conditions, regrease=Regrease([30.0])))))
    assert plain_config(greased)["life"]["conditions"]["regrease"] == \
        {"hours": [30.0], "drop": 0.3, "tau_h": 8.0}
    assert config_hash(greased) != config_hash(cfg)
    plan(greased)  # checked and accepted


def _trace_csv(path: Path) -> Path:
    """A tiny trace in the UR3 CobotOps format: 0-30 min warming 0.2 K a minute, a missing
    reading at 10 min, then a 2-h gap and readings that must not count."""
    rows = ["Num;Timestamp;Temperature_J1;Other;"]
    t0 = np.datetime64("2022-10-26T08:00:00")
    for i in range(31):
        v = "" if i == 10 else f"{25.0 + 0.2 * i:.1f}".replace(".", ",")
        rows.append(f"{i + 1};{t0 + np.timedelta64(60 * i, 's')}Z;{v};1;")
    for i in range(5):
        rows.append(f"{32 + i};{t0 + np.timedelta64(9000 + 60 * i, 's')}Z;60,0;1;")
    path.write_text("\n".join(rows) + "\n")
    return path


def test_a_trace_rise_is_its_first_segment_against_its_first_reading(tmp_path):
    tr = TemperatureTrace(str(_trace_csv(tmp_path / "day.csv")), "Temperature_J1")
    t_h, rise = trace_rise(tr, "k")
    assert t_h.size == 30 and t_h[0] == 0.0 and t_h[-1] == pytest.approx(0.5)
    np.testing.assert_allclose(rise, 0.2 * t_h * 60.0, atol=1e-9)  # the 60 °C after the gap: not


def test_a_life_follows_the_measured_warm_up_after_every_cold_start(tiny, tmp_path):
    tr = TemperatureTrace(str(_trace_csv(tmp_path / "day.csv")), "Temperature_J1", scale=2.0)
    hall = JointThermal(ambient_swing_k=0.0, run_h_per_day=1.0)  # a cold start every hour
    cond = dataclasses.replace(NEUTRAL, thermal=hall, viscosity=True, temperature_trace=tr)
    sim = _sim(tiny, cond)
    hour, c = sim.schedule.hour, sim.conditions
    since = hour % 1.0
    np.testing.assert_allclose(c.temperature_c, 20.0 + 2.0 * np.minimum(since, 0.5) * 12.0,
                               atol=1e-9)  # 2 x 0.2 K/min, held from 30 min on
    np.testing.assert_array_equal(c.friction, friction_scale(c.temperature_c))


@pytest.mark.parametrize(("trace", "match"), [
    ({"path": "no/such.csv", "column": "Temperature_J1"},
     r"^dataset.life.conditions.temperature_trace.path: no file 'no/such.csv'$"),
    ({"path": "{csv}", "column": "Temperature_J9"},
     r"^dataset.life.conditions.temperature_trace.column: 'Temperature_J9' is not a column "
     r"of .*; columns: Num, Timestamp, Temperature_J1, Other$"),
    ({"path": "{csv}", "column": "Temperature_J1", "scale": 11.0},
     r"^dataset.life.conditions.temperature_trace.scale must lie in \[0, 10\], got 11.0$"),
])
def test_a_bad_temperature_trace_is_refused_naming_the_key(trace, match, tmp_path):
    csv = str(_trace_csv(tmp_path / "day.csv"))
    cfg = dataset_preset("tiny_life")
    cfg["life"].update(hours=3.0, commissioning_h=1.0, fault={"fault": "healthy"})
    cfg["life"]["conditions"] = {"temperature_trace": {
        k: (csv if v == "{csv}" else v) for k, v in trace.items()}}
    with pytest.raises(ValueError, match=match):
        plan(dataset_config(cfg))
    cfg["life"]["conditions"]["thermal"] = None
    with pytest.raises(ValueError, match=r"temperature_trace needs dataset.life.conditions."
                                         r"thermal"):
        plan(dataset_config(cfg))


def test_a_measured_warm_up_out_of_the_physical_range_is_refused_naming_its_row(tmp_path):
    """Issue 82: a rise-mode trace took any number: 1e30 °C in one cell gave a rise of 1e30
    K; now refused in one line naming the column and the row."""
    path = _trace_csv(tmp_path / "day.csv")
    rows = path.read_text().splitlines()
    rows[5] = rows[5].replace("25,8", "1e30")
    path.write_text("\n".join(rows) + "\n")
    tr = TemperatureTrace(str(path), "Temperature_J1")
    with pytest.raises(ValueError, match=r"^k.column: 'Temperature_J1' of .* must lie in "
                                         r"\[-40, 150\] °C, got 1e\+30 at row 5$"):
        trace_rise(tr, "k")


def test_no_temperature_trace_keeps_a_data_sets_config_hash(tmp_path):
    cfg = dataset_config(dataset_preset("tiny_real_day"))
    assert "temperature_trace" not in plain_config(cfg)["life"]["conditions"]
    tr = TemperatureTrace(str(_trace_csv(tmp_path / "day.csv")), "Temperature_J1")
    traced = dataclasses.replace(cfg, life=dataclasses.replace(cfg.life, conditions=(
        dataclasses.replace(cfg.life.conditions, temperature_trace=tr))))
    assert config_hash(traced) != config_hash(cfg)
    plan(traced)  # checked and accepted


def _hours_table(path: Path, rows=((0.5, 30.0), (1.5, 50.0), (2.0, 40.0))) -> Path:
    """A tiny table of mode 'hours': the joint's temperature on operating hours."""
    path.write_text("hour,temperature_c\n" + "".join(f"{h},{t}\n" for h, t in rows))
    return path


def test_a_life_replays_a_table_of_the_joints_temperature_on_its_hours(tiny, tmp_path):
    """Mode 'hours': the table's temperature on the life's operating hours, linear between
    its rows, the first held before them and the last beyond; no hall, no cold starts."""
    tr = TemperatureTrace(str(_hours_table(tmp_path / "j1.csv")), mode="hours")
    h, t = trace_table(tr, "k")
    np.testing.assert_array_equal(h, [0.5, 1.5, 2.0])
    sim = _sim(tiny, dataclasses.replace(NEUTRAL, viscosity=True, temperature_trace=tr))
    hour, c = sim.schedule.hour, sim.conditions
    assert hour.min() < 0.5 and hour.max() > 2.0  # both ends held
    np.testing.assert_allclose(c.temperature_c, np.interp(hour, h, t), atol=1e-12)
    np.testing.assert_array_equal(c.friction, friction_scale(c.temperature_c))


@pytest.mark.parametrize(("rows", "extra", "match"), [
    (((0.5, 30.0), (1.5, 50.0), (1.0, 40.0)), {},
     r"\.path: hour of .* must increase from >= 0 h, got 1 at row 3 after 1\.5$"),
    (((-1.0, 30.0), (1.5, 50.0)), {}, r"\.path: hour of .* must increase from >= 0 h, got -1 "
                                      r"at row 1$"),
    (((0.5, 30.0), (1.5, 170.0)), {},
     r"\.path: temperature_c of .* must lie in \[-40, 150\] °C, got 170 at row 2$"),
    (((0.5, 30.0),), {"scale": 2.0}, r"\.scale must be 1 in mode 'hours' \(the table is the "
                                     r"joint's temperature\), got 2$"),
    (((0.5, 30.0),), {"mode": "table"}, r"\.mode must be one of rise, hours, got 'table'$"),
])
def test_a_bad_temperature_table_is_refused_naming_the_key(rows, extra, match, tmp_path):
    cfg = dataset_preset("tiny_life")
    cfg["life"].update(hours=3.0, commissioning_h=1.0, fault={"fault": "healthy"})
    cfg["life"]["conditions"] = {"thermal": None, "temperature_trace": {
        "path": str(_hours_table(tmp_path / "j1.csv", rows)), "mode": "hours", **extra}}
    with pytest.raises(ValueError, match=r"^dataset\.life\.conditions\.temperature_trace"
                                         + match):
        plan(dataset_config(cfg))


@pytest.mark.parametrize("mode", ["hours", "rise"])
@pytest.mark.parametrize(("make", "words"), [
    (lambda p: p.write_bytes(b"hour,temperature_c\n" + bytes(range(256)) * 8),
     "not a text file (it holds NUL bytes"),
    (lambda p: os.mkfifo(p), "is a FIFO (named pipe), not a regular file"),
    (lambda p: p.mkdir(), "is a folder, not a file"),
    (lambda p: p.write_text("hour,temperature_c\n" + "1.0,30.0\n" * 500), "over the"),
])
def test_a_temperature_table_is_read_through_the_input_file_checker(make, words, mode,
                                                                      tmp_path, monkeypatch):
    """Issue 82, cause 2: the measured warm-up's table, of either mode, was read with no
    size or binary check (a FIFO would hang the reader); now through check_text_file, one
    line naming the key and the file, nothing read (the size bound lowered here)."""
    monkeypatch.setattr(conditions, "MAX_TRACE_BYTES", 4096)
    path = tmp_path / "j1.csv"
    make(path)
    cfg = dataset_preset("tiny_life")
    cfg["life"].update(hours=3.0, commissioning_h=1.0, fault={"fault": "healthy"})
    cfg["life"]["conditions"] = ({"thermal": None, "temperature_trace": {
        "path": str(path), "mode": "hours"}} if mode == "hours" else {"temperature_trace": {
            "path": str(path), "column": "temperature_c", "time_column": "hour"}})
    with pytest.raises(ValueError) as info:
        plan(dataset_config(cfg))
    line = str(info.value)
    assert line.startswith("dataset.life.conditions.temperature_trace.path ") and words in line


def test_a_traces_mode_is_out_of_the_config_hash_at_its_default(tmp_path):
    cfg = dataset_config(dataset_preset("tiny_real_day"))

    def traced(tr):
        return dataclasses.replace(cfg, life=dataclasses.replace(cfg.life, conditions=(
            dataclasses.replace(cfg.life.conditions, temperature_trace=tr))))

    rise = traced(TemperatureTrace(str(_trace_csv(tmp_path / "day.csv")), "Temperature_J1"))
    assert "mode" not in plain_config(rise)["life"]["conditions"]["temperature_trace"]
    hours = traced(TemperatureTrace(str(_hours_table(tmp_path / "j1.csv")), mode="hours"))
    assert plain_config(hours)["life"]["conditions"]["temperature_trace"]["mode"] == "hours"
    assert len({config_hash(c) for c in (cfg, rise, hours)}) == 3
    plan(hours)  # checked and accepted


def test_the_ur3_days_first_warm_up_is_its_first_49_minutes(ur3_day):
    t_h, rise = trace_rise(TemperatureTrace(str(ur3_day), "Temperature_J1"), "k")
    assert t_h[-1] == pytest.approx(0.816, abs=1e-3)  # before the 5.2-h gap
    assert t_h.size == 2859  # 2868 rows, 9 without a reading
    assert rise[-1] == pytest.approx(7.875) and rise.min() >= -0.1  # warming, 0.0625-K steps


def _with_joint(name: str):
    """tiny_real_day composed with the named joint of the ``thermal`` config group."""
    cfg = compose_app("generate", ["dataset=tiny_real_day",
                                   f"+thermal@dataset.life.conditions.thermal={name}"])
    return dataset_config(OmegaConf.to_container(cfg.dataset, resolve=True))


def test_a_named_joint_is_selected_in_the_config_and_the_industrial_keeps_the_hash():
    base = dataset_config(dataset_preset("tiny_real_day"))
    assert config_hash(_with_joint("industrial")) == config_hash(base)
    cobot = _with_joint("small_cobot")
    # the preset's tau over the data set's own hall (its ambient_points kept)
    assert cobot.life.conditions.thermal == JointThermal.preset(
        "small_cobot", ambient_points=base.life.conditions.thermal.ambient_points)
    assert config_hash(cobot) != config_hash(base)


def test_an_unknown_named_joint_is_refused_in_one_line():
    with pytest.raises(Exception) as err:
        _with_joint("kuka")
    assert one_line(err.value) == ("Could not find 'thermal/kuka'; available: industrial, "
                                   "small_cobot")
