"""Friction calibration accepts only physics: declared ranges, harmonic ripple groups.

* every library effect declares the physical range of its characterising parameters,
  with a source;
* a planted frictional memory of 5 ms is accepted inside its range; a lag of 0.6 s (as a
  fit on a real recording gave) is rejected as implausible and reported;
* a planted out-of-range thermal drift (12 s on a 60 s recording; warm-up takes minutes)
  is reported as structure of the final residual that a rejected candidate would have
  absorbed;
* harmonics 2 and 4 of the wave-generator turn come back as one grouped effect labelled
  with their orders.
"""

from __future__ import annotations

import math
import re

import numpy as np
import pytest

from swgcal import SelectionConfig, render_report
from swgcal.friction import calibrate, friction_problem, summarize
from swgcal.friction.library import PositionRipple
from swgcal.friction.ripple_groups import harmonic_groups
from swgcal.friction.synthetic import synthetic_recording
from swgsim.gear.friction import FRICTION_LIBRARY
from swgsim.gear.friction.ripples import RippleTerm

N = 50  # gear ratio of the harmonic-group case


def run(effects, seed=0, candidates=None, gear_ratio=None, **rec_kw):
    rec, truth = synthetic_recording(effects, rng=np.random.default_rng(seed), **rec_kw)
    problem = friction_problem(rec, v_s=truth.v_s, gear_ratio=gear_ratio)
    cfg = SelectionConfig(candidates=candidates) if candidates else None
    return calibrate(problem, cfg), truth


@pytest.mark.parametrize("gear_ratio", [None, 100.0])
def test_every_effect_declares_ranges_with_sources(gear_ratio):
    rec, truth = synthetic_recording([], duration_s=10, rng=np.random.default_rng(0))
    sig = rec.signals(v_s=truth.v_s, gear_ratio=gear_ratio)
    for key, cls in FRICTION_LIBRARY.items():
        term = cls.for_signals(sig, key)
        names = set(term.primary()) | {p.name for p in term.nonlinear}
        for name in names:
            if isinstance(term, RippleTerm) and name == "period" and gear_ratio:
                name = "order"  # with N the range is on the wave-generator order
            assert name in term.ranges, (key, name)
            lo, hi, src = term.ranges[name]
            assert lo < hi, (key, name)
            # a source names a publication year, a standard or the project's docs
            assert any(ch.isdigit() for ch in src) or "docs/" in src, (key, src)


def test_range_violations_name_parameter_range_and_source():
    from swgcal.friction.library import ThermalDrift, VelocityLag

    v = VelocityLag().range_violations({"t_lag": 0.6})
    assert len(v) == 1 and "t_lag = 0.6 s outside [0.0001, 0.05] s" in v[0]
    assert "Hess & Soom" in v[0]
    assert VelocityLag().range_violations({"t_lag": 0.005}) == []
    assert ThermalDrift().range_violations({"t_th": 3.6, "d": 0.1})[0].startswith("t_th")
    # a ripple of the gear: wave-generator orders between 2/N and 4(N + 1)
    r = PositionRipple(gear_ratio=N)
    assert r.range_violations({"order": 2.0, "amplitude": 0.1}) == []
    assert r.range_violations({"order": 0.5 / N, "amplitude": 0.1})


def test_harmonic_groups_with_and_without_gear_ratio():
    p2, p4 = 2 * math.pi / (2 * N), 2 * math.pi / (4 * N)
    g = harmonic_groups([p2, p4 * 1.002, 0.037], gear_ratio=N)
    assert len(g) == 1 and g[0].members == (0, 1) and g[0].harmonics == (2, 4)
    # order 2.1 is no integer order: not grouped (tolerance 1 %)
    assert harmonic_groups([p2 / 1.05, p4], gear_ratio=N) == []
    # without N: the longest period, or a multiple of it, is the fundamental
    g = harmonic_groups([0.06, 0.0301, 0.02])
    assert len(g) == 1 and g[0].harmonics == (1, 2, 3)
    g = harmonic_groups([0.04, 0.08 / 3])  # orders 2 and 3 of a missing fundamental
    assert g[0].harmonics == (2, 3) and g[0].fundamental == pytest.approx(0.08, rel=1e-3)
    assert harmonic_groups([0.05, 0.0371]) == []  # ratio 1.35: unrelated
    # a longer period that groups with nothing does not block the others
    g = harmonic_groups([0.0032, 0.00125, 0.000625])
    assert len(g) == 1 and g[0].members == (1, 2) and g[0].harmonics == (1, 2)
    # standard errors widen the tolerance (3 s.e.: 1.5 % and 1.8 %, combined 2.3 %) ...
    assert harmonic_groups([0.06, 0.0306]) == []  # 2 % off, tolerance 1.4 %
    assert harmonic_groups([0.06, 0.0306], rel_se=[0.005, 0.006])[0].harmonics == (1, 2)
    # ... but a period known only to 3 % (3 s.e.) joins no group
    assert harmonic_groups([0.06, 0.0301], rel_se=[0.01, 0.001]) == []


def test_planted_5ms_velocity_lag_is_accepted_inside_its_range():
    # 2 ms sampling, as the Franka recordings: a 5 ms lag spans 2.5 samples
    res, truth = run([{"kind": "velocity_lag", "params": {"t_lag": 0.005}}], seed=1,
                     candidates=["velocity_lag", "inertia", "stribeck", "presliding"],
                     dt_s=0.002, duration_s=30.0)
    assert res.added == ["velocity_lag"], [c.status for c in res.iterations[0].candidates]
    est = res.final.estimates_of("velocity_lag")["t_lag"]
    assert est.value == pytest.approx(0.005, rel=0.10)
    s = summarize(res)
    assert s["effects_added"][0]["ranges"]["t_lag"]["inside"]
    assert not s["implausible_candidates"]


def test_lag_of_0p6_s_is_rejected_as_implausible():
    res, truth = run([{"kind": "velocity_lag", "params": {"t_lag": 0.6}}], seed=2,
                     candidates=["velocity_lag", "inertia", "stribeck", "presliding"])
    assert "velocity_lag" not in res.added
    lags = [c for it in res.iterations for c in it.candidates if c.kind == "velocity_lag"
            and c.implausible]
    assert lags, [c.status for it in res.iterations for c in it.candidates]
    assert lags[0].params["t_lag"] == pytest.approx(0.6, rel=0.1)
    assert "t_lag = " in lags[0].status and "outside [0.0001, 0.05] s" in lags[0].status
    s = summarize(res)
    imp = [c for c in s["implausible_candidates"] if c["kind"] == "velocity_lag"]
    assert imp and imp[0]["validation_gain"] > 0


def test_out_of_range_thermal_drift_is_reported_as_absorbable_structure():
    res, truth = run([{"kind": "thermal_drift", "params": {"d": 0.2, "t_th": 12.0}}], seed=3)
    assert "thermal_drift" not in res.added
    s = summarize(res)
    imp = [c for c in s["implausible_candidates"] if c["final_iteration"]
           and c["kind"] == "thermal_drift"]
    assert imp, [c["status"] for c in s["iterations"][-1]["candidates"]]
    assert imp[0]["validation_gain"] > 0.05
    assert "t_th = 1" in imp[0]["violations"] and "[60, inf] s" in imp[0]["violations"]
    assert res.unexplained
    md = render_report(res, s)
    assert "rejected as implausible" in md and "thermal_drift" in md


def test_harmonics_of_one_fundamental_come_back_as_one_effect_with_orders():
    p0 = 2 * math.pi / N  # one wave-generator turn over the output angle
    planted = {"kind": "position_ripple", "options": {"harmonics": [2, 4]},
               "params": {"period": p0, "a_sin_2": 0.03, "a_cos_2": 0.02, "a_sin_4": 0.02,
                          "a_cos_4": -0.015}}
    res, truth = run([planted], seed=4, gear_ratio=N,
                     candidates=["position_ripple", "friction_ripple", "stribeck"])
    ripples = [t for t in res.effect_terms() if isinstance(t, RippleTerm)]
    assert len(ripples) == 1, res.added
    (r,) = ripples
    assert r.harmonics == (2, 4)
    period = float(res.final.thetas[res.final.terms.index(r)][0])
    # reached: orders within 5e-4 of 2 and 4 (seed 4); tolerance 2e-3
    np.testing.assert_allclose(r.orders(period), [2.0, 4.0], atol=2e-3)
    est = res.final.estimates_of(r.name)
    # reached: 0.6 and 2.6 standard errors (s.e. 2-3 % of the amplitude); tolerance 4 s.e.
    for h, true in ((2, math.hypot(0.03, 0.02)), (4, math.hypot(0.02, 0.015))):
        e = est[f"amplitude_{h}"]
        assert e.std < 0.05 * true and abs(e.value - true) < 4 * e.std, (h, e)
    s = summarize(res)
    (g,) = s["ripples"]["groups"]
    assert g["grouped"] and g["harmonics"] == [2, 4]
    hist = [h for h in s["ripples"]["history"] if h["accepted"]]
    assert len(hist) == 2 and hist[1]["val_rmse_after"] < hist[0]["val_rmse_after"]
    e = next(e for e in s["effects_added"] if e["name"] == r.name)
    assert e["orders"]["integer_order"] == [True, True]
    assert res.rmse_after <= 1.2 * truth.sigma
    assert re.search(r"wave-generator orders (1\.99\d|2\.00\d), (3\.99\d|4\.00\d)",
                     render_report(res, s))
