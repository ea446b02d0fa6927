"""What joint-friction terms see, and the paper's friction law on the joint.

:class:`FrictionSignals` is the input of every friction term (:mod:`.effects`,
:mod:`.ripples`): the trajectory (t, q, q̇, q̈ and optionally the load torque) in the joint
coordinate q (the gear output angle), the velocity the friction law acts on, the
smooth-sign velocity and the data scales that set the bounds of nonlinear parameters.

The base model is the paper's friction law, eq. (5), mapped to the joint coordinate q (the
flank sliding velocity φ̇_b = −φ̇_out / sin α_tooth of eq. (6) is proportional to q̇, so
its constant factors fold into the coefficients):

    τ = b0 sgn(q̇) + b1 q̇ + b2 q̇³ + b3 sin(q + θ_b)

with the smooth sign sgn(q̇) = tanh(q̇ / v_s). b3 sin(q + θ_b) is fitted linearly as
A sin q + B cos q (b3 = hypot(A, B), θ_b = atan2(B, A)). The μ F_n term needs a load
signal; the recordings have none, so it lives in the effect library (``load_coulomb``).
"""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from swgsim.gear.terms import Param, Term

__all__ = ["FrictionSignals", "PaperLaw", "Scales"]


@dataclass(frozen=True)
class Scales:
    """Data scales that set the bounds of nonlinear parameters.

    Attributes
    ----------
    v_ref : float
        99th percentile of ``|q̇|`` [rad/s].
    q_span : float
        max q − min q [rad].
    t0, t_span : float
        Start time and duration [s].
    dt_med : float
        Median sample interval [s].
    dq_med : float
        Median ``|Δq|`` per sample while moving [rad].
    q_center : float
        (max q + min q) / 2 [rad].
    """

    v_ref: float
    q_span: float
    t0: float
    t_span: float
    dt_med: float
    dq_med: float
    q_center: float = 0.0

    @classmethod
    def of(cls, t_s: np.ndarray, q_rad: np.ndarray, dq_rad_s: np.ndarray) -> Scales:
        """Scales of a trajectory: time [s], joint angle [rad], velocity [rad/s], each
        of shape (n,), n ≥ 2."""
        v = np.abs(dq_rad_s)
        v_ref = float(np.percentile(v, 99))
        dq = np.abs(np.diff(q_rad))
        moving = v[1:] > 0.05 * v_ref
        return cls(v_ref=v_ref, q_span=float(np.ptp(q_rad)) or 1e-9, t0=float(t_s[0]),
                   t_span=float(t_s[-1] - t_s[0]),
                   dt_med=float(np.median(np.diff(t_s))),
                   dq_med=float(np.median(dq[moving])) if moving.any() else float(
                       np.median(dq) or 1e-9),
                   q_center=float(0.5 * (np.max(q_rad) + np.min(q_rad))))


@dataclass(frozen=True)
class FrictionSignals:
    """What friction terms see. ``v_eff`` is the velocity the friction law acts on
    (``dq_rad_s`` unless a transform term such as ``velocity_lag`` changed it).

    Attributes
    ----------
    t_s, q_rad, dq_rad_s, ddq_rad_s2, load_nm : ndarray, shape (n,)
        Time, joint angle (gear output angle), velocity, acceleration, transmitted load
        torque (None without a load signal) [s, rad, rad/s, rad/s², N m].
    v_eff : ndarray, shape (n,)
        Velocity seen by the friction law [rad/s].
    v_s : float
        Smooth-sign velocity [rad/s].
    scales : Scales
    extra : dict
        Integrator states of one time step (``{"states": {term name: state}}``).
    gear_ratio : float or None
        Reduction ratio N (wave-generator turns per output turn) when known [-].
    temperature_c : ndarray, shape (n,), or None
        The joint's measured temperature where the recording has one [°C]
        (``temperature_friction``); None otherwise (the simulation's friction effects).
    measured : dict of str to ndarray, shape (n,)
        Other measured variables of a recording, by column (``measured_variable``).
    """

    t_s: np.ndarray
    q_rad: np.ndarray
    dq_rad_s: np.ndarray
    ddq_rad_s2: np.ndarray
    load_nm: np.ndarray | None
    v_eff: np.ndarray
    v_s: float
    scales: Scales
    extra: dict[str, Any] = field(default_factory=dict)
    gear_ratio: float | None = None
    temperature_c: np.ndarray | None = None
    measured: dict[str, np.ndarray] = field(default_factory=dict)

    @property
    def n(self) -> int:
        return int(self.t_s.shape[0])

    @property
    def sgn(self) -> np.ndarray:
        """Smooth sign tanh(v_eff / v_s), shape (n,)."""
        return np.tanh(self.v_eff / self.v_s)

    def replace(self, **changes: Any) -> FrictionSignals:
        return dataclasses.replace(self, **changes)


class PaperLaw(Term):
    """Paper eq. (5) on the joint: b0 sgn(q̇) + b1 q̇ + b2 q̇³ + b3 sin(q + θ_b)."""

    kind = "paper_law"
    linear = (
        Param("b0", "N m", "Coulomb level (smooth sign tanh(q̇/v_s))"),
        Param("b1", "N m s/rad", "viscous coefficient"),
        Param("b2", "N m s³/rad³", "cubic viscous coefficient"),
        Param("b3_sin", "N m", "b3 cos θ_b (coefficient of sin q)"),
        Param("b3_cos", "N m", "b3 sin θ_b (coefficient of cos q)"),
    )
    description = "paper eq. (5)-(6) mapped to the joint coordinate, smooth Coulomb sign"
    source = "paper eq. (5)-(6); Tuttle & Seering 1996"

    def columns(self, sig: FrictionSignals, theta: np.ndarray) -> np.ndarray:
        v = sig.v_eff
        q = sig.q_rad
        return np.column_stack([sig.sgn, v, v ** 3, np.sin(q), np.cos(q)])

    def derived(self, coef: np.ndarray, theta: np.ndarray) -> dict[str, float]:
        b0, b1, b2, a, b = (float(x) for x in coef)
        return {"b0": b0, "b1": b1, "b2": b2, "b3": float(np.hypot(a, b)),
                "theta_b": float(np.arctan2(b, a))}

    def derived_units(self) -> dict[str, str]:
        return {"b0": "N m", "b1": "N m s/rad", "b2": "N m s³/rad³", "b3": "N m",
                "theta_b": "rad"}

    def from_derived(self, b0: float, b1: float, b2: float, b3: float,
                     theta_b: float) -> np.ndarray:
        """Raw coefficients from (b0, b1, b2, b3, θ_b)."""
        return np.array([b0, b1, b2, b3 * np.cos(theta_b), b3 * np.sin(theta_b)])
