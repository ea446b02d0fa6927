"""Ripples over the joint angle: a fundamental period and its harmonics.

A ripple of a strain wave gear is periodic in the wave-generator angle: kinematic error
and meshing-stiffness ripple at orders 1, 2, 4 of the wave generator, the sensing ripple
at order 2 (1 + 1/N), motor cogging at higher orders (Tuttle & Seering 1996, IEEE T-RA
12(3); docs/PHYSICS.md sec. 1, 4, 5). Over the output angle q a ripple of order k has
the period 2π / (k N), N the reduction ratio; when N is known the period is reported as
the order k = 2π / (period · N). Harmonics of one fundamental belong to one effect:
:class:`RippleTerm` carries one fundamental period and a set of harmonic numbers h, each
with its own amplitude and phase, τ = Σ_h b(v) (a_h sin(2π h q / P) + c_h cos(2π h q /
P)), b = 1 (``position_ripple``) or sgn(v) (``friction_ripple``).
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from typing import Any

import numpy as np

from swgsim.gear.friction.signals import FrictionSignals
from swgsim.gear.terms import Param, Term

__all__ = ["RippleTerm", "PositionRipple", "FrictionRipple", "wave_generator_order",
           "period_in_gear_terms"]


def wave_generator_order(period_rad: float, gear_ratio: float) -> float:
    """Order of a ripple over the output angle as a multiple of the wave-generator turn.

    k = 2π / (period · N): a ripple k times per wave-generator revolution repeats N k
    times per output revolution (circular spline fixed, flexspline output).

    Parameters
    ----------
    period_rad : float
        Period over the output angle [rad], > 0.
    gear_ratio : float
        Reduction ratio N [-], > 0.

    Returns
    -------
    float
        Order k [-].

    Raises
    ------
    ValueError
        A non-positive period or ratio.
    """
    if not (period_rad > 0 and gear_ratio > 0):
        raise ValueError(f"period_rad and gear_ratio must be > 0, got {period_rad}, "
                         f"{gear_ratio}")
    return 2.0 * math.pi / (float(period_rad) * float(gear_ratio))


def period_in_gear_terms(period: float, std: float, gear_ratio: float | None,
                         rel_tol: float = 0.01) -> dict[str, Any]:
    """A ripple's period over the output angle in the gear's terms, with standard errors.

    The output order is the number of ripple cycles per output revolution, 2π / P. With
    the reduction ratio N the wave-generator order is k = 2π / (P N) (the motor turns with
    the wave generator: k is also the order per motor revolution, where a motor with p
    pole pairs ripples at 2p and 6p, cogging at the least common multiple of slots and
    poles); the flexspline has 2N teeth (circular spline fixed, two teeth more on the
    circular spline), so the tooth mesh is order 2N per wave-generator turn
    (docs/PHYSICS.md sec. 1; Tuttle & Seering 1996).

    Parameters
    ----------
    period, std : float
        Period [rad] (> 0) and its standard error [rad] (NaN where unknown).
    gear_ratio : float or None
        N [-], > 1, when known.
    rel_tol : float, default 0.01
        Relative tolerance of an integer order (widened to 3 standard errors).

    Returns
    -------
    dict
        ``period``, ``period_std`` [rad], ``rel_std`` [-], ``output_order`` and
        ``output_order_std`` [cycles per output revolution]; with N also ``wg_order``,
        ``wg_order_std``, ``nearest_integer_wg_order`` and ``integer_within_3_std``
        (the nearest integer lies within 3 standard errors or ``rel_tol``),
        ``reading`` (what an integer order of a strain wave gear is).

    Raises
    ------
    ValueError
        A non-positive period.
    """
    if not period > 0:
        raise ValueError(f"period must be > 0, got {period}")
    rel = float(std) / float(period) if np.isfinite(std) else float("nan")
    out_order = 2.0 * math.pi / float(period)
    out: dict[str, Any] = {"period": float(period), "period_std": float(std), "rel_std": rel,
                           "output_order": out_order, "output_order_std": out_order * rel}
    if gear_ratio:
        k = wave_generator_order(period, gear_ratio)
        ki = int(round(k))
        tol = max(rel_tol, 3.0 * rel) if np.isfinite(rel) else rel_tol
        near = ki >= 1 and abs(k / ki - 1.0) <= tol
        out.update({"wg_order": k, "wg_order_std": k * rel, "nearest_integer_wg_order": ki,
                    "integer_within_3_std": bool(near),
                    "reading": _order_reading(k, ki, near, float(gear_ratio), tol)})
    return out


def _order_reading(k: float, ki: int, near: bool, n: float, tol: float) -> str:
    """What a wave-generator order is in a strain wave gear (docs/PHYSICS.md sec. 1)."""
    sensing = 2.0 * (1.0 + 1.0 / n)
    if abs(k / sensing - 1.0) <= tol / 4 and not (near and ki == 2 and
                                                  abs(k - 2) < abs(k - sensing)):
        return "order 2(1 + 1/N): the gauges' sensing ripple (the wave passes the gauges)"
    if not near:
        return ("not an integer wave-generator order: a motor order of pole pairs or slots "
                "that is not one, or another shaft")
    names = {1: "once per wave-generator turn: its eccentricity or bearing",
             2: "twice per turn: the elliptical wave (kinematic error, meshing stiffness)",
             4: "4 per turn: the wave's second harmonic (kinematic error)"}
    if ki in names:
        return names[ki]
    if abs(ki - 2 * n) <= 1:
        return "the tooth mesh: 2N flexspline teeth per wave-generator turn"
    return (f"integer order {ki}: a motor order (2p or 6p for p pole pairs, cogging at the "
            "least common multiple of slots and poles) or a harmonic of the wave")


class RippleTerm(Term):
    """Sinusoids over q at harmonics h of one fundamental period P (found from the
    residual spectrum), the same in both directions of motion or (``odd``) flipping with
    it.

    Parameters
    ----------
    name : str, optional
    harmonics : sequence of int, default (1,)
        Harmonic numbers h >= 1 of the fundamental, distinct. With (1,) the linear
        parameters are ``a_sin``, ``a_cos``; otherwise ``a_sin_h``, ``a_cos_h`` per h.
    gear_ratio : float, optional
        Reduction ratio N: the fundamental is then also reported as the wave-generator
        order ``order`` = 2π / (P N).

    Raises
    ------
    ValueError
        Empty or repeated harmonics, a harmonic below 1, or a gear ratio not above 1.
    """

    nonlinear = (Param("period", "rad", "period over the joint angle (fundamental)",
                       log=True),)
    odd = False

    def __init__(self, name: str | None = None, harmonics: Sequence[int] = (1,),
                 gear_ratio: float | None = None) -> None:
        super().__init__(name)
        h = tuple(sorted(int(x) for x in harmonics))
        if not h or h[0] < 1 or len(set(h)) != len(h):
            raise ValueError(f"harmonics must be distinct integers >= 1, got {list(harmonics)}")
        if gear_ratio is not None and not gear_ratio > 1:
            raise ValueError(f"gear_ratio must be > 1 or None, got {gear_ratio}")
        self.harmonics = h
        self.gear_ratio = None if gear_ratio is None else float(gear_ratio)

    @classmethod
    def for_signals(cls, sig: FrictionSignals, name: str | None = None) -> RippleTerm:
        return cls(name, gear_ratio=getattr(sig, "gear_ratio", None))

    @property
    def single(self) -> bool:
        """One sinusoid at the fundamental (the form the selection loop tries)."""
        return self.harmonics == (1,)

    @property
    def linear(self):  # type: ignore[override]
        if self.single:
            return (Param("a_sin", "N m", "sine coefficient"),
                    Param("a_cos", "N m", "cosine coefficient"))
        out = []
        for h in self.harmonics:
            out += [Param(f"a_sin_{h}", "N m", f"sine coefficient of harmonic {h}"),
                    Param(f"a_cos_{h}", "N m", f"cosine coefficient of harmonic {h}")]
        return tuple(out)

    def options(self) -> dict[str, Any]:
        out: dict[str, Any] = {}
        if not self.single:
            out["harmonics"] = list(self.harmonics)
        if self.gear_ratio is not None:
            out["gear_ratio"] = self.gear_ratio
        return out

    def _base(self, sig):
        return sig.sgn if self.odd else np.ones(sig.n)

    def columns(self, sig, theta):
        w = 2 * np.pi * sig.q_rad / theta[0]
        b = self._base(sig)
        cols = []
        for h in self.harmonics:
            cols += [b * np.sin(h * w), b * np.cos(h * w)]
        return np.column_stack(cols)

    def derived(self, coef, theta):
        period = float(theta[0])
        out: dict[str, float] = {}
        if self.single:
            out["amplitude"] = float(np.hypot(coef[0], coef[1]))
            out["phase"] = float(np.arctan2(coef[1], coef[0]))
        else:
            amps = []
            for i, h in enumerate(self.harmonics):
                a, c = float(coef[2 * i]), float(coef[2 * i + 1])
                out[f"amplitude_{h}"] = float(np.hypot(a, c))
                out[f"phase_{h}"] = float(np.arctan2(c, a))
                amps.append(out[f"amplitude_{h}"])
            # the amplitude of one sinusoid of the same mean square
            out["amplitude"] = float(np.sqrt(np.sum(np.square(amps))))
        out["period"] = period
        if self.gear_ratio is not None:
            out["order"] = wave_generator_order(period, self.gear_ratio)
        return out

    def derived_units(self):
        out = {"amplitude": "N m"}
        if self.single:
            out["phase"] = "rad"
        else:
            for h in self.harmonics:
                out[f"amplitude_{h}"] = "N m"
                out[f"phase_{h}"] = "rad"
        out["period"] = "rad"
        if self.gear_ratio is not None:
            out["order"] = "-"
        return out

    def primary(self):
        return ("amplitude", "period")

    def orders(self, period: float) -> list[float] | None:
        """Wave-generator orders of the harmonics for a fundamental period [rad] (None
        without a gear ratio)."""
        if self.gear_ratio is None:
            return None
        k = wave_generator_order(period, self.gear_ratio)
        return [h * k for h in self.harmonics]


class PositionRipple(RippleTerm):
    """Torque ripple periodic in the joint angle, the same in both directions: kinematic
    error and meshing stiffness ripple at orders of the wave generator (N q, 2 N q),
    motor cogging, gauge ripple (Tuttle & Seering 1996; docs/PHYSICS.md sec. 1 and 5)."""

    kind = "position_ripple"
    description = "ripple periodic in q, even in the direction of motion"
    source = "Tuttle & Seering 1996; docs/PHYSICS.md sec. 1, 5"


class FrictionRipple(RippleTerm):
    """Friction whose level varies periodically with rotation (tooth meshing; Tuttle &
    Seering 1996): τ = sgn(v) Σ_h (a_h sin(2π h q/P) + c_h cos(2π h q/P))."""

    kind = "friction_ripple"
    description = "friction level periodic in q, odd in the direction of motion"
    source = "Tuttle & Seering 1996"
    odd = True
