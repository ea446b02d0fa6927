"""The monitor evaluation's tables with lives of a real day beside the stationary ones
(swgmon.evaluation.report), on small hand-made result frames whose figures are known."""

from __future__ import annotations

import numpy as np
import pandas as pd
import pytest

from swgmon.evaluation.report import (
    _mildest_detected,
    false_alarm_table,
    nuisance_table,
    real_day_figure,
    targets,
    with_nuisance,
    write_table,
)


def _frames() -> tuple[pd.DataFrame, pd.DataFrame]:
    """Two held-out gears of one data set, stationary and under 'hall'; the monitor and the
    per-window rule. Gear 2 under 'hall': one gear-fault alarm and two advisories in 200 h;
    its mild eccentric WG found after 90 min, the strong one after 6 min."""
    fa, res = [], []
    for n in ("none", "hall"):
        for g in (1, 2):
            key = {"dataset": "bench", "held_out_gear": g, "seed": 0, "nuisance": n}
            bad = n == "hall" and g == 2
            fa.append({**key, "detector": "monitor", "healthy_hours": 200.0,
                       "false_alarms": 1 if bad else 0, "gear_fault_alarms": 1 if bad else 0,
                       "advisories": 2 if bad else 0})
            fa.append({**key, "detector": "per_window", "healthy_hours": 200.0,
                       "false_alarms": 40})
            for d in ("monitor", "per_window"):
                for sev, ttd in ((0.05, 1.5 if bad else 0.2), (0.2, 0.1)):
                    res.append({**key, "detector": d, "fault": "eccentric_wg",
                                "severity": sev, "onset": "step", "detected": True,
                                "time_to_detect_h": ttd, "fault_at_alarm": "eccentric_wg",
                                "fault_after_1h": "eccentric_wg", "severity_est": sev,
                                "severity_at_alarm": sev})
    return pd.DataFrame(res), pd.DataFrame(fa)


def test_an_older_table_reads_as_stationary_with_every_alarm_a_gear_fault_alarm():
    fa = pd.DataFrame({"dataset": ["b"], "detector": ["per_window"], "held_out_gear": [1],
                       "healthy_hours": [100.0], "false_alarms": [3]})
    out = with_nuisance(fa)
    assert out.nuisance.tolist() == ["none"]
    assert out.gear_fault_alarms.tolist() == [3] and out.advisories.tolist() == [0]



def test_sensor_faults_and_unexplained_changes_are_counted_apart():
    """false_alarm_table: of 5 alarms in 100 h, 1 a gear fault's, 1 a sensor fault's and 3
    unexplained changes: 10, 10 and 30 per 1000 h (an unexplained change is not a sensor
    fault: the real-day table called both 'sensor-fault alarms' until the rerun at
    55b9bf7); a table without the kinds counts every other alarm a sensor fault's."""
    fa = pd.DataFrame({"dataset": ["b"], "detector": ["monitor"], "held_out_gear": [1],
                       "nuisance": ["all"], "healthy_hours": [100.0], "false_alarms": [5],
                       "gear_fault_alarms": [1], "sensor_fault_alarms": [1],
                       "unexplained_changes": [3], "advisories": [0]})
    row = false_alarm_table(fa).iloc[0]
    assert (row.gear_fault_per_1000_h, row.sensor_fault_per_1000_h,
            row.unexplained_per_1000_h) == pytest.approx((10.0, 10.0, 30.0))
    old = false_alarm_table(fa.drop(columns=["sensor_fault_alarms", "unexplained_changes"]))
    assert (old.sensor_fault_per_1000_h.item(), old.unexplained_per_1000_h.item()) == (40.0, 0.0)

def test_gear_fault_alarms_and_advisories_are_counted_apart_per_nuisance():
    _, fa = _frames()
    t = false_alarm_table(fa)
    row = t[(t.nuisance == "hall") & (t.detector == "monitor") & (t.held_out_gear == 2)]
    assert row.gear_fault_per_1000_h.item() == pytest.approx(5.0)
    assert row.advisories_per_1000_h.item() == pytest.approx(10.0)
    assert row.sensor_fault_per_1000_h.item() == 0.0
    pw = t[(t.nuisance == "hall") & (t.detector == "per_window")]
    assert (pw.gear_fault_per_1000_h == 200.0).all() and (pw.advisories == 0).all()


def test_the_real_day_table_puts_each_nuisance_beside_the_stationary_lives():
    res, fa = _frames()
    wide = nuisance_table(res, fa)
    assert list(wide.columns[-2:]) == ["none", "hall"]
    mon = wide[wide.detector == "monitor"].set_index("what")
    gf = mon.loc["gear-fault alarms per 1000 h (worst gear)"]
    assert gf["none"] == 0.0 and gf["hall"] == pytest.approx(5.0)
    ttd = mon.loc[[w for w in mon.index if w.startswith("median time to detect")][0]]
    assert ttd["none"] == pytest.approx(12.0) and ttd["hall"] == pytest.approx(90.0)
    assert set(wide.detector) == {"monitor", "per_window"}


def test_stationary_targets_ignore_the_nuisance_lives_and_the_table_shows_both(tmp_path):
    res, fa = _frames()
    t = targets(res, fa).set_index("what")
    assert t.loc["false alarms per 1000 h (worst gear)", "measured"].startswith("0 (0 in 400 h)")
    text = write_table(res, fa, tmp_path / "table.md")
    assert "## A real day" in text and "| hall |" in text.splitlines()[
        text.splitlines().index(next(ln for ln in text.splitlines() if "A real day" in ln)) + 2]
    assert np.isfinite(nuisance_table(res, fa).iloc[:, -1].astype(float)).any()


def test_without_nuisance_lives_there_is_no_real_day_table(tmp_path):
    res, fa = _frames()
    res, fa = res[res.nuisance == "none"], fa[fa.nuisance == "none"]
    assert nuisance_table(res, fa).empty
    assert "A real day" not in write_table(res, fa, tmp_path / "table.md")


def test_the_real_day_figure_shows_each_nuisance_and_the_mildest_faults(tmp_path):
    res, fa = _frames()
    res.loc[(res.nuisance == "hall") & (res.held_out_gear == 2) & (res.severity == 0.05)
            & (res.detector == "monitor"), "detected"] = False
    det = _mildest_detected(res)
    assert det.loc[("bench", "hall", "eccentric_wg"), "mean"] == pytest.approx(0.5)
    assert det.loc[("bench", "none", "eccentric_wg"), "size"] == 2
    (p,) = real_day_figure(res, fa, tmp_path)
    assert p == tmp_path / "real_day.png" and p.stat().st_size > 10_000
    none = res.nuisance == "none"
    assert real_day_figure(res[none], fa[fa.nuisance == "none"], tmp_path / "x") == []
    other = fa[fa.detector == "per_window"].assign(dataset="robot_joint")  # no monitor rows
    (p,) = real_day_figure(res, pd.concat([fa, other]), tmp_path)  # as before: bench only
