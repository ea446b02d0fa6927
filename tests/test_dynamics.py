"""Dynamic I/O model, paper eq. (1)-(6): catalogue fits, efficiency, integrator."""

import dataclasses

import numpy as np
import pytest
from scipy.optimize import brentq

from swgsim import dynamics as dy


def secant_stiffness(p: dy.GearParams, torque_nm: float) -> float:
    """Output-side secant stiffness T / δ from eq. (2)-(3) under a static output torque."""
    c = p.c_out
    t_stiff = torque_nm / c
    d = brentq(lambda x: p.k1_nm_per_rad * x + p.k2_nm_per_rad3 * x**3 - t_stiff, 0, 1)
    return torque_nm / (d / c)  # Δφ_k = c δ


def test_stiffness_matches_catalogue():
    cat = dy.Catalogue()
    p = dy.rt1_size20(cat)
    assert secant_stiffness(p, 2.0) == pytest.approx(cat.k1_nm_per_rad, rel=0.10)
    assert secant_stiffness(p, cat.t_low_nm) == pytest.approx(cat.k1_nm_per_rad, rel=0.10)
    assert secant_stiffness(p, cat.t_high_nm) == pytest.approx(cat.k3_nm_per_rad, rel=0.10)


@pytest.fixture(scope="module")
def rated():
    p = dy.rt1_size20()
    lower_b1 = dataclasses.replace(p, b1_nms=p.b1_nms * 2 / 3)
    return dy.simulate([p, lower_b1], 2000.0, 52.0, window_s=0.06)


def test_efficiency_at_rated_torque_in_catalogue_band(rated):
    assert rated.success
    assert rated.efficiency[0] == pytest.approx(0.77, abs=0.05)
    assert rated.t_out[0].mean() == pytest.approx(52.0, rel=1e-3)


def test_lower_b1_raises_efficiency_by_a_few_percent(rated):
    """Paper Table II: b1 lowered by 1/3 raises η by a few per cent (paper: about 7 %)."""
    gain = rated.efficiency[1] / rated.efficiency[0] - 1
    assert 0.01 < gain < 0.10


def test_rk4_agrees_with_solve_ivp():
    """Fixed-step RK4 (one step per 0.1 ms sample) against DOP853 at rtol 1e-10.

    Stated tolerance: output torque within 5e-4 of its ripple range, angles within 1e-8
    rad, efficiency within 1e-6.
    """
    p = dy.rt1_size20()
    for n, t in ((4000.0, 7.0), (2000.0, 70.0)):
        ref = dy.simulate_reference(p, n, t, phi_in0=0.3, window_s=0.03, settle_s=0.02)
        fast = dy.simulate([p], n, t, phi_in0=0.3, window_s=0.03, settle_s=0.02, substeps=1)
        assert np.abs(fast.t_out - ref.t_out).max() < 5e-4 * np.ptp(ref.t_out)
        assert np.abs(fast.states[0] - ref.states[0]).max() < 1e-8
        assert fast.efficiency[0] == pytest.approx(ref.efficiency[0], abs=1e-6)


def test_batch_equals_single_runs():
    p = dy.rt1_size20()
    q = dataclasses.replace(p, k1_nm_per_rad=p.k1_nm_per_rad * 0.8)
    both = dy.simulate([p, q], [2000.0, 4000.0], [7.0, 70.0], [0.1, 2.0], window_s=0.02)
    one = dy.simulate([q], 4000.0, 70.0, 2.0, window_s=0.02)
    np.testing.assert_allclose(both.t_out[1], one.t_out[0], rtol=1e-12, atol=1e-12)


@pytest.mark.parametrize("kw, match", [
    ({"n_in_rpm": 0.0, "t_out_nm": 7.0}, "n_in_rpm"),
    ({"n_in_rpm": -100.0, "t_out_nm": 7.0}, "n_in_rpm"),
    ({"n_in_rpm": 2000.0, "t_out_nm": -1.0}, "t_out_nm"),
])
def test_bad_operating_point_is_refused(kw, match):
    with pytest.raises(ValueError, match=match):
        dy.simulate([dy.rt1_size20()], **kw)


def test_calibrated_friction_effect_enters_the_dynamics():
    """An effect accepted by the calibration loop, as extra output friction."""
    from swgsim.calibration.chain import FrictionEffects

    p = dy.rt1_size20()
    base = dy.simulate([p], 2000.0, 39.0, window_s=0.02)
    fx = FrictionEffects([{"kind": "asymmetric_coulomb", "params": {"delta_c": -0.5}}],
                         v_s=1e-3)
    more = dy.simulate([p], 2000.0, 39.0, window_s=0.02, friction_effects=fx)
    assert more.t_out.mean() == pytest.approx(base.t_out.mean(), abs=0.01)  # load held
    assert more.efficiency[0] < base.efficiency[0] - 0.005  # more loss


@pytest.mark.parametrize("j_out", [8.8e-3, 0.69])
def test_torsional_mode_matches_the_simulated_ring_down(j_out):
    """The transient of a start without kinematic error, A(t) − B(t) with B already in
    periodic steady motion at the same input angle, decays at the predicted rate."""
    p = dy.rt1_size20(j_out_kgm2=j_out)
    n, tq, fs = 2000.0, 39.0, 20e3
    f_hz, tau = dy.torsional_mode(p, n, tq)
    settle = 20 * tau
    a = dy.simulate([p], n, tq, phi_in0=0.0, sample_rate_hz=fs, window_s=8 * tau,
                 settle_s=0.0, substeps=1)
    phi0 = -n * dy.RPM * settle
    for _ in range(3):  # B's input angle meets A's once A's transient has died out
        b = dy.simulate([p], n, tq, phi_in0=phi0, sample_rate_hz=fs, window_s=8 * tau,
                        settle_s=settle, substeps=1)
        phi0 -= b.states[0, 0, -1] - a.states[0, 0, -1]
    d = np.abs(a.t_out[0] - b.t_out[0])
    t = a.time
    # envelope: the largest |difference| in each of 8 blocks of one decay time
    blocks = np.array_split(np.arange(t.size), 8)
    env = np.array([d[i].max() for i in blocks])
    tm = np.array([t[i][np.argmax(d[i])] for i in blocks])
    slope = np.polyfit(tm[1:6], np.log(env[1:6]), 1)[0]
    assert -1.0 / slope == pytest.approx(tau, rel=0.05)
    # the ring-down oscillates at the mode's frequency: interpolated zero crossings of
    # A - B over the first six decay times
    x = (a.t_out[0] - b.t_out[0])[: int(6 * tau * fs)]
    i = np.flatnonzero(np.sign(x[:-1]) != np.sign(x[1:]))
    tc = (i - x[i] / (x[i + 1] - x[i])) / fs
    f_sim = (tc.size - 1) / 2 / (tc[-1] - tc[0])
    assert f_sim == pytest.approx(f_hz, rel=0.02)
