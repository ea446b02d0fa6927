"""The monitor through a real joint's day (preset tiny_real_day: daily warm-ups, the hall
warming, run-in, a heavier tool, the bridges' drift, a temperature sensor): no gear-fault
alarm on the healthy gear, the changes that leave commissioning's range advised, the
heavier tool's points recommissioned, and a fault under them still found and named
(swgmon/detection/normal.py); its temperature sensor's faults: test_temperature_sensor.py.
Fixtures: tests/learn/conftest.py."""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest
from real_day import commissioned, growing, repaired

from swgcli import dataset_preset
from swgmon.advisories.report import event_line
from swgmon.advisories.stream import (
    _after_change,
    adopt_change,
    monitor_stream,
)
from swgmon.assessment.gear_monitor import MaintenanceEvent
from swgmon.assessment.sensor_check import NamingConfig
from swgmon.detection.laws import LawFit, cools
from swgmon.detection.normal import EFFICIENCY, Conditions, NormalBehaviour, NormalConfig
from swgmon.detection.rule import Alarm, RuleConfig
from swgmon.evaluation.training import features_of
from swgsim.datasets.conditions import Regrease
from swgsim.datasets.config import dataset_config
from swgsim.datasets.life import LifeSimulator, life_dataset
from swgsim.datasets.schedule import FaultOnset
from swgsim.gear.thermal import FrictionLaw


def _stream(day, fault: FaultOnset, hours: float | None = None):
    """The same day with a fault, in memory (its healthy records from ``day``), to
    ``hours`` (None: the whole day; a life's windows do not depend on its length)."""
    p, bank = day
    life = dataclasses.replace(p.config.life, fault=fault)
    if hours is not None:
        life = dataclasses.replace(life, hours=hours)
    return life_dataset(LifeSimulator(p, 3, life, bank))


def test_a_healthy_real_day_raises_no_gear_fault_alarm(model, healthy):
    ds = healthy
    t = ds["temperature_c"].values
    assert t.max() - t.min() > 20.0  # warm-ups and the hall: the day is not flat
    res = monitor_stream(ds, model, RuleConfig(), source="day")
    assert res.alarms == []
    kinds = {a["condition"] for a in res.advisories}
    assert "load" in kinds  # the heavier tool from 36 h is advised, not alarmed
    assert all(a["hour"] >= 24.0 for a in res.advisories)  # none inside commissioning
    kinds = [e["kind"] for e in res.events()]
    assert kinds.count("advisory") == len(res.advisories)
    assert set(kinds) == {"advisory", "recommissioned"}  # no fault named
    assert all(r["hour"] >= 36.0 for r in res.recommissioned)  # the new tool's points


def test_a_fault_under_the_real_day_is_found_and_named(model, day):
    """The eccentric WG from 40 h, through warm-ups and the heavier tool (from 36 h): the
    day to 42 h (the rest of it would only be named again at each alarm)."""
    ds = _stream(day, FaultOnset("eccentric_wg", 40.0, 0.1), hours=42.0)
    res = monitor_stream(ds, model, RuleConfig(), source="day")
    assert res.alarms, "the eccentric WG under the real day was not found"
    first = res.alarms[0]
    assert 40.0 <= first.hour <= 41.0 and first.fault == "eccentric_wg"


def test_temperature_outside_its_range_is_refused_naming_the_window(model, healthy):
    ds = healthy.copy(deep=True)
    ds["temperature_c"].values[100] = 400.0
    with pytest.raises(ValueError, match=r"window 100 is 400 °C; allowed: in \[-40"):
        monitor_stream(ds, model, RuleConfig(), source="day")
    ds["temperature_c"].values[100] = -np.inf
    with pytest.raises(ValueError, match=r"window 100 is -inf °C; allowed: in \[-40.*or NaN"):
        monitor_stream(ds, model, RuleConfig(), source="day")


def _hot_after_commissioning(day):
    """The preset's healthy gear commissioned at a constant 30 °C (the hall at 30 °C, no
    warm-up, no stops, no run-in, no new tool) that runs at 80 °C from 24.1 h on: the
    grease and the bridges at 80 °C (issue 43, cause 2)."""
    from swgsim.gear.thermal import JointThermal

    p, bank = day
    life = p.config.life
    hot = JointThermal(r_th_k_per_w=1e-6, tau_min=0.1, ambient_c=30.0, ambient_swing_k=0.0,
                       ambient_points=[[0.0, 0.0], [24.0, 0.0], [24.1, 50.0]],
                       run_h_per_day=24.0)
    cond = dataclasses.replace(life.conditions, thermal=hot, run_in=None, payload=[])
    return life_dataset(LifeSimulator(p, 3, dataclasses.replace(
        life, hours=28.0, conditions=cond), bank))


def test_a_joint_commissioned_at_one_temperature_is_advised_not_alarmed_when_hot(model, day):
    """Commissioning's temperature varied by less than the fit's least spread (2 K): the
    temperature's range is still commissioning's, widened by the sensor's uncertainty;
    at 80 °C every window is outside it, advised once, and not judged (no gear-fault
    alarm: the eccentric WG this case raised before)."""
    from swgmon.detection.normal import Outside

    ds = _hot_after_commissioning(day)
    t, comm = ds["temperature_c"].values, ds["commissioning"].values
    assert np.ptp(t[comm]) < 2.0 and abs(t[comm].mean() - 30.0) < 0.5
    assert (t[~comm][ds["hour"].values[~comm] > 25.0] > 79.0).all()
    res = monitor_stream(ds, model, RuleConfig(), source="hot")
    assert res.alarms == []
    assert [a["condition"] for a in res.advisories][:1] == ["temperature"]
    assert 24.0 <= res.advisories[0]["hour"] <= 24.5
    hot = res.trace.hour > 25.0
    assert (res.trace.outside[hot] & Outside.TEMPERATURE).all()
    assert (res.trace.outside[hot] & Outside.UNJUDGED).all()
    assert (res.trace.p[hot] == 1.0).all()  # not judged: the CUSUMs hold
    assert (np.diff(res.trace.cusums[hot], axis=0) == 0.0).all()


@pytest.mark.parametrize(("form", "ratio_40c"), [("linear", 0.8), ("exponential", 0.3)])
def test_a_joint_commissioned_over_one_warm_up_learns_no_law_it_cannot_tell(
        model, day, form, ratio_40c):
    """Commissioning the first 8 h, one warm-up with the run-in going on and no cold
    start: which part of the friction's fall is the temperature's is not known
    (swgmon/detection/laws.py, loss_model). Its bounds are kept and the efficiency judged
    in the spread they make: no alarm at all (with the catalogue's law taken there, an
    unexplained change at 32.3 h for each of these laws)."""
    p, bank = day
    life = p.config.life
    life = dataclasses.replace(life, commissioning_h=8.0, conditions=dataclasses.replace(
        life.conditions, friction_law=FrictionLaw(form, ratio_40c)))
    ds = life_dataset(LifeSimulator(p, 3, life, bank))
    comm = ds["commissioning"].values
    assert not cools(ds["temperature_c"].values[comm], LawFit().min_spread_k)
    res = monitor_stream(ds, model, RuleConfig(), source="day")
    assert [(a.hour, a.fault) for a in res.alarms] == []


def test_the_threshold_reported_is_the_one_the_rule_used(model, healthy, tmp_path):
    """An unevenly spaced stream (window 1 missing: its first spacing 4 min, the median
    2 min): the result, summary.json and report.md carry h of the median spacing, the
    rule's, not of the first two windows' (issue 43, cause 5)."""
    import json

    from swgmon.advisories.report import write_outputs
    from swgmon.detection.rule import threshold

    ds = healthy.isel(sample=np.r_[0, 2:healthy.sizes["sample"]])
    hours = ds["hour"].values
    assert (hours[1] - hours[0]) * 60 == pytest.approx(4.0)
    res = monitor_stream(ds, model, RuleConfig(), source="uneven")
    used = threshold(RuleConfig(), 60 * float(np.median(np.diff(hours))))
    assert res.threshold == used != threshold(RuleConfig(), 4.0)
    write_outputs(res, tmp_path, "uneven")
    assert json.loads((tmp_path / "summary.json").read_text())["threshold"] == used
    assert f"alarm threshold h = {used:.2f}." in (tmp_path / "report.md").read_text()


def test_the_monitor_app_ends_well_on_a_day_with_recommissioned_points(model, tmp_path,
                                                                        monkeypatch, capsys):
    """swgsim-monitor on the preset tiny_real_day as swgsim-generate writes it (the heavier
    tool's points recommissioned): every event printed by its kind, exit 0 (it printed a
    recommissioning as an alarm and ended in KeyError: 'fault', issue 43, cause 1). The
    console's entry point in this process, as its command line runs it (a fresh process
    cost an import of the stack and tested nothing more)."""
    import json
    import sys

    from swgcli.monitor import main
    from swgmon.assessment.model_io import save_model
    from swgsim.datasets.generate import generate

    generate(dataset_config(dataset_preset("tiny_real_day")), tmp_path / "day", n_jobs=1,
             progress=False)
    m = save_model(model, tmp_path / "model", [{"name": "tiny_bench"}])
    monkeypatch.setenv("HYDRA_FULL_ERROR", "0")
    monkeypatch.chdir(tmp_path)
    monkeypatch.setattr(sys, "argv", [
        "swgsim-monitor", f"stream={tmp_path / 'day'}", f"diagnosis_model={m}",
        f"out_dir={tmp_path / 'out'}", "~logger", f"hydra.run.dir={tmp_path / 'hydra'}"])
    capsys.readouterr()
    code = 0
    try:
        main()
    except SystemExit as e:
        code = e.code
    run = capsys.readouterr()
    assert code in (0, None), run.err
    summary = json.loads((tmp_path / "out" / "summary.json").read_text())
    kinds = [e["kind"] for e in summary["events"]]
    assert "recommissioned" in kinds and "advisory" in kinds
    lines = run.out.splitlines()
    assert f"alarm threshold h = {summary['threshold']:.2f}" in lines
    assert sum(s.startswith("recommissioned at ") for s in lines) == kinds.count(
        "recommissioned")
    report = (tmp_path / "out" / "report.md").read_text()
    assert report.count("- recommissioned at ") == kinds.count("recommissioned")


@pytest.mark.parametrize(("form", "ratio_40c"), [("linear", 0.8), ("exponential", 0.5),
                                                 ("saturating", 0.8)])
def test_a_joint_whose_friction_follows_another_law_raises_no_gear_fault_alarm(
        model, day, form, ratio_40c):
    """Daily warm-ups with the friction following a law the monitor does not share (the
    catalogue's viscosity law gave an eccentric-WG alarm at 32.4 h for each of these): the
    monitor learns the joint's law at commissioning (swgmon/detection/normal.py)."""
    p, bank = day
    life = p.config.life
    law = FrictionLaw(form, ratio_40c)
    life = dataclasses.replace(life, conditions=dataclasses.replace(life.conditions,
                                                                    friction_law=law))
    ds = life_dataset(LifeSimulator(p, 3, life, bank))
    res = monitor_stream(ds, model, RuleConfig(), source="day")
    assert res.alarms == []


def test_an_even_change_of_friction_is_named_an_unexplained_change_not_a_gear_fault(
        model, healthy):
    """The loss torque 50 % higher at every operating point from 40 h (what a
    re-greasing does to the efficiency alone; the bridges left as they were): no gear
    fault's signature, so the alarm says "unexplained change" with the friction's change
    (swgmon/assessment/sensor_check.py, fit_friction) - the part the friction tracking had not
    followed by then - and the monitor goes on from the new level without a gear-fault
    alarm. (A 20 % step the tracking follows before any alarm, on this warming joint.)"""
    ds = healthy.copy(deep=True)
    eta = ds["efficiency"].values
    later = ds["hour"].values >= 40.0
    eta[later] = 1.0 / (1.0 + 1.5 * (1.0 / eta[later] - 1.0))
    res = monitor_stream(ds, model, RuleConfig(), source="day")
    named = [e for e in res.events() if e["kind"] not in ("advisory", "recommissioned")]
    assert named and {e["kind"] for e in named} == {"unexplained_change"}
    assert 40.0 <= named[0]["hour"] <= 42.0
    assert 0.1 <= named[0]["severity"] <= 0.5
    # issue 87: an interval of finite width from the fit's profile, not [x, x]
    assert named[0]["severity_low"] < named[0]["severity"] < named[0]["severity_high"]
    assert "unexplained change" in event_line(named[0]) and "] %" in event_line(named[0])


def test_a_declared_regreasing_recommissions_the_friction_an_undeclared_one_is_unexplained(
        model, day):
    """The joint re-greased at 40 h (its friction 50 % up at once, running in again over
    8 h) with the efficiency's law linear: declared in the maintenance log, the monitor
    follows the friction window by window for a day (NormalConfig.regrease_settle_h) and
    raises no alarm, listing the declared event; undeclared, the alarm names an
    unexplained change (the friction up), not a gear fault."""
    p, bank = day
    life = p.config.life
    cond = dataclasses.replace(life.conditions, friction_law=FrictionLaw("linear", 0.8),
                               regrease=Regrease(hours=[40.0], drop=0.5, tau_h=8.0))
    ds = life_dataset(LifeSimulator(p, 3, dataclasses.replace(life, conditions=cond), bank))
    log = [MaintenanceEvent(40.0, "regrease")]
    res = monitor_stream(ds, model, RuleConfig(), source="day", maintenance=log)
    assert res.alarms == []
    assert [r["maintenance"] for r in res.recommissioned if r.get("declared")] == ["regrease"]
    res = monitor_stream(ds, model, RuleConfig(), source="day")
    assert [a.kind for a in res.alarms] == ["unexplained_change"]  # measured: at 41.20 h
    assert 40.0 <= res.alarms[0].hour <= 42.0 and res.alarms[0].severity > 0
    with pytest.raises(ValueError, match=r"maintenance\[0\]\.kind: 'oil' is not one of"):
        monitor_stream(ds, model, RuleConfig(), maintenance=[MaintenanceEvent(40.0, "oil")])


@pytest.mark.parametrize(("change", "settles"), [(0.0025, False), (0.04, False), (0.3, True)])
def test_an_unexplained_change_within_seen_friction_is_not_followed_window_by_window(
        change, settles):
    """A change the friction fit found within what commissioning saw (its range widened by
    friction_margin, 5 %; a false alarm on bench sensor_stuck scored seeds 1 and 2: about
    0.25 % at 32-33 h) is adopted at its level but followed at the usual pace: followed
    window by window for regrease_settle_h, the tracking absorbed the stuck reading's
    efficiency evidence later (root crack named 28 and 219 times). A re-greasing's step
    (+30 %) is a friction commissioning did not see, and is followed so."""

    class Normal:  # what adopt_change asks of the monitor's normal behaviour
        friction_range = np.array([0.9998, 1.0002])
        config = NormalConfig()
        beyond_friction = NormalBehaviour.beyond_friction

    mon = dataclasses.make_dataclass("M", ["normal", "regreased"])(Normal(), [])
    alarm = Alarm(32.35, 0, 0, "unexplained_change", "unexplained_change", change, change,
                  change, None, [])
    assert adopt_change(mon, alarm, 1.0) == pytest.approx(1.0 + change)
    assert mon.regreased == ([32.35] if settles else [])


def test_a_gear_fault_soon_after_an_unexplained_change_is_named_again():
    """A gear-fault alarm within naming.recur_h after an unexplained change, while the reading is
    in use, is named again with the change undone (stream._after_change, then _drifting:
    a drifting reading whose first effect was taken for the friction); not after a day,
    not without a reading in use, not an unexplained change (the recurring change's own
    rule) and not a sensor's fault."""

    def alarm(hour, fault):
        return Alarm(hour, 0, 0, fault, fault, 0.1, 0.1, 0.1, None, [])

    mon = dataclasses.make_dataclass("M", ["reading_virtual", "naming"])(False, NamingConfig())
    recur_h = mon.naming.recur_h
    cond = Conditions(np.ones(2), np.full(2, 30.0))
    before = [alarm(10.0, "unexplained_change")]
    assert _after_change(mon, before, alarm(12.0, "reduced_damping"), 12.0, cond)
    assert not _after_change(mon, before, alarm(10.0 + recur_h + 0.1, "root_crack"),
                             10.0 + recur_h + 0.1, cond)
    assert not _after_change(mon, [alarm(10.0, "root_crack")], alarm(12.0, "root_crack"),
                             12.0, cond)
    assert not _after_change(mon, before, alarm(12.0, "unexplained_change"), 12.0, cond)
    assert not _after_change(mon, before, alarm(12.0, "temperature_sensor"), 12.0, cond)
    assert not _after_change(mon, before, alarm(12.0, "reduced_damping"), 12.0,
                             Conditions(np.ones(2)))
    mon.reading_virtual = True
    assert not _after_change(mon, before, alarm(12.0, "reduced_damping"), 12.0, cond)


def test_a_slowly_growing_fault_under_warm_ups_is_alarmed_not_absorbed(model, day):
    """An eccentric WG growing linearly from 0 at 26 h to its mildest Table V severity
    (0.05) 40 h later, through the daily warm-ups, the friction following a linear law:
    the friction tracking does not absorb it (measured: alarmed at 42.4 h, named right),
    and an advisory that recommends recommissioning says what it would relearn."""
    p, bank = day
    ds = life_dataset(LifeSimulator(p, 3, growing(p.config.life), bank))
    res = monitor_stream(ds, model, RuleConfig(), source="day")
    assert res.alarms and res.alarms[0].fault == "eccentric_wg"
    assert 26.0 < res.alarms[0].hour < 66.0
    assert all("relearns as normal" in a["advice"] and "x commissioning's" in a["advice"]
               for a in res.advisories)


def test_a_declared_repair_commissions_the_monitor_anew(model, day):
    """An eccentric WG from 30 h, repaired at 34 h (the fault gone): declared, the monitor
    commissions anew on 24 h of windows after the repair and monitors the rest (measured:
    the fault alarmed at 30.27 h, nothing after); a repair inside commissioning is
    refused naming its hour."""
    p, bank = day
    ds = life_dataset(LifeSimulator(p, 3, repaired(p.config.life), bank))
    res = monitor_stream(ds, model, RuleConfig(), source="day",
                         maintenance=[MaintenanceEvent(34.0, "repair")])
    assert [(a.fault, a.hour < 31.0) for a in res.alarms] == [("eccentric_wg", True)]
    entry = [r for r in res.recommissioned if r.get("declared")]
    assert [r["maintenance"] for r in entry] == ["repair"] and entry[0]["hour"] == 34.0
    assert len(res.trace.hour) == ds.sizes["sample"] - 2 * res.n_commissioning
    assert res.trace.hour[0] >= 24.0 and np.all(np.diff(res.trace.hour) > 0)
    assert all(len(event_line(e)) for e in res.events())
    with pytest.raises(ValueError, match=r"maintenance\[0\]\.hour: a repair at 10 h; allowed"):
        monitor_stream(ds, model, RuleConfig(), maintenance=[MaintenanceEvent(10.0, "repair")])




def test_a_tool_change_too_late_to_commission_anew_says_so_and_keeps_later_events(
        model, healthy):
    """Issue 82, cause 4: a tool change declared at 50 h leaves 10 h of windows, fewer than
    commissioning's 24 h: the entry said the monitor commissions anew, the re-greasing
    declared after it was missing and the last 10 h went unmonitored without a word. Now
    both events are listed, each saying it is not monitored and why."""
    log = [MaintenanceEvent(50.0, "tool_change"), MaintenanceEvent(55.0, "regrease")]
    res = monitor_stream(healthy, model, RuleConfig(), source="day", maintenance=log)
    entry = [r for r in res.recommissioned if r.get("declared")]
    assert [(r["maintenance"], r["hour"], r["monitored"]) for r in entry] == [
        ("tool_change", 50.0, False), ("regrease", 55.0, False)]
    assert "fewer than the 720 commissioning needs" in entry[0]["note"]
    assert "windows from 50 h to 59.97 h are not monitored" in entry[0]["note"]
    assert "not monitored, after the tool change at 50 h" in entry[1]["note"]
    assert res.trace.hour[-1] < 50.0
    assert all(len(event_line(e)) for e in res.events())


def test_the_friction_is_tracked_only_where_the_loss_law_is_not_extrapolated(model, day):
    """GearMonitor.track_friction: a window beyond commissioning's temperatures is no
    evidence of the friction (its loss law there an extrapolation: end slopes carried on,
    below a convex law), so it leaves the tracked factor where it was; the same windows
    inside the range move it. The default evaluation's bench under the hall 10 K warmer:
    the factor tracked to 1.005-1.007 on the hot windows then read each cold start's
    efficiency +1.7 sigma high (bench gear 2, seed 1: 7 reduced-damping alarms in 200 h;
    none with the hot windows left out)."""
    mon, sim, n_comm = commissioned(model, day)[:3]
    g, gp, gm = features_of(sim, n_comm, n_comm + 20)
    g[:, EFFICIENCY] *= 0.9  # a loss well above the law's
    hours = np.asarray(gm["hour"], float)
    inside = Conditions.of(gm)
    hot = Conditions(inside.torque_nm, inside.temperature_c * 0 + mon.normal.temp_range[
        mon.normal.index(gp), 1] + 3.0 * mon.normal.config.temperature_margin_k)
    start = mon.friction, mon.last_hour
    for c, moves in ((inside, True), (hot, False)):
        fork = mon.fork()
        fr = fork.track_friction(g, gp, hours, c, fork.normal.index(gp))
        assert fr[0] == start[0]
        assert (fork.friction > start[0] + 1e-3) == moves, (c, fork.friction, start)
