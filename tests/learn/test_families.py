"""Families of benign changes (swgmon.evaluation.families): draws deterministic per seed and
different between seeds, inside the declared ranges, accepted by the conditions' checks;
design and scored seeds kept apart; a range out of its bounds refused in one line naming
it; the evaluation's lives of a family (swgmon.evaluation.study.life_conditions,
swgmon.evaluation.evaluate.nuisance_fault_lives)."""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest

from swgcli import dataset_preset
from swgmon.detection.rule import TEMPERATURE_SENSOR, UNEXPLAINED_CHANGE, Alarm
from swgmon.evaluation.evaluate import _benign, healthy_life, maintenance_log, monitor_healthy
from swgmon.evaluation.families import (
    RANGES,
    SENSOR_STATES,
    GrowthFamily,
    NuisanceFamily,
    _draws,
    benchmark_families,
    default_families,
    draw_conditions,
    draw_growth,
)
from swgmon.evaluation.study import FAMILY_PREFIX, MonitorStudyConfig, life_conditions
from swgmon.evaluation.training import train_model
from swgsim.base.typed import check_tree
from swgsim.datasets.growth import DEPTH_AT_ONE_M, RunToFailure
from swgsim.datasets.plan import plan
from swgsim.datasets.records import record_bank
from swgsim.datasets.schedule import LifeConfig, schedule
from swgsim.gear.thermal import MONOTONE_FORMS

FAMILIES = default_families()
SEEDS = [0, 1, 2, 3, 4, 100, 101, 102, 103, 104]


@pytest.mark.parametrize("name", FAMILIES)
def test_a_draw_is_the_same_for_a_seed_and_differs_between_seeds(name):
    fam = FAMILIES[name]
    assert draw_conditions(fam, 7) == draw_conditions(fam, 7)
    assert draw_conditions(fam, 7) != draw_conditions(fam, 8)


@pytest.mark.parametrize("name", FAMILIES)
def test_every_draw_passes_the_conditions_checks(name):
    fam = FAMILIES[name]
    fam.check(name)
    for seed in SEEDS:
        draw = draw_conditions(fam, seed)
        check_tree(draw, f"families.{name}")
        draw.check_inside(49.0, f"families.{name}")


def test_draws_stay_inside_the_declared_ranges():
    fam = NuisanceFamily()
    forms, states = set(), set()
    for seed in range(200):
        values, form, state = _draws(fam, seed)
        for k, v in values.items():
            lo, hi = getattr(fam, k)
            assert lo <= v <= hi, (k, v)
        forms.add(form), states.add(state)
        c = draw_conditions(fam, seed)
        assert 0.3 <= c.friction_law.ratio_40c <= 1.0
        assert c.friction_law.form in MONOTONE_FORMS
        assert 0.3 <= c.thermal.r_th_k_per_w <= 0.5 and 20.0 <= c.thermal.tau_min <= 60.0
        assert 0.0 <= c.bridge_drift.span_mean_per_k <= 4e-4
        assert 0.8 <= c.payload[0][1] <= 1.2 and 30.0 <= c.payload[0][0] <= 48.0
        if c.regrease is not None:
            assert 30.0 <= c.regrease.hours[0] <= 48.0 and 0.1 <= c.regrease.drop <= 0.5
    assert forms == set(MONOTONE_FORMS) and states == set(SENSOR_STATES)


def test_a_narrow_range_gives_its_value_and_the_parts_not_drawn_keep_defaults():
    fam = NuisanceFamily(parts=["warm_up"], r_th_k_per_w=[0.4, 0.4])
    c = draw_conditions(fam, 3)
    assert c.thermal.r_th_k_per_w == 0.4
    assert c.friction_law.ratio_40c is None and c.run_in is None and c.payload == []
    assert c.regrease is None
    assert c.temperature_sensor is not None and c.thermal.ambient_points == []


def test_a_part_draws_the_same_magnitude_alone_and_in_all():
    alone, together = draw_conditions(FAMILIES["warm_up"], 5), draw_conditions(
        FAMILIES["all"], 5)
    assert alone.thermal.r_th_k_per_w == together.thermal.r_th_k_per_w
    assert alone.friction_law == together.friction_law


def test_still_and_sensor_families():
    run_in = draw_conditions(FAMILIES["run_in"], 0)
    assert run_in.thermal is None and not run_in.viscosity and run_in.bridge_drift is None
    assert all(draw_conditions(FAMILIES["sensor"], s).temperature_sensor is None
               for s in SEEDS)
    for fault in ("stuck", "drift", "dropout"):
        for seed in SEEDS:
            ts = draw_conditions(FAMILIES[f"sensor_{fault}"], seed).temperature_sensor
            assert ts.fault == fault and 30.0 <= ts.fault_hour <= 120.0
            assert (ts.drift_k_per_h != 0.0) == (fault == "drift")
            assert abs(ts.drift_k_per_h) <= 0.5
    greased = draw_conditions(FAMILIES["regrease"], 0)
    assert greased.thermal is None and len(greased.regrease.hours) == 1


def test_a_fault_hour_inside_commissioning_is_refused():
    fams = {"sensor_stuck": NuisanceFamily(parts=["sensor"], sensor_states=["stuck"],
                                           sensor_fault_h=[10.0, 40.0])}
    with pytest.raises(ValueError, match=r"families\.sensor_stuck\.sensor_fault_h must lie "
                                         r"after commissioning \(> 24 h\)"):
        check_tree(MonitorStudyConfig(families=fams), "monitor.study")


@pytest.mark.parametrize("field", list(RANGES))
def test_a_range_outside_its_bounds_is_one_line_naming_it(field):
    hi = RANGES[field][2]
    fam = NuisanceFamily(**{field: [hi, 2 * abs(hi) + 1.0]})
    with pytest.raises(ValueError, match=rf"^fam\.{field} must be \[lo, hi\].*within \[") as e:
        fam.check("fam")
    assert "\n" not in str(e.value)


@pytest.mark.parametrize("change, match", [
    ({"parts": ["bogus"]}, r"fam\.parts must list distinct values of friction_law"),
    ({"parts": []}, r"fam\.parts"),
    ({"friction_forms": ["cubic"]}, r"fam\.friction_forms"),
    ({"sensor_states": ["loose"]}, r"fam\.sensor_states"),
    ({"still": True}, r"fam\.parts: a still family draws none of"),
    ({"tau_min": [60.0, 20.0]}, r"fam\.tau_min must be \[lo, hi\], lo <= hi"),
    ({"parts": ["drift"], "logged": True}, r"fam\.logged: only a family with the regrease"),
])
def test_a_bad_family_is_refused_naming_the_key(change, match):
    with pytest.raises(ValueError, match=match):
        NuisanceFamily(**change).check("fam")


def test_a_seed_not_an_integer_in_range_is_refused():
    with pytest.raises(ValueError, match="seed must be an integer"):
        draw_conditions(NuisanceFamily(), -1)


def test_design_and_family_seeds_that_overlap_are_refused():
    check_tree(MonitorStudyConfig(families=default_families()), "monitor.study")
    cfg = MonitorStudyConfig(design_seeds=[100, 3], family_seeds=[0, 3])
    with pytest.raises(ValueError, match=r"^monitor\.study\.family_seeds must be disjoint "
                                         r"from design_seeds, both hold \[3\]$"):
        check_tree(cfg, "monitor.study")


def test_a_family_out_of_range_in_the_study_is_refused_naming_it():
    fams = {"warm_up": NuisanceFamily(parts=["warm_up"], tau_min=[0.0, 60.0])}
    with pytest.raises(ValueError, match=r"monitor\.study\.families\.warm_up\.tau_min"):
        check_tree(MonitorStudyConfig(families=fams), "monitor.study")
    late = {"payload": NuisanceFamily(parts=["payload"], still=True, payload_h=[30.0, 60.0])}
    with pytest.raises(ValueError, match=r"^monitor\.study\.families\.payload\[seed=\d+\]"
                                         r"\.payload\[0\]\[0\] must lie in \[0, 49\] h"):
        check_tree(MonitorStudyConfig(families=late, design_seeds=list(range(100, 120))),
                   "monitor.study")


def test_the_fixed_nuisances_are_lived_as_before_and_families_by_the_seed():
    cfg = MonitorStudyConfig(families=default_families())
    assert life_conditions(cfg, "none", 0) is None
    assert life_conditions(cfg, "warm_up", 3) is cfg.nuisances["warm_up"]
    assert life_conditions(cfg, "family:warm_up", 3) == draw_conditions(
        cfg.families["warm_up"], 3)
    with pytest.raises(KeyError, match="family:all"):
        life_conditions(cfg, "family:bogus", 0)


def test_a_family_life_also_lives_slowly_growing_faults():
    from swgcli import dataset_preset
    from swgmon.evaluation.evaluate import nuisance_fault_lives
    from swgsim.datasets.plan import plan

    p = plan(dataset_preset("tiny_bench"))
    cfg = dataclasses.replace(MonitorStudyConfig(), faults=["eccentric_wg"])
    fixed = nuisance_fault_lives(p, cfg, 0)
    lives = nuisance_fault_lives(p, cfg, 0, growing=True)
    assert lives[:len(fixed)] == fixed  # the step faults as without
    (grow, kind), = lives[len(fixed):]
    assert kind == "growing" and grow.growth == "linear" and grow.growth_h == 40.0
    assert grow.severity == min((f.severity for f, _ in fixed), key=abs)


def test_only_a_logged_family_hands_its_regreasing_to_the_monitor():
    """swgmon.evaluation.evaluate.maintenance_log: the re-greasing drawn for the life, declared
    where the family is logged, not where it is not (an unexplained change to name)."""
    cfg = MonitorStudyConfig(families={k: FAMILIES[k] for k in ("regrease",
                                                                "regrease_logged")})
    for key, logged in (("regrease", False), ("regrease_logged", True)):
        life = f"family:{key}"
        cond = life_conditions(cfg, life, 3)
        log = maintenance_log(cfg, life, cond)
        assert [(e.hour, e.kind) for e in log] == (
            [(cond.regrease.hours[0], "regrease")] if logged else [])
    assert maintenance_log(cfg, "none", None) == []



def _alarm(fault: str, hour: float) -> Alarm:
    return Alarm(hour, 0, 0, fault, fault, 0.0, 0.0, 0.0)


def test_a_fault_life_passes_only_the_alarms_its_own_benign_events_explain():
    """swgmon.evaluation.evaluate._benign: after a fault's onset an alarm is that fault's
    detection unless the life holds what it names - a re-greasing at or before an
    unexplained change, a temperature sensor failed at or before an alarm naming it. An
    unexplained change in a life with no re-greasing (reduced damping under a warm-up,
    read as an even friction change) is the fault's alarm, named wrong, not passed by."""
    cfg = MonitorStudyConfig(families={k: FAMILIES[k] for k in ("regrease", "sensor_stuck")})
    greased = life_conditions(cfg, "family:regrease", 3)
    h = greased.regrease.hours[0]
    assert _benign(_alarm(UNEXPLAINED_CHANGE, h + 0.5), greased)
    assert not _benign(_alarm(UNEXPLAINED_CHANGE, h - 0.5), greased)
    assert not _benign(_alarm("reduced_damping", h + 0.5), greased)
    stuck = life_conditions(cfg, "family:sensor_stuck", 3)
    f = stuck.temperature_sensor.fault_hour
    assert _benign(_alarm(TEMPERATURE_SENSOR, f + 0.5), stuck)
    assert not _benign(_alarm(TEMPERATURE_SENSOR, f - 0.5), stuck)
    plain = life_conditions(cfg, "warm_up", 3)
    for fault in (UNEXPLAINED_CHANGE, TEMPERATURE_SENSOR):
        assert not _benign(_alarm(fault, 100.0), plain)
        assert not _benign(_alarm(fault, 100.0), None)

def _day_csv(path):
    """A measured warm-up in the UR3 CobotOps format: two joints warming 0.2 and 0.3 K a
    minute for 30 min."""
    rows = ["Num;Timestamp;Temperature_T0;Temperature_J1;"]
    for i in range(31):
        t = f"2022-10-26T08:{i:02d}:00Z"
        rows.append(f"{i + 1};{t};{25.0 + 0.2 * i:.1f};{25.0 + 0.3 * i:.1f};".replace(".", ","))
    path.write_text("\n".join(rows) + "\n")
    return str(path)


def test_a_trace_family_draws_a_measured_warm_up_and_leaves_the_other_draws(tmp_path):
    """The trace part: a column of the user's file and a scale drawn from a stream of
    their own, so the friction law of a seed is that of the friction_law family."""
    fam = NuisanceFamily(parts=["trace", "friction_law"], trace_path=_day_csv(
        tmp_path / "day.csv"), trace_columns=["Temperature_T0", "Temperature_J1"])
    fam.check("fam")
    seen = set()
    for seed in SEEDS:
        c = draw_conditions(fam, seed)
        assert 1.0 <= c.temperature_trace.scale <= 4.0
        seen.add(c.temperature_trace.column)
        assert c.friction_law == draw_conditions(FAMILIES["friction_law"], seed).friction_law
        check_tree(c, "c")
        c.check_inside(49.0, "c")
    assert seen == {"Temperature_T0", "Temperature_J1"}
    assert "trace" not in NuisanceFamily().parts  # the file is the user's
    with pytest.raises(ValueError, match=r"^fam\.trace_path: the trace part needs"):
        NuisanceFamily(parts=["trace"]).check("fam")
    with pytest.raises(ValueError, match=r"^fam\.trace\.column: 'Temperature_J9' is not"):
        dataclasses.replace(fam, trace_columns=["Temperature_J9"]).check("fam")


@pytest.fixture(scope="module")
def bench():
    """The bench's plan, gears 1-3's records and the diagnosis model trained on gears 1
    and 2 as the evaluation trains it (gear 3 held out); for the slow tests only."""
    p = plan(dataset_preset("bench"))
    banks = {g: record_bank(p, g) for g in (1, 2, 3)}
    return p, banks, train_model(p, banks, [1, 2], MonitorStudyConfig(families=FAMILIES))


def _bench_life(bench, family: str, seed: int, hours: float | None = None):
    """The alarms of the bench's held-out gear 3 through a family's healthy life
    (``hours``: its length, None the study's)."""
    p, banks, model = bench
    cfg = MonitorStudyConfig(families=FAMILIES)
    cfg = cfg if hours is None else dataclasses.replace(cfg, nuisance_hours=hours)
    life = FAMILY_PREFIX + family
    sim = healthy_life(p, banks[3], 3, cfg, seed, life)
    return monitor_healthy(model, cfg, sim, seed, life)[3]


def _failed_h(family: str, seed: int) -> float:
    """The hour a family's drawn temperature sensor fails."""
    return draw_conditions(FAMILIES[family], seed).temperature_sensor.fault_hour


@pytest.mark.slow
def test_a_drifting_reading_under_a_steep_friction_law_is_named_not_stormed(bench):
    """Bench, gear 3 held out, family sensor_drift, seed 73 (the reading drifts -0.34 K/h
    from 69.5 h, the friction saturating at 0.40 at 40 degC), to 80 h. Found on the draws
    before issue 84 keyed them by name (seed 2 then: -0.235 K/h from 70.5 h, saturating at
    0.35): the efficiency saw the drift first and two unexplained changes were taken, then
    each restart of the CUSUM named a root crack (853 alarms in 200 h). The recurring
    change named again over the windows since the first, with the friction as before it
    (stream._drifting), names the sensor, and no gear fault follows."""
    named = _bench_life(bench, "sensor_drift", 73, 80.0)
    assert not [a for a in named if a.kind == "gear_fault"]
    sensor = [a.hour for a in named if a.fault == TEMPERATURE_SENSOR]
    start = _failed_h("sensor_drift", 73)
    assert sensor and start <= sensor[0] <= start + 5.5


@pytest.mark.slow
@pytest.mark.parametrize(("family", "seed"), [("sensor_stuck", 1), ("sensor_dropout", 2)])
def test_a_monitor_on_the_laws_temperature_raises_no_gear_fault_alarm(bench, family, seed):
    """Bench, gear 3 held out, the study's healthy lives (224 h) whose reading sticks
    (seed 1) or drops out (seed 2) under saturating friction laws: the sensor named at
    once, then the monitor goes on at the laws' virtual temperature. Calibrated with the
    reading (draws before issue 84: stuck from 94.47 h), reduced damping was named at
    96.18 h and an eccentric WG at 176.38 h (the virtual temperature's error moved the
    efficiency alone); calibrated as it scores (GearMonitor.read_virtually), no gear-fault
    alarm."""
    named = _bench_life(bench, family, seed)
    assert not [a for a in named if a.kind == "gear_fault"]
    sensor = [a.hour for a in named if a.fault == TEMPERATURE_SENSOR]
    failed_h = _failed_h(family, seed)
    assert sensor and failed_h <= sensor[0] <= failed_h + 1.0


# ------------------------------------------------------------------ issue 83's physics
@pytest.mark.parametrize("name", list(benchmark_families()))
def test_every_benchmark_draw_holds_the_physics_the_monitor_was_not_built_on(name):
    """Issue 83: the benchmark's families live the joint in two nodes, a Coulomb term with a
    u-shaped law of its own (and its own run-in where one is drawn), the friction in the
    dynamics; every draw passes the conditions' checks for a 200-h life."""
    fam = benchmark_families()[name]
    fam.check(name)
    for seed in range(20):
        c = draw_conditions(fam, seed)
        check_tree(c, f"families.{name}")
        c.check_inside(200.0, f"families.{name}")
        assert c.thermal.network is not None and c.viscous_in_dynamics
        assert c.coulomb_law.form == "u_shaped" and 45.0 <= c.coulomb_law.minimum_c <= 80.0
        if c.run_in is not None:
            assert c.run_in.split and 0.0 <= c.run_in.coulomb_drop <= 0.3
    sensor = [draw_conditions(fam, s).temperature_sensor for s in range(20)]
    if name == "sensor_lagging":
        assert all(5.0 <= x.lag_min <= 40.0 and x.offset_k == 0 for x in sensor)
    if name == "sensor_offset":
        assert all(-2.0 <= x.offset_k <= 2.0 and x.lag_min == 0 for x in sensor)


def test_a_keyed_magnitude_is_drawn_by_its_name_alone():
    """Each of issue 83's magnitudes comes from a stream keyed by its name: the same for a
    seed whatever else a family draws or declares, so adding one moves no other."""
    a = NuisanceFamily(parts=["warm_up", "network"])
    b = NuisanceFamily(parts=["warm_up", "network", "coulomb"], coulomb_tau_h=[5.0, 6.0])
    for seed in (0, 1, 1000):
        va, vb = _draws(a, seed)[0], _draws(b, seed)[0]
        assert va["grease_r_k_per_w"] == vb["grease_r_k_per_w"]
        assert va["drive_w"] == vb["drive_w"] and va["coulomb_tau_h"] != vb["coulomb_tau_h"]


# ------------------------------------------------------------------ duty changes
def test_the_duty_part_moves_no_other_draw():
    """The duty part's magnitudes are keyed by their names: every family without it draws no
    duty change, and the benchmark's ``all`` with it draws what it drew without it, the
    change aside."""
    bench = benchmark_families()
    for name, fam in {**FAMILIES, **bench}.items():
        if "duty" not in fam.parts:
            assert all(draw_conditions(fam, s).duty_change is None for s in SEEDS), name
    with_duty = bench["all"]
    without = dataclasses.replace(with_duty, parts=[p for p in with_duty.parts if p != "duty"])
    for seed in SEEDS:
        a, b = draw_conditions(with_duty, seed), draw_conditions(without, seed)
        assert a.duty_change is not None and dataclasses.replace(a, duty_change=None) == b
        va, vb = _draws(with_duty, seed), _draws(without, seed)
        assert va == vb  # every value is drawn whichever parts a family names


def test_the_benchmarks_duty_family_draws_a_new_program_inside_the_life():
    fam = benchmark_families()["duty"]
    shifts = []
    for seed in SEEDS:
        c = draw_conditions(fam, seed)
        change = c.duty_change
        assert 30.0 <= change.hour_h <= 48.0 and change.dwell_factors == []
        assert -1.0 <= change.load_shift <= 1.0
        c.check_inside(200.0, "c")
        shifts.append(change.load_shift)
        life = LifeConfig(hours=200.0, commissioning_h=24.0, conditions=c)
        check_tree(life, "life")
        s = schedule(life, [2000.0, 4000.0], [7.0, 39.0, 70.0])
        t = np.array([d.t_out_nm for d in s.duty])[s.duty_index]
        after = s.hour >= change.hour_h
        high = np.mean(t[after] == 70.0)
        assert np.mean(t[~after] == 70.0) == pytest.approx(1 / 3, abs=0.01)
        assert (high - 1 / 3) * change.load_shift >= 0  # more high load for a shift > 0
    assert min(shifts) < 0 < max(shifts)


def test_adding_a_friction_form_moves_only_the_seeds_it_wins():
    """Issue 84: every draw is keyed by its name. A new friction form (or sensor state)
    takes the seeds it wins and leaves every other seed's form and every magnitude as it
    was; the order of the list does not matter."""
    base = NuisanceFamily(parts=["warm_up", "friction_law"])
    forms = list(base.friction_forms)
    grown = dataclasses.replace(base, friction_forms=[*forms, "new_form_for_test"])
    moved = 0
    for seed in range(200):
        (va, fa, sa), (vb, fb, sb) = _draws(base, seed), _draws(grown, seed)
        assert va == vb and sa == sb
        if fb != fa:
            assert fb == "new_form_for_test"
            moved += 1
        reordered = dataclasses.replace(base, friction_forms=forms[::-1])
        assert _draws(reordered, seed)[1] == fa
    assert 0 < moved < 200 / len(forms)  # about 1 / (n + 1) of the seeds


# ------------------------------------------------------------- growth families (issue 85)
def _drawn(fault: str, seed: int, family=None, gear: int = 9) -> RunToFailure:
    nominal = RunToFailure(failure=0.9 if "crack" in fault else 0.1, stress_mpa_per_nm=0.6)
    return draw_growth(family or GrowthFamily(), fault, nominal,
                       0.25 if "crack" in fault else 0.0, 39.0, gear, seed)


def test_a_growth_draw_is_keyed_by_its_name_fault_gear_and_seed():
    a = _drawn("root_tooth_crack", 3)
    assert a == _drawn("root_tooth_crack", 3)  # pure
    assert a != _drawn("root_tooth_crack", 4) and a != _drawn("root_tooth_crack", 3, gear=10)
    fixed = _drawn("root_tooth_crack", 3, GrowthFamily(failure_spread=0.0))
    assert (fixed.paris_m, fixed.threshold_sif) == (a.paris_m, a.threshold_sif)  # only failure
    assert fixed.failure == 0.9 and a.failure != 0.9


def test_a_redraw_takes_streams_of_its_own_and_moves_no_first_draw():
    """Attempt 0 keys as draws did before attempts existed (the key without a number);
    each later attempt draws every constant anew from its own streams."""
    nominal = RunToFailure(failure=0.9, stress_mpa_per_nm=0.6)
    first = _drawn("root_tooth_crack", 3)
    assert draw_growth(GrowthFamily(), "root_tooth_crack", nominal, 0.25, 39.0, 9, 3, 0) == first
    again = [draw_growth(GrowthFamily(), "root_tooth_crack", nominal, 0.25, 39.0, 9, 3, a)
             for a in (1, 2)]
    assert len({(d.paris_m, d.threshold_sif, d.failure) for d in [first, *again]}) == 3


def test_a_drawn_crack_grows_at_the_nominal_rate_at_the_pivot_and_stays_in_its_ranges():
    fam, nominal = GrowthFamily(), RunToFailure(failure=0.9, stress_mpa_per_nm=0.6)
    pivot = 1.12 * 0.6 * 39.0 * np.sqrt(np.pi * np.sqrt(0.25 * 0.9)
                                        * DEPTH_AT_ONE_M["root_tooth_crack"])
    ms, shares, fails = [], [], []
    for seed in range(200):
        d = _drawn("root_tooth_crack", seed)
        assert d.paris_c * pivot ** d.paris_m == pytest.approx(
            nominal.paris_c * pivot ** nominal.paris_m, rel=1e-12)
        ms.append(d.paris_m), shares.append(d.threshold_sif / pivot), fails.append(d.failure)
        assert d.activation_kj_per_mol is None
    assert fam.paris_m[0] <= min(ms) < 2.6 and 3.9 < max(ms) <= fam.paris_m[1]
    assert 0.0 <= min(shares) < 0.05 and 0.45 < max(shares) <= 0.5
    assert 0.25 < min(fails) and max(fails) <= 0.99  # the crack's top severity
    assert np.std(np.log(fails)) == pytest.approx(0.1, rel=0.2)


def test_a_drawn_wear_takes_an_arrhenius_law_that_wears_alike_at_the_pivot():
    from swgsim.datasets.growth import archard_depth
    d, nominal = _drawn("eccentric_wg", 1), RunToFailure()
    assert 20.0 <= d.activation_kj_per_mol <= 60.0 and (d.paris_m, d.threshold_sif) == (3.0, 0.0)
    load, revs = np.full(3, 39.0), np.full(3, 1e5)
    worn = {t: [archard_depth(load, revs, np.full(3, t), law.wear_coeff_m_per_nm_rev,
                              law.film_exponent, law.activation_kj_per_mol)[-1]
                for law in (d, nominal)] for t in (20.0, 40.0, 60.0)}
    assert worn[40.0][0] == pytest.approx(worn[40.0][1], rel=1e-12)  # the pivot
    assert worn[20.0][0] < worn[20.0][1] and worn[60.0][0] > worn[60.0][1]  # steeper


@pytest.mark.parametrize(("change", "match"), [
    ({"paris_m": [4.0, 2.5]}, r"growth.paris_m must be \[lo, hi\] with lo <= hi"),
    ({"paris_m": [0.5, 3.0]}, r"growth.paris_m\[0\] must lie in \[1, 6\], got 0.5"),
    ({"threshold_share": [0.0, 1.0]}, r"growth.threshold_share\[1\]"),
    ({"failure_spread": 2.0}, r"growth.failure_spread"),
])
def test_a_bad_growth_family_is_refused_in_one_line_naming_the_key(change, match):
    with pytest.raises(ValueError, match=match) as info:
        GrowthFamily(**change).check("growth")
    assert "\n" not in str(info.value)
