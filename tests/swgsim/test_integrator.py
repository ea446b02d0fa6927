"""The compiled RK4 integrator against the array form of the gear model.

swgsim.gear.integrator integrates each variant with scalar arithmetic; the reference here is
the same RK4 on arrays (``rk4_record``) with the model's array right-hand side
(``dynamics.rhs``) and the profile's inputs added as ``simulate_profile`` added them before the
integrator was compiled. Same model, step and stage times: the states agree to rounding
(bit-identical on the developers' machine; 1e-12 relative allowed for other libm builds).
"""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest

from swgsim.gear import dynamics as dy
from swgsim.gear import integrator as it
from swgsim.gear import profile as pf
from swgsim.gear import profile_dynamics as pd

RTOL = 1e-12


def _close(a, b):
    scale = np.abs(b).max(axis=-1, keepdims=True) + 1e-300
    assert np.max(np.abs(a - b) / scale) < RTOL


def _variants():
    p = dy.rt1_size20(j_out_kgm2=0.69)
    return [p, dataclasses.replace(p, backlash_rad=2e-4, k1_nm_per_rad=0.8 * p.k1_nm_per_rad)]


def test_steady_window_matches_the_array_form():
    """A steady window (speed and brake per variant, one with backlash) from simulate equals
    RK4 on dynamics.rhs from the same start, sample by sample, after the settling time."""
    gs = _variants()
    w_d, t_l = np.array([1000.0, 2500.0]) * dy.RPM, np.array([10.0, 39.0])
    bk = dy.ke_batch(dy.Batch.of(gs))
    x0 = dy.steady_state(bk, w_d, t_l, np.array([0.3, 1.0]))
    h = 1.0 / (10e3 * 2)
    ref = it.rk4_record(lambda j, x, last=False: dy.rhs(0.0, x, bk, w_d, t_l), x0, 40, 60, 2, h)
    res = dy.simulate(gs, w_d / dy.RPM, t_l, [0.3, 1.0], window_s=0.006, settle_s=0.004)
    _close(res.states, ref)


def _reference_profile(gs, prof, x0, fs, sub, feedforward):
    """simulate_profile's right-hand side as it was written on arrays, from states x0."""
    bk = dy.ke_batch(dy.Batch.of(gs))
    n, h = int(round(prof.speed.duration_s * fs)), 1.0 / (fs * sub)
    th = np.arange(2 * (n - 1) * sub + 1) * (h / 2)
    wd_h, ad_h = pf.speed_at(prof, th)
    ad_l = pf.speed_at(prof, th, side="left")[1]
    steps = isinstance(prof.load, pf.LoadSteps)
    tl_h = pf.load_at(prof.load, th) if steps else None
    tl_l = pf.load_at(prof.load, th, side="left") if steps else None
    g_max = 0.0 if steps else prof.load.max_torque_nm
    ff = (bk.j_in_kgm2 + bk.j_out_kgm2 / bk.ratio**2) / bk.j_in_kgm2 if feedforward else None
    inv_j_out = 1.0 / bk.j_out_kgm2

    def f(j, x, last=False):
        d = dy.rhs(0.0, x, bk, wd_h[j], 0.0)
        if ff is not None:
            d[1] += ff * (ad_l[j] if last else ad_h[j])
        if steps:
            d[3] += (tl_l[j] if last else tl_h[j]) * inv_j_out
        else:
            d[3] += g_max * np.cos(prof.load.q0_rad - x[2]) * inv_j_out
        return d
    return it.rk4_record(f, x0, 0, n, sub, h)


@pytest.mark.parametrize("load, feedforward", [
    (pf.LoadSteps(7.0, ((0.05, 39.0),)), True),
    (pf.GravityLink(), False)])
def test_profile_matches_the_array_form(load, feedforward):
    """Along a profile through standstill and reversal with load steps and feed-forward, or
    a link under gravity: simulate_profile equals RK4 on the array form."""
    sp = pf.SpeedProfile(0.0, (pf.Move(500.0, 1e4), pf.Hold(0.03), pf.Move(-300.0, 1e4),
                               pf.Hold(0.02)))
    prof, gs = pf.Profile(sp, load), _variants()
    res = pd.simulate_profile(gs, prof, [0.3, 1.0], 5e3, substeps=2, feedforward=feedforward)
    ref = _reference_profile(gs, prof, res.states[:, :, 0], 5e3, 2, feedforward)
    _close(res.states, ref)


def test_a_short_stage_input_is_refused():
    """A per-stage input shorter than the steps need is refused before integrating."""
    gs = _variants()
    bk = dy.ke_batch(dy.Batch.of(gs))
    x0 = dy.steady_state(bk, np.full(2, 100.0), np.zeros(2), np.zeros(2))
    inputs = it.StageInputs(w_d=np.zeros(2), t_opposing=np.zeros(2), w_d_stage=np.ones(5))
    with pytest.raises(ValueError, match="5 stages, 9 needed"):
        it.integrate(bk, x0, inputs, 0, 3, 2, 1e-4)
