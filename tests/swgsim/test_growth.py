"""Lives that run to failure (swgsim.datasets.growth): Paris' and Archard's laws against
their closed forms and a numerical integration, the life's load, payload, temperature and
scatter driving the failure hour, the refusals, and a life without the option as before
(its schedule, its config hash)."""

from __future__ import annotations

import dataclasses
import json
import re
from pathlib import Path

import numpy as np
import pytest
from data_sets import PRESET_HASHES
from scipy.integrate import solve_ivp

from swgcli import dataset_preset
from swgsim.base.typed import check_tree
from swgsim.datasets.conditions import ConditionsConfig
from swgsim.datasets.config import dataset_config
from swgsim.datasets.growth import (
    DEPTH_AT_ONE_M,
    RunToFailure,
    archard_depth,
    arrhenius_factor,
    film_factor,
    grown_severity,
    load_cycles,
    paris_crack_depth,
    paris_damage,
    paris_threshold_depth,
)
from swgsim.datasets.life import LifeSimulator
from swgsim.datasets.plan import config_hash, plain_config, plan
from swgsim.datasets.schedule import (
    DutyPoint,
    FaultOnset,
    LifeConfig,
    schedule,
    severity_at,
)
from swgsim.gear.thermal import VISCOSITY_COEFF_PER_K, JointThermal

ROOT = Path(__file__).resolve().parents[2]
DUTY = [DutyPoint(2000.0, 39.0, 10.0), DutyPoint(4000.0, 70.0, 10.0)]


def _paris_closed_form(a0, c, m, y, ds, n):
    """a(N) at constant amplitude, the textbook form (m != 2)."""
    e = 1.0 - m / 2.0
    return (a0 ** e + e * c * (y * ds * np.sqrt(np.pi)) ** m * n) ** (1.0 / e)


@pytest.mark.parametrize("m", [2.0, 2.6, 3.0, 4.0])
def test_paris_law_at_constant_amplitude_is_its_closed_form_and_the_ode(m):
    a0, c, y, ds = 40e-6, 6.9e-12, 1.12, 30.0
    n = np.full(50, 2.0e5)  # 50 blocks of 2e5 cycles
    a = paris_crack_depth(a0, paris_damage(n, np.full(50, ds), c, m), m, y)
    big_n = np.cumsum(n)
    exact = (a0 * np.exp(c * (y * ds) ** 2 * np.pi * big_n) if m == 2.0
             else _paris_closed_form(a0, c, m, y, ds, big_n))
    np.testing.assert_allclose(a, exact, rtol=1e-12)  # the same algebra: round-off only
    ode = solve_ivp(lambda _, a_: c * (y * ds * np.sqrt(np.pi * a_)) ** m, (0, big_n[-1]),
                    [a0], t_eval=big_n, rtol=1e-10, atol=1e-15)
    np.testing.assert_allclose(a, ode.y[0], rtol=1e-6)  # the ODE solver's tolerance, x100
    assert np.all(np.diff(a) > 0)


def test_paris_law_at_variable_amplitude_is_the_piecewise_ode():
    """Blocks of different stress ranges: the damage sum equals integrating block by block
    (no retardation), whatever the order of the blocks."""
    a0, c, m, y = 40e-6, 6.9e-12, 3.0, 1.12
    ds = np.array([10.0, 45.0, 25.0, 45.0, 5.0])
    n = np.array([3e6, 1e6, 2e6, 5e5, 4e6])
    a = paris_crack_depth(a0, paris_damage(n, ds, c, m), m, y)
    a_ref, x = [], a0
    for d, k in zip(ds, n, strict=True):
        x = solve_ivp(lambda _, a_, d=d: c * (y * d * np.sqrt(np.pi * a_)) ** m, (0, k), [x],
                      rtol=1e-10, atol=1e-15).y[0, -1]
        a_ref.append(x)
    np.testing.assert_allclose(a, a_ref, rtol=1e-6)
    rev = paris_crack_depth(a0, paris_damage(n[::-1], ds[::-1], c, m), m, y)
    assert rev[-1] == pytest.approx(a[-1], rel=1e-12)


def test_a_crack_without_bound_is_infinite():
    assert np.isinf(paris_crack_depth(1e-4, np.array([1e9]), 3.0, 1.12))[0]


@pytest.mark.parametrize("m", [2.0, 2.5, 3.0, 4.0])
def test_the_threshold_law_without_a_threshold_is_paris_closed_form(m):
    """Runge-Kutta in u = a^(1 - m/2), where Paris' law is a straight line: exact."""
    a0, c, y = 40e-6, 6.9e-12, 1.12
    ds, n = np.array([10.0, 45.0, 25.0, 45.0, 5.0]), np.array([3e6, 1e6, 2e6, 5e5, 4e6])
    a = paris_threshold_depth(a0, n, ds, c, m, y, 0.0)
    np.testing.assert_allclose(a, paris_crack_depth(a0, paris_damage(n, ds, c, m), m, y),
                               rtol=1e-9)


@pytest.mark.parametrize("m", [2.5, 3.0, 4.0])
def test_the_threshold_law_at_constant_amplitude_is_its_quadrature(m):
    """N(a) = ∫ da / (C (ΔK^m - ΔK_th^m)) from a0 to each block's depth (scipy.quad)."""
    from scipy.integrate import quad
    a0, c, y, ds, th = 40e-6, 6.9e-12, 1.12, 30.0, 0.25
    assert y * ds * np.sqrt(np.pi * a0) > th  # grows from the start
    n = np.full(20, 4.0e5)
    a = paris_threshold_depth(a0, n, ds * np.ones(20), c, m, y, th, substeps=8)
    finite = np.isfinite(a)
    assert finite.sum() >= 5
    cycles = [quad(lambda x: 1.0 / (c * ((y * ds * np.sqrt(np.pi * x)) ** m - th ** m)),
                   a0, ak, epsrel=1e-12)[0] for ak in a[finite]]
    np.testing.assert_allclose(cycles, np.cumsum(n)[finite], rtol=1e-5)
    slower = paris_threshold_depth(a0, n, ds * np.ones(20), c, m, y, 0.0)
    assert np.all(a[finite] < slower[finite])


def test_below_the_threshold_no_crack_grows_and_a_stop_ends_the_integration():
    a0, c, m, y = 40e-6, 6.9e-12, 3.0, 1.12
    th = 1.12 * 30.0 * np.sqrt(np.pi * a0)  # ΔK at 30 MPa: the threshold
    ds = np.array([20.0, 29.9, 45.0, 45.0, 45.0])
    a = paris_threshold_depth(a0, np.array([1e6, 1e6, 1e6, 1e8, 1e8]), ds, c, m, y, th,
                              stop_m=60e-6)
    assert a[0] == a[1] == pytest.approx(a0, rel=1e-12)  # below: nothing
    assert a0 < a[2] < 60e-6 and np.all(np.isinf(a[3:]))  # then through the stop: inf


def test_the_arrhenius_law_replaces_the_film_factor():
    revs = np.full(10, 1.2e5)
    cold = archard_depth(np.full(10, 39.0), revs, np.full(10, 20.0), 2e-14, 0.67, 40.0)
    np.testing.assert_allclose(cold, 2e-14 * 39.0 * np.cumsum(revs), rtol=1e-12)
    hot = archard_depth(np.full(10, 39.0), revs, np.full(10, 50.0), 2e-14, 0.67, 40.0)
    # Q/R (1/293.15 - 1/323.15), Q 40 kJ/mol, R 8.314462618 J/(mol K): 1.5237...
    np.testing.assert_allclose(hot / cold, np.exp(40e3 / 8.314462618
                                                  * (1 / 293.15 - 1 / 323.15)), rtol=1e-12)
    assert arrhenius_factor(np.array([20.0]), 40.0)[0] == 1.0


def test_a_threshold_holds_a_life_still_at_light_load(tiny):
    """The crack grows in the heavy windows only; the same life without it, in all."""
    law = RunToFailure(stress_mpa_per_nm=2.0)
    d1 = DEPTH_AT_ONE_M["root_tooth_crack"]
    th = law.shape_factor * law.stress_mpa_per_nm * 50.0 * np.sqrt(np.pi * 0.3 * d1)
    hours = np.arange(40) / 6.0
    load = np.where(np.arange(40) % 2 == 0, 39.0, 70.0)
    kw = dict(hours=hours, interval_min=10.0, n_in_rpm=np.full(40, 2000.0),
              t_acting_nm=load, temp_c=np.full(40, 20.0))
    free = grown_severity("root_tooth_crack", "paris", law, 0.0, 0.3, **kw)
    held = grown_severity("root_tooth_crack", "paris",
                          dataclasses.replace(law, threshold_sif=th), 0.0, 0.3, **kw)
    steps = np.diff(held)
    assert np.all(np.abs(steps[load[:-1] < 50.0]) < 1e-12)  # round-off of a^(1 - m/2)
    growing = held[1:] < law.failure_severity("root_tooth_crack")  # before it saturates
    assert growing.sum() > 5 and np.all(steps[(load[:-1] > 50.0) & growing] > 1e-6)
    assert np.all(held <= free) and np.argmax(held >= 0.5) > np.argmax(free >= 0.5)


def test_archard_wear_is_linear_in_sliding_distance_and_follows_the_film():
    revs = np.full(40, 1.2e5)
    d = archard_depth(np.full(40, 39.0), revs, np.full(40, 20.0), 2e-14, 0.67)
    np.testing.assert_allclose(d, 2e-14 * 39.0 * np.cumsum(revs), rtol=1e-12)
    twice = archard_depth(np.full(40, 78.0), revs, np.full(40, 20.0), 2e-14, 0.67)
    np.testing.assert_allclose(twice, 2 * d, rtol=1e-12)
    hot = archard_depth(np.full(40, 39.0), revs, np.full(40, 35.0), 2e-14, 0.67)
    # ν(35)/ν(20) = exp(-0.035 * 15): the film factor exp(+0.035 * 15 * 0.67)
    np.testing.assert_allclose(hot / d, np.exp(VISCOSITY_COEFF_PER_K * 15 * 0.67), rtol=1e-12)
    assert film_factor(np.array([20.0]), 0.67)[0] == 1.0


def test_a_life_grows_on_its_window_grid_by_the_closed_form_then_saturates():
    """Constant duty: window k holds the crack of k intervals of cycles; the failure
    severity from the first window at or over it on."""
    law = RunToFailure()
    hours = np.arange(0, 2000, 1.0)  # one window an hour
    onset, s0 = 100.0, 0.05
    sev = grown_severity("root_tooth_crack", "paris", law, onset, s0, hours, 60.0,
                         np.full(hours.size, 3000.0), np.full(hours.size, 52.0),
                         np.full(hours.size, 20.0))
    assert np.all(sev[hours < onset] == 0) and sev[hours == onset][0] == s0
    depth = DEPTH_AT_ONE_M["root_tooth_crack"]
    n = load_cycles(np.array([3000.0]), 60.0)[0] * np.maximum(hours - onset, 0)
    exact = _paris_closed_form(s0 * depth, law.paris_c, law.paris_m, law.shape_factor,
                               law.stress_mpa_per_nm * 52.0, n) / depth
    fail = law.failure_severity("root_tooth_crack")
    with np.errstate(invalid="ignore"):  # past the closed form's pole: no crack left
        grown = (hours >= onset) & (n < _paris_pole(s0 * depth, law, 52.0)) & (exact < fail)
    np.testing.assert_allclose(sev[grown], exact[grown], rtol=1e-10)
    assert grown.sum() > 10 and np.all(sev[(hours >= onset) & ~grown] == fail)


def _paris_pole(a0, law, t_nm):
    """Cycles at which the closed form's crack grows without bound (m > 2)."""
    e = 1.0 - law.paris_m / 2.0
    k = law.paris_c * (law.shape_factor * law.stress_mpa_per_nm * t_nm * np.sqrt(np.pi)) \
        ** law.paris_m
    return a0 ** e / (-e * k)


@pytest.fixture(scope="module")
def tiny(tiny_bench):
    """The tiny bench's plan with gear 3's records (shared: tests/conftest.py)."""
    p, banks = tiny_bench
    return p, banks[3]


NEUTRAL = ConditionsConfig(thermal=None, viscosity=False, run_in=None, payload=[],
                           bridge_drift=None, temperature_sensor=None)


def _failure_h(tiny, fault="wear", growth="archard", s0=0.0, conditions=None,
               life_seed=0, **law):
    life = LifeConfig(hours=3000.0, commissioning_h=24.0, interval_min=10.0, duty=DUTY,
                      fault=FaultOnset(fault, 48.0, s0, growth=growth,
                                       to_failure=RunToFailure(**law)),
                      life_seed=life_seed, conditions=conditions)
    check_tree(life, "dataset.life")
    # its schedule alone: a bank of its own, whose records (asked for by the life, at
    # 2000 rpm too) are never simulated, not the shared one's
    return LifeSimulator(tiny[0], 3, life).schedule.failure_h


@pytest.mark.parametrize("fault, growth, s0", [("wear", "archard", 0.0),
                                               ("root_tooth_crack", "paris", 0.05)])
def test_a_heavier_payload_fails_sooner(tiny, fault, growth, s0):
    light = _failure_h(tiny, fault, growth, s0, NEUTRAL, scatter=0.0)
    heavy = _failure_h(tiny, fault, growth, s0, dataclasses.replace(
        NEUTRAL, payload=[[0.0, 1.2]]), scatter=0.0)
    assert np.isfinite(light) and 48.0 < heavy < light


def test_a_hotter_hall_wears_faster(tiny):
    def hall(offset_k):
        th = JointThermal(ambient_points=[[0.0, offset_k]])
        return _failure_h(tiny, conditions=dataclasses.replace(NEUTRAL, thermal=th),
                          scatter=0.0)
    assert 48.0 < hall(15.0) < hall(0.0)


def test_scatter_spreads_the_failure_hours_of_gears(tiny):
    seeds = range(6)
    none = [_failure_h(tiny, life_seed=s, scatter=0.0) for s in seeds]
    some = [_failure_h(tiny, life_seed=s, scatter=0.3) for s in seeds]
    wide = [_failure_h(tiny, life_seed=s, scatter=0.6) for s in seeds]
    assert np.ptp(none) == 0 and 0 < np.std(np.log(some)) < np.std(np.log(wide))
    assert some == [_failure_h(tiny, life_seed=s, scatter=0.3) for s in seeds]  # seeded


def test_the_schedule_is_a_staircase_of_the_failure_severity():
    life = LifeConfig(hours=3000.0, commissioning_h=24.0, interval_min=10.0, duty=DUTY,
                      severity_levels=4,
                      fault=FaultOnset("eccentric_wg", 48.0, 0.0, growth="archard"))
    s = schedule(life, [], [])
    fail = RunToFailure().failure_severity("eccentric_wg")
    assert set(np.unique(s.severity)) == {0.0, *(fail * np.arange(1, 5) / 4)}
    assert np.all(s.fault[s.hour < 48.0] == "healthy")
    assert np.all(s.fault[s.hour >= 48.0] == "eccentric_wg")
    assert np.all(s.severity[s.hour >= s.failure_h] == fail) and np.all(np.diff(s.severity) >= 0)


@pytest.mark.parametrize("fault, key", [
    (FaultOnset("wear", 6.0, 0.5, growth="archard", to_failure=RunToFailure(failure=0.5)),
     "dataset.life.fault.to_failure.failure must lie in (0.5, 1]"),
    (FaultOnset("root_tooth_crack", 6.0, 0.0, growth="paris"),
     "dataset.life.fault.severity must lie in (0, 0.99]"),
    (FaultOnset("wear", 6.0, 0.1, growth="paris"),
     "dataset.life.fault.growth=paris grows root_tooth_crack, tip_tooth_crack, not wear"),
    (FaultOnset("reduced_stiffness", 6.0, 0.1, growth="archard"),
     "dataset.life.fault.growth=archard grows eccentric_wg, wear"),
    (FaultOnset("wear", 6.0, 0.1, to_failure=RunToFailure()),
     "dataset.life.fault.to_failure is for growth paris or archard"),
    (FaultOnset("wear", 6.0, 0.1, growth="archard", to_failure=RunToFailure(scatter=-1)),
     "dataset.life.fault.to_failure.scatter must lie in [0, 2]"),
    (FaultOnset("root_tooth_crack", 6.0, 0.1, growth="paris",
                to_failure=RunToFailure(threshold_sif=-1.0)),
     "dataset.life.fault.to_failure.threshold_sif must lie in [0, 100] MPa √m"),
    (FaultOnset("wear", 6.0, 0.1, growth="archard",
                to_failure=RunToFailure(activation_kj_per_mol=500.0)),
     "dataset.life.fault.to_failure.activation_kj_per_mol must lie in [1, 200] kJ/mol"),
    (FaultOnset("wear", 6.0, 0.0, growth="points", points=[[6.0, 0.1], [6.0, 0.2]]),
     "dataset.life.fault.points must be [hour, severity] pairs with strictly increasing"),
    (FaultOnset("wear", 6.0, 0.0, growth="points", points=[[6.0, 0.1], [7.0, 1.2]]),
     "dataset.life.fault.points[1][1]=1.2: outside the allowed range [0.0, 1.0]"),
])
def test_bad_growth_to_failure_is_refused_in_one_line(fault, key):
    cfg = dataset_config(dataset_preset("tiny_life"))
    cfg.life.fault = fault
    with pytest.raises(ValueError, match=re.escape(key)) as info:
        plan(cfg)
    assert "\n" not in str(info.value)


def test_the_option_parses_from_a_mapping_and_enters_the_hash():
    raw = dataset_preset("tiny_life")
    base = config_hash(dataset_config(raw))
    raw["life"]["fault"].update(growth="archard", severity=0.0,
                                to_failure={"failure": 0.2, "scatter": 0.1})
    cfg = dataset_config(raw)
    assert cfg.life.fault.to_failure == RunToFailure(failure=0.2, scatter=0.1)
    assert plain_config(cfg)["life"]["fault"]["to_failure"]["failure"] == 0.2
    assert config_hash(cfg) != base
    assert "to_failure" not in plain_config(dataset_config(dataset_preset("tiny_life")))[
        "life"]["fault"]


def test_every_preset_keeps_its_config_hash():
    names = sorted(p.stem for p in (ROOT / "conf" / "dataset").glob("*.yaml"))
    assert names == sorted(PRESET_HASHES)
    assert {n: config_hash(dataset_config(dataset_preset(n))) for n in names} == PRESET_HASHES


def _severity_before(f: FaultOnset, hours: np.ndarray, levels: int) -> np.ndarray:
    """severity_at as it was before lives could run to failure (commit c77338c), kept
    verbatim as the reference path."""
    h = np.asarray(hours, float)
    if f.fault == "healthy":
        return np.zeros_like(h)
    if f.growth == "step":
        return np.where(h >= f.onset_h, f.severity, 0.0)
    if f.growth == "linear":
        set_in = h >= f.onset_h
        exact = np.clip((h - f.onset_h) / f.growth_h, 0.0, 1.0) * f.severity
        top = f.severity
    else:
        hp = np.array([p[0] for p in f.points], float)
        sp = np.array([p[1] for p in f.points], float)
        set_in = h >= max(hp[0], f.onset_h)
        exact = np.interp(h, hp, sp)
        top = sp[np.argmax(np.abs(sp))]
    if top == 0:
        return np.zeros_like(h)
    step = abs(top) / int(levels)
    q = np.floor(np.abs(exact) / step + 1e-9) * step
    q = np.maximum(q, step) * np.sign(np.where(exact != 0, exact, top))
    return np.where(set_in, q, 0.0)


@pytest.mark.parametrize("fault", [
    FaultOnset(), FaultOnset("eccentric_wg", 30.0, 0.1),
    FaultOnset("reduced_damping", 30.0, 0.4, growth="linear", growth_h=17.3),
    FaultOnset("root_tooth_crack", 30.0, 0.9, growth="points",
               points=[[31.0, 0.2], [40.5, 0.7], [90.0, 0.9]]),
    FaultOnset("sensor_gain_drift", 25.0, 0.02, growth="linear", growth_h=10.0),
])
def test_a_life_without_the_option_has_the_schedule_it_had(fault):
    life = LifeConfig(hours=120.0, commissioning_h=24.0, severity_levels=7, fault=fault)
    check_tree(life, "dataset.life")
    s = schedule(life, [2000.0, 4000.0], [7.0, 39.0, 70.0])
    before = _severity_before(fault, s.hour, 7)
    assert np.array_equal(s.severity, before)
    assert np.array_equal(s.fault, np.where(before != 0, fault.fault, "healthy"))
    assert np.isnan(s.failure_h)
    np.testing.assert_array_equal(severity_at(fault, s.hour, 7), before)


def test_the_documented_example_is_a_valid_life_that_fails():
    """The YAML example of docs/DATASET.md, "Lives that run to failure", on the tiny
    bench: checked, planned, and its crack reaches the failure severity within the life."""
    import yaml

    text = (ROOT / "docs" / "DATASET.md").read_text(encoding="utf-8")
    block = re.search(r"```yaml\n(life:\n.*?)```", text, re.S).group(1)
    raw = dataset_preset("tiny_bench")
    raw["life"] = yaml.safe_load(block)["life"]
    p = plan(raw)
    life = p.config.life
    s = LifeSimulator(p, int(p.config.gears[0].id), life).schedule
    assert life.fault.growth == "paris"
    assert life.fault.onset_h < s.failure_h < life.hours
    assert s.severity[-1] == life.fault.to_failure.failure


def test_a_life_run_to_failure_writes_its_staircase_and_its_law(tiny):
    """Windows before the onset, growing and failed carry the schedule's severity; the
    shard's life attribute names the law, a life without it keeps its attribute as before."""
    from swgsim.datasets.life import life_dataset

    life = LifeConfig(hours=3.0, commissioning_h=1.0, interval_min=2.0, severity_levels=2,
                      duty=[DutyPoint(4000.0, 70.0, 10.0)],
                      fault=FaultOnset("eccentric_wg", 1.0, 0.0, growth="archard",
                                       to_failure=RunToFailure(wear_coeff_m_per_nm_rev=1e-11)))
    check_tree(life, "dataset.life")
    sim = LifeSimulator(tiny[0], 3, life, tiny[1])
    s = sim.schedule
    assert 1.0 < s.failure_h < 3.0
    assert s.severity[-1] == 0.3  # failed: the eccentric WG's failure severity
    on = int(np.flatnonzero(s.hour >= 1.0)[0])
    ds = life_dataset(sim, on - 1, on + 1)  # the last healthy window and the first faulty
    np.testing.assert_array_equal(ds["severity"].values, s.severity[on - 1:on + 1])
    assert ds["severity"].values[0] == 0 and ds["severity"].values[1] == 0.15
    assert _attr(ds)["fault"]["to_failure"]["wear_coeff_m_per_nm_rev"] == 1e-11
    plain = LifeSimulator(tiny[0], 3, dataclasses.replace(life, fault=FaultOnset()), tiny[1])
    assert "to_failure" not in _attr(life_dataset(plain, 0, 1))["fault"]


def _attr(ds) -> dict:
    """The life attribute of a life's data set (JSON text once made)."""
    life = ds.attrs["life"]
    return json.loads(life) if isinstance(life, str) else life


def test_the_failure_preset_fails_within_its_life():
    """conf/dataset/tiny_failure.yaml, composed as the app would: every gear's wear reaches
    its failure severity inside the life, at a different hour (its scatter)."""
    from omegaconf import OmegaConf

    from swgcli import compose_app

    p = plan(OmegaConf.to_container(compose_app("generate", ["dataset=tiny_failure"]).dataset,
                                    resolve=True))
    life = p.config.life
    hours = [LifeSimulator(p, int(g.id), life).schedule.failure_h for g in p.config.gears]
    assert all(life.fault.onset_h < h < life.hours for h in hours)
    assert len(set(hours)) == len(hours)
