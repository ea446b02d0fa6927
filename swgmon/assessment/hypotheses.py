"""The hypotheses an alarm is weighed against: a registry, one class each.

An alarm is a question with several answers. Each hypothesis fits the windows since the
alarm (:class:`Windows`) and returns its candidates (:class:`Candidate`): the answer it
gives and the windows' z-scores with its effect taken out. The monitor weighs them all by
one rule (:func:`~.naming.name`, :func:`log_odds`): the candidate with
the largest posterior odds that it explains the alarm, where they exceed 1; else the gear
fault the diagnosis model names. A hypothesis that holds without an alarm (a stuck
reading) is also a check (:class:`ReadingCheck`): the stream asks it, window by
window, where it is found (:class:`Finding`), names the temperature sensor's fault there
and goes on without the reading. The hypotheses are a registry (:data:`HYPOTHESES`; one's own by
:func:`register_hypothesis`, docs/ARCHITECTURE.md, "To add a hypothesis"); which are
weighed, in which order, is ``naming.hypotheses`` (:class:`~.sensor_check.NamingConfig`).
Design and sources: docs/monitor/assessment.md, "The hypotheses".
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Protocol, runtime_checkable

import numpy as np

from swgmon.assessment.sensor_check import (
    NamingConfig,
    fit_bridge_faults,
    fit_temperature,
    fit_temperature_drift,
    still_reading,
)
from swgmon.assessment.unexplained import fit_friction
from swgmon.detection.normal import Conditions, NormalBehaviour
from swgmon.detection.rule import TEMPERATURE_SENSOR, UNEXPLAINED_CHANGE
from swgsim.base.registry import Registry


@dataclass(frozen=True)
class Windows:
    """The windows since an alarm, as every hypothesis fits them.

    Attributes
    ----------
    normal : NormalBehaviour
        Commissioning's normal behaviour.
    feats : ndarray, shape (n, F)
        The windows' health features.
    points : ndarray, shape (n, 2)
        Their operating points (input speed [rpm], torque [N m]).
    cond : Conditions or None
        Their conditions (None: the points' loads, no reading).
    friction : ndarray, shape (n,)
        The friction factor in force at each window [-].
    index : ndarray of int, shape (n,)
        Each window's operating point in ``normal``.
    z, spread : ndarray, shape (n, F)
        Their z-scores and spread (:meth:`NormalBehaviour.z_and_spread`).
    hours : ndarray, shape (n,), or None
        Their operating hours [h]; None: no rate is fitted.
    naming : NamingConfig
        The naming's numbers.
    classes : tuple of str
        The diagnosis model's classes (a sensor fault it has no class for is not named).
    read : bool
        Whether the joint's temperature reading is in use (not virtual, not absent).
    """

    normal: NormalBehaviour
    feats: np.ndarray
    points: np.ndarray
    cond: Conditions | None
    friction: np.ndarray
    index: np.ndarray
    z: np.ndarray
    spread: np.ndarray
    hours: np.ndarray | None
    naming: NamingConfig
    classes: tuple[str, ...]
    read: bool


@dataclass(frozen=True)
class Candidate:
    """One answer a hypothesis gives.

    Attributes
    ----------
    hypothesis : str
        The hypothesis's name (``naming.hypotheses``).
    fault : str
        What the monitor names if it wins: a sensor fault, the temperature sensor's,
        an unexplained change, or a fault of one's own.
    bridge : int or None
        The faulty bridge (0..4) of a bridge's sensor fault, else None.
    z : ndarray, shape (n, F)
        The windows' z-scores with the hypothesis's effect taken out.
    fit : object or None
        The fit behind it (its severity: :func:`~.naming.diagnose`).
    """

    hypothesis: str
    fault: str
    bridge: int | None
    z: np.ndarray
    fit: object | None = None


class Hypothesis(Protocol):
    """What the registry holds: a ``name`` and the candidates it fits to windows."""

    name: str

    def candidates(self, w: Windows) -> list[Candidate]:
        """The hypothesis's plausible answers for the windows ``w`` (none: it does not
        explain them)."""


class BridgeFault:
    """One bridge's offset step or gain drift (:func:`~.sensor_check.fit_bridge_faults`):
    each plausible fit of a fault the model has a class for, whose other bridges have not
    moved on average (``naming.rest_max``)."""

    name = "bridge_fault"

    def candidates(self, w: Windows) -> list[Candidate]:
        fits = fit_bridge_faults(w.normal, w.feats, w.points, w.cond, w.friction, w.index,
                                 w.z, w.spread, w.hours)
        return [Candidate(self.name, f.fault, f.bridge, f.z) for f in fits
                if f.fault in w.classes and f.plausible(w.naming)
                and f.rest <= w.naming.rest_max]


class TemperatureReading:
    """The temperature reading is wrong, window by window: stuck, lagging or off
    (:func:`~.sensor_check.fit_temperature`); only while the reading is in use."""

    name = "temperature_reading"

    def candidates(self, w: Windows) -> list[Candidate]:
        fit = fit_temperature(w.normal, w.feats, w.points, w.cond, w.friction, w.index,
                              w.naming) if w.read else None
        return [Candidate(self.name, TEMPERATURE_SENSOR, None, fit.z, fit)] \
            if fit is not None and fit.plausible(w.naming) else []


class TemperatureDrift:
    """The temperature reading drifts: an offset and a rate
    (:func:`~.sensor_check.fit_temperature_drift`); only while the reading is in use."""

    name = "temperature_drift"

    def candidates(self, w: Windows) -> list[Candidate]:
        fit = fit_temperature_drift(w.normal, w.feats, w.points, w.cond, w.friction,
                                    w.index, w.hours, w.naming) if w.read else None
        return [Candidate(self.name, TEMPERATURE_SENSOR, None, fit.z, fit)] \
            if fit is not None and fit.plausible(w.naming) else []


class EvenFriction:
    """The friction changed evenly, as no gear fault changes it: re-greasing, another
    grease, a seal (:func:`~.unexplained.fit_friction`), named an unexplained change."""

    name = "even_friction"

    def candidates(self, w: Windows) -> list[Candidate]:
        fit = fit_friction(w.normal, w.feats, w.points, w.cond, w.friction, w.index,
                           w.hours, w.naming)
        return [Candidate(self.name, UNEXPLAINED_CHANGE, None, fit.z, fit)] \
            if fit.plausible(w.naming) else []


@dataclass(frozen=True)
class Stream:
    """The windows a check reads: those since the monitor last went on up to the first
    without a reading, no alarm needed. The attributes are :class:`Windows`'s of the same
    name, but ``friction``, one factor in force [-], and ``cond``, never None.
    """

    normal: NormalBehaviour
    feats: np.ndarray
    points: np.ndarray
    cond: Conditions
    friction: float
    hours: np.ndarray
    naming: NamingConfig
    read: bool


@dataclass(frozen=True)
class Finding:
    """Where a check holds: the window its fault began at and the one it is found at
    (indices into the :class:`Stream`'s windows, ``first`` <= ``found``)."""

    hypothesis: str
    first: int
    found: int


@runtime_checkable
class ReadingCheck(Protocol):
    """A hypothesis that holds without an alarm: the temperature reading has failed.
    The stream (:func:`~swgmon.advisories.stream.run_stream`) asks every one in force, in
    ``naming.hypotheses``'s order, each on the windows before the last one's finding; at
    the earliest it names the temperature sensor's fault (an alarm raised from ``first``
    and within ``confirm_h`` of ``found`` too) and goes on without the reading."""

    name: str

    def found(self, s: Stream) -> Finding | None:
        """Where the check holds in ``s``, else None."""


class StuckReading:
    """The reading is stuck: one value, to the bit, while the temperature the bridges and
    the efficiency say moves (:func:`~.sensor_check.still_reading`); only while the
    reading is in use. Weighed at an alarm, a stuck reading is
    :class:`TemperatureReading`'s candidate."""

    name = "stuck_reading"

    def candidates(self, w: Windows) -> list[Candidate]:
        return []

    def found(self, s: Stream) -> Finding | None:
        still = still_reading(s.normal, s.feats, s.points, s.cond, s.friction, s.hours,
                              s.naming) if s.read else None
        return None if still is None else Finding(self.name, *still)


def effective_windows(x: np.ndarray) -> float:
    """The effective number of independent windows in a series ``x`` (n,): n (1 − ρ) /
    (1 + ρ), ρ its lag-1 autocorrelation clipped to [0, 0.99], at least 1 (the variance
    of an AR(1) series' mean; D. S. Wilks, *Statistical Methods in the Atmospheric
    Sciences*, 3rd ed., 2011, eq. 5.12). Neighbouring windows share their conditions, so
    an hour of windows is worth fewer than its count."""
    x = np.asarray(x, float)
    d = x - x.mean()
    den = float(d @ d)
    rho = float(d[1:] @ d[:-1]) / den if len(x) > 2 and den > 0 else 0.0
    rho = min(max(rho, 0.0), 0.99)
    return max(1.0, len(x) * (1.0 - rho) / (1.0 + rho))


#: The trapezoid rule's grid over [0, 1] and its log weights (:func:`_log_marginal`):
#: error below 1e-3 nats (tests, against scipy's quad).
_T = np.linspace(0.0, 1.0, 4097)
_LOG_W = np.log(np.r_[0.5, np.ones(len(_T) - 2), 0.5] / (len(_T) - 1))


def _log_marginal(n: float, s: float, median_lo: float, median_hi: float) -> float:
    """ln ∫ ξⁿ exp((1 − ξ) s) dξ / (ξ₁ − ξ₀) over the Beta(ξ, 1) exponents whose median
    p-value lies in [``median_lo``, ``median_hi``] (ξ = ln 2 / −ln median): the marginal
    likelihood ratio of Beta(ξ, 1) p-values, ξ uniform there, against uniform ones, for n
    windows with S = −Σ ln p = ``s``."""
    lo, hi = (np.log(2.0) / -np.log(m) if m > 0 else 0.0 for m in (median_lo, median_hi))
    xi = lo + _T * (hi - lo)
    with np.errstate(divide="ignore"):
        g = n * np.log(xi) + (1.0 - xi) * s + _LOG_W
    top = float(g.max())
    return top + float(np.log(np.sum(np.exp(g - top))))


def log_odds(p: np.ndarray, prior_odds: float, right_median_p: float,
             wrong_median_p: float) -> float:
    """Log posterior odds that a candidate explains an alarm, from its corrected windows:
    the rule that weighs the hypotheses (docs/monitor/assessment.md, "The rule").

    The windows' conformal p-values follow Beta(ξ, 1) (the family of Sellke, Bayarri and
    Berger, "Calibration of p values for testing precise null hypotheses", The American
    Statistician 55(1), 2001; ξ = 1: uniform, healthy). The candidate explains the
    alarm: ξ uniform over the exponents whose median p-value is at least
    ``right_median_p`` (as a right candidate leaves the windows); it does not: ξ uniform
    over those whose median is at most ``wrong_median_p`` (as a wrong one leaves them).
    The Bayes factor of the two on the effective number n of windows
    (:func:`effective_windows`, S = −Σ ln p scaled with it), times the prior odds.

    Parameters
    ----------
    p : ndarray, shape (n,)
        The corrected windows' conformal p-values, in (0, 1] (n ≥ 1).
    prior_odds : float
        Prior odds of the candidate against its windows staying abnormal, > 0
        (``naming.prior_odds``).
    right_median_p : float
        The least median p-value a right candidate leaves, in (``wrong_median_p``, 0.5)
        (``naming.right_median_p``).
    wrong_median_p : float
        The largest median p-value a wrong candidate leaves, in (0, ``right_median_p``)
        (``naming.wrong_median_p``).

    Returns
    -------
    float
        The log posterior odds [nats]; the candidate explains the alarm where they are
        positive.
    """
    x = -np.log(np.clip(np.asarray(p, float), 1e-300, 1.0))
    n = effective_windows(x)
    s = n * float(x.mean())
    return float(np.log(prior_odds) + _log_marginal(n, s, right_median_p, 0.5)
                 - _log_marginal(n, s, 0.0, wrong_median_p))


#: The hypotheses by name, weighed in registration order where ``naming.hypotheses`` is
#: None; carried to worker processes by :func:`swgsim.base.registry.travelling`.
HYPOTHESES: Registry[Hypothesis] = Registry("hypothesis", __name__, "HYPOTHESES", [
    (h.name, h()) for h in (BridgeFault, TemperatureReading, TemperatureDrift, EvenFriction,
                            StuckReading)])


def register_hypothesis(h: Hypothesis) -> Hypothesis:
    """Register ``h`` under ``h.name`` (weighed after those before it; a name taken is
    refused, :meth:`swgsim.base.registry.Registry.add`); returns it."""
    return HYPOTHESES.add(h.name, h)


def registered(naming: NamingConfig) -> list[Hypothesis]:
    """The hypotheses ``naming.hypotheses`` names, in its order (None: every registered
    one); checked before any work by the apps and the studies.

    Raises
    ------
    ValueError
        A name not registered, or a name twice (one line naming ``naming.hypotheses``).
    """
    names = list(HYPOTHESES) if naming.hypotheses is None else list(naming.hypotheses)
    for n in names:
        what = "no hypothesis" if n not in HYPOTHESES else "twice in the list"
        if n not in HYPOTHESES or names.count(n) > 1:
            raise ValueError(f"naming.hypotheses: {n!r} is {what}; registered: "
                             f"{', '.join(HYPOTHESES)}")
    return [HYPOTHESES[n] for n in names]


__all__ = ["HYPOTHESES", "BridgeFault", "Candidate", "EvenFriction", "Finding", "Hypothesis",
           "ReadingCheck", "Stream", "StuckReading", "TemperatureDrift",
           "TemperatureReading", "Windows", "effective_windows", "log_odds",
           "register_hypothesis", "registered"]
