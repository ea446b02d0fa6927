"""Simulated "measured" friction data with planted effects, for tests and examples.

The trajectory resembles the real Franka recordings (``/work/shared/data/joint_friction``):
a sum of three sines in q (span about 2 rad, ``|q̇|`` up to about 0.65 rad/s, about 20
reversals a minute) on a warped time axis with a slow passage every 9.3 s (low-speed
coverage, as in point-to-point motion), irregular sampling (10 ms ± 20 %). The torque is
the paper law plus the planted library effects plus optional hidden (out-of-library)
terms plus mildly coloured Gaussian noise: AR(1) with coefficient ``noise_rho`` and
marginal standard deviation ``noise_rel`` times the range of the clean torque.
"""

from __future__ import annotations

from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np

from swgsim.gear.friction.signals import FrictionSignals, PaperLaw, Scales
from swgsim.gear.friction.simulation import parse_effects
from swgsim.gear.terms import evaluate_terms

from .data import FrictionRecording

__all__ = ["BASE_MODEL_TRUTH", "PLANTED", "SyntheticTruth", "synthetic_trajectory",
           "synthetic_recording", "session_recording"]

BASE_MODEL_TRUTH = {"b0": 0.30, "b1": 0.40, "b2": 0.50, "b3": 0.05, "theta_b": 0.3}
"""Paper-law parameters of the synthetic joint [N m, N m s/rad, N m s³/rad³, N m, rad]."""

V_SMOOTH = 0.004
"""Smooth-sign velocity of the synthetic data [rad/s] (about 1 % of max |q̇|)."""

PLANTED: dict[str, dict[str, Any]] = {
    "asymmetric_coulomb": {"params": {"delta_c": 0.15}, "check": {"delta_c": 0.15}},
    "stribeck": {"params": {"f_s": 0.12, "v_st": 0.03},
                 "check": {"f_s": 0.12, "v_st": 0.03}},
    "presliding": {"params": {"f_d": 0.15, "q_c": 0.004},
                   "check": {"f_d": 0.15, "q_c": 0.004}},
    "position_ripple": {"params": {"a_sin": 0.03, "a_cos": 0.02, "period": 0.045},
                        "check": {"amplitude": float(np.hypot(0.03, 0.02)), "period": 0.045}},
    "friction_ripple": {"params": {"a_sin": 0.02, "a_cos": -0.025, "period": 0.07},
                        "check": {"amplitude": float(np.hypot(0.02, 0.025)), "period": 0.07}},
    "load_coulomb": {"params": {"c1": 0.1, "c2": -0.06},
                     "check": {"rms": float(np.sqrt(0.1 ** 2 / 3 + 0.06 ** 2 / 5))}},
    "gravity_residual": {"params": {"c2": 0.12, "c3": -0.08},
                         "check": {"rms": float(np.sqrt(0.12 ** 2 / 5 + 0.08 ** 2 / 7))}},
    "inertia": {"params": {"j_a": 0.1}, "check": {"j_a": 0.1}},
    # drifts with physical time constants (minutes, :mod:`swgcal.friction.ranges`) need a
    # recording of a few time constants to be told from a straight line: 240 s at 40 ms
    "thermal_drift": {"params": {"d": 0.2, "t_th": 120.0}, "check": {"d": 0.2, "t_th": 120.0},
                      "recording": {"duration_s": 240.0, "dt_s": 0.04}},
    "sensor_drift": {"params": {"c": 0.2, "t_d": 90.0}, "check": {"c": 0.2, "t_d": 90.0},
                     "recording": {"duration_s": 240.0, "dt_s": 0.04}},
    "velocity_lag": {"params": {"t_lag": 0.04}, "check": {"t_lag": 0.04}},
    # a delay shows only through what it acts on: planted with a ripple at 2 ms sampling
    "transport_delay": {"params": {"delay": 0.003}, "check": {"delay": 0.003},
                        "sessions": {"temperatures_c": [30.0], "friction_factors": [1.0],
                                     "duration_s": 40.0, "with_temperature": False},
                        "with": [{"kind": "position_ripple",
                                  "params": {"a_sin": 0.03, "a_cos": 0.02, "period": 0.01}}]},
    # a temperature needs a temperature column: a cold and a warm session, the warm one's
    # paper-law friction 12 % lower (b0, b1, b2 scaled by 0.88 over 11.2 K; checked as the
    # change at the reference speed, k_ref, in tests/swgcal/test_calib_sessions.py)
    # a variable nobody declared: a column of the file the friction follows (planted in
    # tests/swgcal/test_calib_sessions.py: friction 0.05 N m per unit of a slow variable)
    "measured_variable": {"params": {"c_even": 0.0, "c_odd": 0.05}, "check": {"c_odd": 0.05},
                          "sessions": {"temperatures_c": [30.0], "friction_factors": [1.0],
                                       "with_temperature": False}},
    "temperature_friction": {"params": {}, "check": {},
                             "sessions": {"temperatures_c": [27.5, 38.7],
                                          "friction_factors": [1.0, 0.88]}},
}
"""Planted value of every library effect (inside its physical range, :mod:`swgcal.friction.ranges`),
the derived parameters a test checks and, where the default recording is too short to
identify the effect, the ``recording`` options (``duration_s``, ``dt_s``) to plant it in;
an effect that needs sessions (a temperature) or another effect to act on (a delay) is
planted by :func:`session_recording` with the ``sessions`` options, beside the effects
``with``."""


@dataclass(frozen=True)
class SyntheticTruth:
    """What was planted.

    Attributes
    ----------
    sigma : float
        Marginal noise standard deviation [N m].
    tau_clean : ndarray, shape (n,)
        Torque without noise [N m].
    effects : list of dict
        Planted effect list (``{kind, params}``).
    v_s : float
        Smooth-sign velocity [rad/s].
    """

    sigma: float
    tau_clean: np.ndarray
    effects: list[dict[str, Any]]
    v_s: float


def synthetic_trajectory(duration_s: float = 60.0, dt_s: float = 0.01, jitter: float = 0.2,
                         rng: np.random.Generator | None = None
                         ) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """Multi-sine joint trajectory on irregular samples.

    Parameters
    ----------
    duration_s, dt_s : float, default 60 and 0.01
        Duration and mean sample interval [s].
    jitter : float, default 0.2
        Relative uniform jitter of the sample interval, in [0, 0.9].
    rng : numpy.random.Generator, optional
        Phases and sample times; default ``np.random.default_rng(0)``.

    Returns
    -------
    t, q, dq, ddq : ndarray, shape (n,)
        [s, rad, rad/s, rad/s²]
    """
    if not 0 <= jitter <= 0.9:
        raise ValueError(f"jitter must be in [0, 0.9], got {jitter}")
    rng = rng if rng is not None else np.random.default_rng(0)
    n = int(duration_s / dt_s)
    dt = dt_s * (1 + jitter * rng.uniform(-1, 1, n))
    t = np.concatenate([[0.0], np.cumsum(dt[:-1])])
    # time warp s(t) with speed factor w = 0.1 + 0.9 ((1 - cos th) / 2)^2, th = 2 pi t / T_w:
    # slow passages every T_w seconds (low-speed coverage, as in point-to-point motion)
    t_w = 9.3
    th = 2 * np.pi * t / t_w
    w = 0.1 + 0.9 * ((1 - np.cos(th)) / 2) ** 2
    dw = 0.9 * (1 - np.cos(th)) / 2 * np.sin(th) * 2 * np.pi / t_w
    s = 0.1 * t + 0.9 * (3 * t / 8 - t_w / (4 * np.pi) * np.sin(th)
                         + t_w / (32 * np.pi) * np.sin(2 * th))
    amp = np.array([0.80, 0.20, 0.06])
    f = np.array([0.11, 0.29, 0.67])
    ph = rng.uniform(0, 2 * np.pi, 3)
    om = 2 * np.pi * f
    arg = om[:, None] * s[None, :] + ph[:, None]  # (3, n)
    q = (amp[:, None] * np.sin(arg)).sum(0)
    q_s = (amp[:, None] * om[:, None] * np.cos(arg)).sum(0)  # dq/ds
    q_ss = -(amp[:, None] * om[:, None] ** 2 * np.sin(arg)).sum(0)
    dq = q_s * w
    ddq = q_ss * w * w + q_s * dw
    return t, q, dq, ddq


def synthetic_recording(
    effects: Sequence[Mapping[str, Any]] = (),
    *,
    base_model: Mapping[str, float] | None = None,
    v_s: float = V_SMOOTH,
    noise_rel: float = 0.01,
    noise_rho: float = 0.3,
    hidden: Callable[[np.ndarray, np.ndarray, np.ndarray], np.ndarray] | None = None,
    duration_s: float = 60.0,
    dt_s: float = 0.01,
    rng: np.random.Generator | None = None,
    name: str = "synthetic",
) -> tuple[FrictionRecording, SyntheticTruth]:
    """Simulated friction recording: paper law + planted effects + hidden terms + noise.

    Parameters
    ----------
    effects : sequence of mapping
        Library effects ``{kind, params}`` (see :data:`PLANTED`); ``load_coulomb`` and
        ``gravity_residual`` get the trajectory's range of q unless ``options`` say.
    base model : mapping, optional
        Paper-law parameters; default :data:`BASE_MODEL_TRUTH`.
    v_s : float
        Smooth-sign velocity [rad/s].
    noise_rel : float, default 0.01
        Noise standard deviation relative to the range of the clean torque.
    noise_rho : float, default 0.3
        AR(1) coefficient of the noise, in [0, 1).
    hidden : callable (t, q, dq) -> tau, optional
        An out-of-library term [N m].
    duration_s, dt_s : float
        See :func:`synthetic_trajectory`.
    """
    if not 0 <= noise_rho < 1:
        raise ValueError(f"noise_rho must be in [0, 1), got {noise_rho}")
    rng = rng if rng is not None else np.random.default_rng(0)
    t, q, dq, ddq = synthetic_trajectory(duration_s, dt_s, rng=rng)
    base = dict(BASE_MODEL_TRUTH if base_model is None else base_model)
    effects = [dict(e) for e in effects]
    for e in effects:  # range-polynomial effects live on the trajectory's range of q
        if e.get("kind") in ("load_coulomb", "gravity_residual") and "options" not in e:
            e["options"] = {"q_center": float(0.5 * (q.max() + q.min())),
                            "q_half": float(0.5 * np.ptp(q))}
    items = parse_effects(effects)
    sc = Scales(v_ref=1.0, q_span=float(np.ptp(q)), t0=float(t[0]), t_span=float(t[-1] - t[0]),
                dt_med=float(np.median(np.diff(t))), dq_med=1.0)
    sig = FrictionSignals(t_s=t, q_rad=q, dq_rad_s=dq, ddq_rad_s2=ddq, load_nm=None, v_eff=dq,
                          v_s=v_s, scales=sc)
    law = PaperLaw()
    terms = [x[0] for x in items if x[0].is_transform] + [law] + [
        x[0] for x in items if not x[0].is_transform]
    by = {id(x[0]): x for x in items}
    coefs = [law.from_derived(**base) if tm is law else by[id(tm)][1] for tm in terms]
    thetas = [np.empty(0) if tm is law else by[id(tm)][2] for tm in terms]
    tau = evaluate_terms(terms, sig, coefs, thetas)
    if hidden is not None:
        tau = tau + np.asarray(hidden(t, q, dq), float)
    sigma = noise_rel * float(np.ptp(tau))
    w = rng.standard_normal(t.size)
    e = np.empty_like(w)
    e[0] = w[0]
    for k in range(1, w.size):  # AR(1), marginal variance 1
        e[k] = noise_rho * e[k - 1] + np.sqrt(1 - noise_rho ** 2) * w[k]
    rec = FrictionRecording(t_s=t, q_rad=q, dq_rad_s=dq, ddq_rad_s2=ddq, tau_nm=tau + sigma * e,
                            name=name, ddq_source="exact (synthetic)")
    spec = [{"kind": x[0].kind, "params": x[0].to_params(x[1], x[2]),
             **({"options": x[0].options()} if x[0].options() else {})} for x in items]
    return rec, SyntheticTruth(sigma=sigma, tau_clean=tau, effects=spec, v_s=v_s)


def session_recording(
    effects: Sequence[Mapping[str, Any]] = (),
    *,
    temperatures_c: Sequence[float] = (27.5, 38.7),
    friction_factors: Sequence[float] = (1.0, 1.0),
    duration_s: float = 20.0,
    dt_s: float = 0.002,
    gap_s: float = 600.0,
    noise_rel: float = 0.01,
    with_temperature: bool = True,
    rng: np.random.Generator | None = None,
    name: str = "sessions",
) -> tuple[FrictionRecording, list[SyntheticTruth]]:
    """Sessions of one joint joined in one recording, each at its own temperature.

    Each session is a :func:`synthetic_recording` (its own trajectory, the same planted
    ``effects``) whose paper-law Coulomb and viscous coefficients b0, b1, b2 are scaled
    by its friction factor (a warm joint's thinner grease), started ``gap_s`` after the
    previous one ended. With ``with_temperature`` the recording carries each session's
    temperature as a ``temperature_c`` column (constant within a session).

    Parameters
    ----------
    effects : sequence of mapping
        Library effects ``{kind, params}`` planted in every session.
    temperatures_c, friction_factors : sequence of float
        One per session [°C, -].
    duration_s, dt_s : float
        Each session's length and mean sample interval [s].
    gap_s : float
        Time between sessions [s], >= 0.
    noise_rel : float
        As in :func:`synthetic_recording`.

    Returns
    -------
    FrictionRecording, list of SyntheticTruth
        The joined recording and each session's truth.

    Raises
    ------
    ValueError
        Sessions of unequal counts, a factor not positive or a negative gap.
    """
    if len(temperatures_c) != len(friction_factors) or not len(temperatures_c):
        raise ValueError("temperatures_c and friction_factors need one entry per session")
    if min(friction_factors) <= 0 or gap_s < 0:
        raise ValueError(f"friction_factors must be > 0 and gap_s >= 0, got "
                         f"{list(friction_factors)}, {gap_s}")
    rng = rng if rng is not None else np.random.default_rng(0)
    parts, truths, t_end = [], [], 0.0
    for temp, f in zip(temperatures_c, friction_factors, strict=True):
        base = {k: v * f if k in ("b0", "b1", "b2") else v for k, v in BASE_MODEL_TRUTH.items()}
        rec, truth = synthetic_recording(effects, base_model=base, noise_rel=noise_rel,
                                         duration_s=duration_s, dt_s=dt_s, rng=rng)
        t0 = t_end + (gap_s if parts else 0.0)
        parts.append((rec.t_s + t0, rec, np.full(rec.n, float(temp))))
        truths.append(truth)
        t_end = float(parts[-1][0][-1])
    cat = np.concatenate
    return FrictionRecording(
        t_s=cat([p[0] for p in parts]), q_rad=cat([p[1].q_rad for p in parts]),
        dq_rad_s=cat([p[1].dq_rad_s for p in parts]),
        ddq_rad_s2=cat([p[1].ddq_rad_s2 for p in parts]),
        tau_nm=cat([p[1].tau_nm for p in parts]),
        temperature_c=cat([p[2] for p in parts]) if with_temperature else None,
        name=name, ddq_source="exact (synthetic)"), truths
