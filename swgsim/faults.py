"""The paper's five faults (Table I) as parameter transforms with severity and position.

Faults map parameters to parameters, never signals to signals (STYLE.md). Severity 0
reproduces the healthy gear exactly. Each fault states its severity range, the model it
manipulates (paper Table I) and its expected signature (paper Sec. II-C, Fig. 6).

================== =============== ======================= ============================
fault              model           severity s              transform
================== =============== ======================= ============================
reduced_damping    I/O dynamics    [0, 0.9]                b1 ← (1 − s) b1
reduced_stiffness  I/O dynamics    [0, 0.9]                k1 ← (1 − s) k1
eccentric_wg       flexspline      [0, 0.5] of w0          u_ecc = [s w0, θ, 0]
root_tooth_crack   flexspline      [0, 0.99]               k_bar ← (1 − s) k_bar at θ
tip_tooth_crack    flexspline      [0, 1]                  F_tooth ← (1 − s) F_tooth at θ
================== =============== ======================= ============================
"""

from __future__ import annotations

import dataclasses
from collections.abc import Callable
from dataclasses import dataclass

import numpy as np

from .dynamics import GearParams


@dataclass(frozen=True)
class ChainParams:
    """All parameters of one simulated gear variant.

    Attributes
    ----------
    gear : GearParams
        Dynamic I/O model parameters.
    w0_m : float
        Radial WG deflection at the major axis [m] (≈ module, 0.254 mm for size 20 with
        z_f = 200, PHYSICS.md sec. 2).
    ecc_m, ecc_theta_rad : float
        WG eccentricity [m] and its direction in the flexspline frame [rad].
    root_crack_index : int
        Angle index of a root tooth crack (−1: none).
    root_crack_severity : float
        Fraction of the crack bars' stiffness lost [-].
    tip_crack_index : int
        Angle index of a tip tooth crack (−1: none).
    tip_crack_severity : float
        Fraction of the tooth force lost at that angle [-].
    """

    gear: GearParams
    w0_m: float = 0.254e-3
    ecc_m: float = 0.0
    ecc_theta_rad: float = 0.0
    root_crack_index: int = -1
    root_crack_severity: float = 0.0
    tip_crack_index: int = -1
    tip_crack_severity: float = 0.0


@dataclass(frozen=True)
class Fault:
    """A registered fault.

    Attributes
    ----------
    name : str
    model : str
        "I/O dynamics" or "flexspline" (paper Table I).
    severity_range : tuple of float
        Allowed closed range of severity.
    uses_position : bool
        Whether the fault has a circumferential position.
    apply : callable
        ``apply(params, severity, position_deg, n_theta) -> ChainParams``.
    signature : str
        Expected signature in the signals (paper Sec. II-C).
    """

    name: str
    model: str
    severity_range: tuple[float, float]
    uses_position: bool
    apply: Callable[[ChainParams, float, float, int], ChainParams]
    signature: str


def _angle_index(position_deg: float, n_theta: int) -> int:
    return int(round(np.mod(position_deg, 360.0) / 360.0 * n_theta)) % n_theta


def _damping(p, s, pos, n):
    g = dataclasses.replace(p.gear, b1_nms=p.gear.b1_nms * (1.0 - s))
    return dataclasses.replace(p, gear=g)


def _stiffness(p, s, pos, n):
    g = dataclasses.replace(p.gear, k1_nm_per_rad=p.gear.k1_nm_per_rad * (1.0 - s))
    return dataclasses.replace(p, gear=g)


def _eccentric(p, s, pos, n):
    if s == 0.0:
        return p
    return dataclasses.replace(p, ecc_m=s * p.w0_m, ecc_theta_rad=float(np.deg2rad(pos)))


def _root(p, s, pos, n):
    if s == 0.0:
        return p
    return dataclasses.replace(p, root_crack_index=_angle_index(pos, n), root_crack_severity=s)


def _tip(p, s, pos, n):
    if s == 0.0:
        return p
    return dataclasses.replace(p, tip_crack_index=_angle_index(pos, n), tip_crack_severity=s)


def _healthy(p, s, pos, n):
    return p


FAULTS: dict[str, Fault] = {
    f.name: f
    for f in (
        Fault("healthy", "-", (0.0, 0.0), False, _healthy, "reference signals"),
        Fault("reduced_damping", "I/O dynamics", (0.0, 0.9), False, _damping,
              "hardly visible in the signals; efficiency rises (Fig. 6a, Table II)"),
        Fault("reduced_stiffness", "I/O dynamics", (0.0, 0.9), False, _stiffness,
              "torque ripple changes slightly, mostly in s0 (Fig. 6b)"),
        Fault("eccentric_wg", "flexspline", (0.0, 0.5), True, _eccentric,
              "offsets of the WG-bending pair and a changed, order-1 modulated shape (Fig. 6c)"),
        Fault("root_tooth_crack", "flexspline", (0.0, 0.99), True, _root,
              "amplitudes change in all signals (Fig. 6d)"),
        Fault("tip_tooth_crack", "flexspline", (0.0, 1.0), True, _tip,
              "short deviations when a mesh zone passes the crack (Fig. 6e)"),
    )
}


def get_fault(name: str) -> Fault:
    """The registered fault of that name.

    Raises
    ------
    ValueError
        Naming the allowed faults if ``name`` is unknown.
    """
    try:
        return FAULTS[name]
    except KeyError:
        raise ValueError(f"unknown fault {name!r}; allowed: {sorted(FAULTS)}") from None


def apply_fault(params: ChainParams, name: str, severity: float, position_deg: float = 0.0,
                n_theta: int = 120) -> ChainParams:
    """Apply a registered fault to healthy parameters.

    Parameters
    ----------
    params : ChainParams
        Healthy gear.
    name : str
        A key of :data:`FAULTS`.
    severity : float
        Within the fault's ``severity_range`` (0 reproduces ``params`` exactly).
    position_deg : float
        Circumferential position in the flexspline frame [deg] (faults with a position).
    n_theta : int
        Truss nodes around the circumference (positions snap to nodes).

    Raises
    ------
    ValueError
        Unknown fault, or severity outside its range.
    """
    f = get_fault(name)
    lo, hi = f.severity_range
    if not (lo <= severity <= hi) or not np.isfinite(severity):
        raise ValueError(f"severity of {name} must lie in [{lo}, {hi}], got {severity}")
    return f.apply(params, float(severity), float(position_deg), n_theta)
