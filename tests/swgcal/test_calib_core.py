"""Numerical core of the calibration: recurrences, states, fits, uncertainty, splits."""

from __future__ import annotations

import numpy as np
import pytest

from swgcal.core import (
    FitTerm,
    Param,
    fit_terms,
    integrated_autocorr_time,
    linear_recurrence,
    solve_linear,
)
from swgcal.diagnose import noise_floor
from swgcal.periodogram import periodogram_peaks
from swgcal.split import group_split, time_block_split
from swgsim.gear.friction.effects import dahl_state, first_order_lag


def test_linear_recurrence_matches_loop():
    rng = np.random.default_rng(0)
    a, b = rng.uniform(0, 1, 1000), rng.standard_normal(1000)
    ref, x = np.empty(1000), 0.7
    for k in range(1000):
        x = a[k] * x + b[k]
        ref[k] = x
    np.testing.assert_allclose(linear_recurrence(a, b, 0.7), ref, rtol=1e-12, atol=1e-12)


def test_dahl_state_saturates_and_is_rate_independent():
    q = np.concatenate([np.linspace(0, 0.01, 200), np.linspace(0.01, 0.0, 50)])
    z = dahl_state(q, 1e-4)
    assert z[199] == pytest.approx(1.0, abs=1e-6)  # long travel up
    assert z[-1] == pytest.approx(-1.0, abs=1e-6)  # and back down
    # the same path sampled twice as densely gives the same state at common points
    q2 = np.interp(np.arange(0, 250, 0.5), np.arange(250), q)
    np.testing.assert_allclose(dahl_state(q2, 1e-4)[::2], z, atol=1e-9)
    with pytest.raises(ValueError, match="q_c"):
        dahl_state(q, 0.0)


def test_first_order_lag_step_response_on_irregular_samples():
    rng = np.random.default_rng(1)
    t = np.cumsum(rng.uniform(0.001, 0.02, 3000))
    t -= t[0]
    u = np.where(t > 1.0, 1.0, 0.0)
    y = first_order_lag(t, u, 0.5)
    k = t > 1.2
    # exact for a step held over the sample steps: 1 - exp(-(t - t_step)/tau), t_step the
    # first sample after 1 s, one sample's error at most
    t_step = t[np.argmax(t > 1.0) - 1]
    np.testing.assert_allclose(y[k], 1 - np.exp(-(t[k] - t_step) / 0.5), atol=0.05)


def test_integrated_autocorr_time_ar1():
    rng = np.random.default_rng(2)
    rho = 0.6
    e = np.empty(200_000)
    e[0] = 0
    w = rng.standard_normal(e.size)
    for k in range(1, e.size):
        e[k] = rho * e[k - 1] + w[k]
    assert integrated_autocorr_time(e) == pytest.approx((1 + rho) / (1 - rho), rel=0.1)
    assert integrated_autocorr_time(w) == pytest.approx(1.0, abs=0.15)


def test_noise_floor_removes_smooth_structure():
    rng = np.random.default_rng(3)
    t = np.sort(rng.uniform(0, 60, 20_000))
    r = 0.5 * np.sin(2 * np.pi * t / 7) + 0.02 * rng.standard_normal(t.size)
    assert noise_floor(t, r) == pytest.approx(0.02, rel=0.05)


def test_periodogram_finds_period_on_irregular_coordinate():
    rng = np.random.default_rng(4)
    x = np.sort(rng.uniform(-1, 1, 5000))
    r = 0.1 * np.sin(2 * np.pi * x / 0.037 + 1) + 0.05 * rng.standard_normal(x.size)
    (p, power), *_ = periodogram_peaks(x, r, 0.005, 1.0)
    assert p == pytest.approx(0.037, rel=0.01)
    assert 0.5 < power <= 1.2


class _Exp(FitTerm):
    kind = "exp"
    linear = (Param("a", "-"),)
    nonlinear = (Param("tau", "s", log=True),)

    def bounds(self, sig):
        return [(0.01, 100.0)]

    def starts(self, sig, residual, idx):
        return [np.array([1.0])]

    def columns(self, sig, theta):
        return np.exp(-sig / theta[0])[:, None]


class _Lin(FitTerm):
    kind = "lin"
    linear = (Param("c0", "-"), Param("c1", "-"))

    def columns(self, sig, theta):
        return np.column_stack([np.ones_like(sig), sig])


def test_separable_fit_recovers_parameters_and_uncertainty():
    rng = np.random.default_rng(5)
    t = np.linspace(0, 10, 4000)
    sigma = 0.01
    y = 0.3 + 0.05 * t + 2.0 * np.exp(-t / 1.7) + sigma * rng.standard_normal(t.size)
    idx = np.arange(t.size)
    f = fit_terms([_Lin(), _Exp()], t, y, idx)
    est = f.estimates_of("exp")
    assert est["tau"].value == pytest.approx(1.7, rel=0.01)
    assert est["a"].value == pytest.approx(2.0, rel=0.01)
    assert abs(est["tau"].value - 1.7) < 4 * est["tau"].std
    assert f.sigma == pytest.approx(sigma, rel=0.05)
    assert est["tau"].identifiable and est["a"].identifiable


class _Dup(_Lin):
    kind = "dup"
    linear = (Param("d1", "-"),)

    def columns(self, sig, theta):
        return sig[:, None] * (1 + 1e-9)


def test_identifiability_flag_for_collinear_columns():
    rng = np.random.default_rng(6)
    t = np.linspace(0, 1, 500)
    y = 1 + t + 0.01 * rng.standard_normal(t.size)
    f = fit_terms([_Lin(), _Dup()], t, y, np.arange(t.size))
    flags = {e.name: e.flag for e in f.estimates}
    assert flags["d1"] and flags["c1"]  # the data cannot tell c1 from d1
    assert "correlated" in {e.name: e.note for e in f.estimates}["d1"]
    assert not flags["c0"]


def test_time_block_split_roles_guards_and_errors():
    t = np.cumsum(np.random.default_rng(7).uniform(0.001, 0.003, 30_000))
    sp = time_block_split(t, n_blocks=10, validation_blocks=(3, 7), test_blocks=(5, -1),
                          guard_frac=0.05)
    block = (t[-1] - t[0]) / 10
    assert np.intersect1d(sp.fit, sp.test).size == 0
    assert np.intersect1d(sp.validation, sp.test).size == 0
    assert t[sp.test].max() == pytest.approx(t[-1])  # the last block is a test block
    # no fit sample within the guard of a test sample
    gap = np.min(np.abs(t[sp.fit][:, None] - t[sp.test][None, ::50]))
    assert gap >= 2 * 0.05 * block * 0.99
    assert sp.description["test_blocks"] == [5, 9]
    with pytest.raises(ValueError, match="both validation and test"):
        time_block_split(t, 10, (3,), (3,))
    with pytest.raises(ValueError, match="outside"):
        time_block_split(t, 10, (12,), (5,))


def test_group_split_holds_out_whole_groups():
    g = np.repeat(np.arange(6), 100)
    sp = group_split(g, [1], [4, 5])
    assert set(g[sp.test]) == {4, 5} and set(g[sp.validation]) == {1}
    assert not set(g[sp.fit]) & {1, 4, 5}
    with pytest.raises(ValueError, match="not in the data"):
        group_split(g, [9], [4])


def _design(seed=5, m=400):
    rng = np.random.default_rng(seed)
    x = np.column_stack([np.ones(m), rng.standard_normal((m, 3))])
    y = x @ np.array([2.0, 0.5, -1.0, 0.3]) + 0.1 * rng.standard_normal(m)
    return x, y


def test_the_fast_unbounded_solve_matches_the_reference_lstsq():
    x, y = _design()
    np.testing.assert_allclose(solve_linear(x, y), np.linalg.lstsq(x, y, rcond=None)[0],
                               rtol=1e-10, atol=1e-12)


def test_bounded_and_unbounded_solves_agree_where_no_bound_is_active():
    """Bounds wide of the solution: the bounded path (BVLS) gives the unbounded fast path's
    coefficients; the slow reference (lsq_linear on the tall matrix) agrees with both."""
    from scipy.optimize import lsq_linear

    x, y = _design()
    lo, hi = np.array([0.0, 0.0, -5.0, -np.inf]), np.array([np.inf, 3.0, 0.0, np.inf])
    fast = solve_linear(x, y)
    bounded = solve_linear(x, y, lo, hi)
    slow = lsq_linear(x, y, bounds=(lo, hi), method="trf", tol=1e-12).x
    # both are the same minimiser to rounding; the slow path's tolerance 1e-12 [choice]
    np.testing.assert_allclose(bounded, fast, rtol=1e-9, atol=1e-12)
    np.testing.assert_allclose(slow, fast, rtol=1e-6, atol=1e-8)


def test_an_active_bound_matches_the_slow_reference_and_equal_bounds_hold():
    from scipy.optimize import lsq_linear

    x, y = _design()
    lo, hi = np.array([-np.inf, -np.inf, 0.0, -np.inf]), np.full(4, np.inf)  # c2 wants -1
    c = solve_linear(x, y, lo, hi)
    assert c[2] == 0.0
    slow = lsq_linear(x, y, bounds=(lo, hi), method="bvls").x
    np.testing.assert_allclose(c, slow, rtol=1e-8, atol=1e-10)
    held = solve_linear(x, y, np.array([2.5, -np.inf, -np.inf, -np.inf]),
                        np.array([2.5, np.inf, np.inf, np.inf]))
    ref = np.linalg.lstsq(x[:, 1:], y - 2.5, rcond=None)[0]
    np.testing.assert_allclose(held, np.r_[2.5, ref], rtol=1e-9, atol=1e-12)
    with pytest.raises(ValueError, match="lo <= hi"):
        solve_linear(x, y, np.zeros(4), -np.ones(4))


class _Line(FitTerm):
    kind = "line"
    linear = (Param("a", "-"), Param("b", "-"))

    def columns(self, sig, theta):
        return np.column_stack([np.ones(sig.size), sig])


class _PositiveLine(_Line):
    def linear_bounds(self, sig):
        return [(-np.inf, np.inf), (0.0, np.inf)]


def test_a_fit_on_a_bound_is_flagged_and_an_inactive_bound_changes_nothing():
    rng = np.random.default_rng(6)
    t = np.linspace(0, 1, 300)
    idx = np.arange(t.size)
    up = 1.0 + 2.0 * t + 0.05 * rng.standard_normal(t.size)
    free, bounded = (fit_terms([c()], t, up, idx) for c in (_Line, _PositiveLine))
    np.testing.assert_allclose(bounded.coefs[0], free.coefs[0], rtol=1e-9)
    assert not any(e.bound for e in bounded.estimates)
    down = 1.0 - 2.0 * t + 0.05 * rng.standard_normal(t.size)
    f = fit_terms([_PositiveLine()], t, down, idx)
    b = f.estimates_of("line")["b"]
    assert b.value == 0.0 and b.on_bound and b.bound == "on its lower bound 0" and b.std == 0
