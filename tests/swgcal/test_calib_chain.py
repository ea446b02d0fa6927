"""Accepted effects as a simulation option: swgsim.gear.friction.FrictionEffects."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
import yaml

from swgcal.friction.report import NOT_SIMULATED
from swgcal.friction.synthetic import (
    BASE_MODEL_TRUTH,
    PLANTED,
    V_SMOOTH,
    synthetic_recording,
    synthetic_trajectory,
)
from swgsim.gear.friction import FRICTION_LIBRARY, FrictionEffects, parse_effects


def test_a_temperature_effect_is_refused_by_the_simulation_in_one_line():
    with pytest.raises(ValueError, match="temperature_friction needs a measured variable"):
        FrictionEffects([{"kind": "temperature_friction", "params": {"k_c": -0.01, "k_v": 0.0},
                          "options": {"t_ref_c": 30.0}}], v_s=V_SMOOTH)


CONF = Path(__file__).resolve().parents[2] / "conf" / "friction_effects"


@pytest.mark.parametrize("kind", sorted(k for k in FRICTION_LIBRARY
                                         if k not in NOT_SIMULATED))
def test_effect_torque_reproduces_planted_data(kind):
    spec = [{"kind": kind, "params": PLANTED[kind]["params"]}]
    rec, truth = synthetic_recording(spec, rng=np.random.default_rng(0), duration_s=10)
    _, base = synthetic_recording([], rng=np.random.default_rng(0), duration_s=10)
    fx = FrictionEffects(truth.effects, v_s=V_SMOOTH, base_model=BASE_MODEL_TRUTH, t0=0.0)
    extra = fx(rec.t_s, rec.q_rad, rec.dq_rad_s, rec.ddq_rad_s2)
    # same seed, same trajectory: the extra torque is the difference of the clean torques
    np.testing.assert_allclose(base.tau_clean + extra, truth.tau_clean, atol=1e-9)


def test_pointwise_torque_with_integrated_states_matches_trajectory():
    spec = [{"kind": "presliding", "params": {"f_d": 0.15, "q_c": 0.004}},
            {"kind": "velocity_lag", "params": {"t_lag": 0.04}},
            {"kind": "stribeck", "params": {"f_s": 0.1, "v_st": 0.03}}]
    fx = FrictionEffects(spec, v_s=V_SMOOTH, base_model=BASE_MODEL_TRUTH)
    assert fx.n_states == 2
    t, q, dq, ddq = synthetic_trajectory(duration_s=10, dt_s=0.001, jitter=0.0)
    ref = fx(t, q, dq, ddq)
    z = fx.initial_state(dq0=dq[0])
    out = np.empty_like(t)
    for k in range(t.size):  # explicit Euler of the state ODEs, 1 ms steps
        out[k] = fx.torque(t[k], q[k], dq[k], ddq[k], z)
        if k + 1 < t.size:
            z = z + (t[k + 1] - t[k]) * fx.state_derivative(t[k], q[k], dq[k], z)
    err = out - ref
    assert np.sqrt(np.mean(err ** 2)) < 0.03 * np.sqrt(np.mean(ref ** 2))
    # vectorised over variants: shape preserved
    z2 = fx.initial_state(shape=(3,))
    assert fx.torque(0.0, np.zeros(3), np.full(3, 0.1), np.zeros(3), z2).shape == (3,)


def test_spec_errors_are_clear():
    with pytest.raises(KeyError, match="library has"):
        parse_effects([{"kind": "magic", "params": {}}])
    with pytest.raises(KeyError, match="missing"):
        parse_effects([{"kind": "stribeck", "params": {"f_s": 1.0}}])
    with pytest.raises(ValueError, match="must be > 0"):
        parse_effects([{"kind": "stribeck", "params": {"f_s": 1.0, "v_st": -1.0}}])
    with pytest.raises(KeyError, match="needs options"):
        parse_effects([{"kind": "gravity_residual", "params": {"c2": 0.1, "c3": 0.0}}])
    with pytest.raises(ValueError, match="base_model"):
        FrictionEffects([{"kind": "velocity_lag", "params": {"t_lag": 0.1}}], v_s=0.01)


def test_config_group_options_instantiate():
    files = sorted(CONF.glob("*.yaml"))
    assert files
    for f in files:
        c = yaml.safe_load(f.read_text())
        fx = FrictionEffects(c["effects"], v_s=c["v_s"], base_model=c["base_model"], t0=c["t0_s"])
        t, q, dq, ddq = synthetic_trajectory(duration_s=1)
        assert np.all(np.isfinite(fx(t, q, dq, ddq)))
