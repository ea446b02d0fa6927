"""The alarm rule: conformal p-values against the gear's own commissioning, and a CUSUM.

**p-values.** Each window's score s (the diagnosis model's evidence against healthy) is
ranked among the scores of the calibration windows of the same operating point, taken at
commissioning and never used to fit anything: the smoothed conformal p-value
``p = (#{c > s} + U (#{c = s} + 1)) / (n + 1)``, U uniform (Vovk, Gammerman and Shafer,
*Algorithmic Learning in a Random World*, 2005, ch. 2). While the gear is as it was at
commissioning, the p-values are uniform on (0, 1), whatever the score's distribution.

**CUSUM of a betting function.** ``S_t = max(0, S_{t−1} + ln f(p_t))`` with the mixture
``f(p) = ∫_0^1 κ p^(κ−1) dκ = (p (ln p − 1) + 1) / (p ln² p)``, which integrates to 1
over uniform p (the power martingale mixed over κ, Vovk et al. 2005, ch. 7; Volkhonskiy
et al., *Inductive conformal martingales for change-point detection*, COPA 2017). An
alarm when ``S_t >= h``. With ``E_0[f(p)] = 1``, ``ln f`` is a log-likelihood ratio and
Lorden's bound gives an average run length to a false alarm of at least ``e^h`` windows
(Lorden, *Procedures for reacting to a change in distribution*, Ann. Math. Stat. 1971):
``h = ln(design hours · 60 / interval_min)`` sets the design false-alarm rate, one per
``design hours`` of operation (default 1000 h). No parameter is tuned to any gear.

**A second CUSUM for weak, lasting changes.** The mixture gains only from p-values below
about 0.15; a fault that lowers every window's p-value a little (mean p 0.2-0.3) never
reaches h. With ``shift_sigma`` = δ > 0 a second CUSUM runs on the normal scores
``z = Φ⁻¹(1 − p)`` (standard normal while healthy) with ``ln f = δ z − δ²/2``, Page's
CUSUM for a shift of δ standard deviations, also of ``E_0[f] = 1`` (Page, *Continuous
inspection schemes*, Biometrika 1954). An alarm when either reaches ``h + ln 2``, so that
the two together keep the design rate (Bonferroni).

**Shortest commissioning.** One window moves S by at most ``ln f(1 / (n + 1))``, n the
calibration windows of its operating point. For the rule to reach h within its design
delay (``max_delay_windows``) at all, ``max_delay_windows · ln f(1/(n + 1)) >= h``;
:func:`min_calibration` solves it for n, :func:`check_commissioning` refuses less.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

from swgmon.detection.normal import Outside
from swgsim.base.lazy import lazy_module
from swgsim.base.typed import allowed, check_range
from swgsim.sensing.sensor_faults import is_sensor_fault

special = lazy_module("scipy.special")

#: The name of a fault of the joint's temperature sensor (stuck, drifting, off), which
#: :func:`swgmon.assessment.sensor_check.fit_temperature` tests.
TEMPERATURE_SENSOR = "temperature_sensor"
#: The name of an alarm an even change of friction explains
#: (:func:`swgmon.assessment.unexplained.fit_friction`): no gear fault's signature, and no
#: declared maintenance.
UNEXPLAINED_CHANGE = "unexplained_change"


@dataclass
class RuleConfig:
    """The sequential rule's design; it checks itself (:meth:`check`, run by
    :func:`swgsim.base.typed.check_tree`).

    Attributes
    ----------
    design_hours : float
        One false alarm per this many operating hours, in (0, 1e6] h (default 1000 h).
    shift_sigma : float
        δ of the second CUSUM (module docstring), in [0, 10]; 0 runs the mixture alone.
    max_delay_windows : int
        Windows in which a fault that gives every window the smallest p-value must be
        detectable (sets the shortest commissioning), in [1, 1e5] (0 can never alarm).
    min_normal_windows : int
        Fewest normal-behaviour windows per operating point (its mean and spread), in
        [2, 1e5] (a spread needs two windows).
    """

    design_hours: float = 1000.0
    shift_sigma: float = field(default=0.5, metadata=allowed(
        0.0, 10.0, "the shift CUSUM's delta in standard deviations; 0 leaves it out"))
    max_delay_windows: int = field(default=30, metadata=allowed(
        1, 100_000, "windows in which the strongest evidence must reach the threshold"))
    min_normal_windows: int = field(default=30, metadata=allowed(
        2, 100_000, "a mean and a spread per operating point"))

    def check(self, where: str) -> None:
        """Refuse a design false-alarm rate out of range, in one line naming the key
        (the other fields' ranges are their metadata, :func:`swgsim.base.typed.allowed`).

        Parameters
        ----------
        where : str
            Full name of the rule for messages (``rule``, ``monitor.study.rule``).

        Raises
        ------
        ValueError
            ``design_hours`` outside (0, 1e6] h.
        """
        check_range(self.design_hours, 0.0, 1e6, f"{where}.design_hours", "h", lo_open=True,
                    why="one false alarm per this many operating hours")


def log_bet(p: np.ndarray) -> np.ndarray:
    """ln f(p) of the mixture betting function (module docstring), p in (0, 1]."""
    p = np.clip(np.asarray(p, float), 1e-300, 1.0)
    lp = np.log(p)
    small = np.abs(lp) < 1e-6  # f(1) = 1/2 + O(ln p)
    with np.errstate(divide="ignore", invalid="ignore"):
        f = (p * (lp - 1.0) + 1.0) / (p * lp ** 2)
    return np.where(small, np.log(0.5), np.log(np.where(small, 1.0, f)))


def normal_scores(p: np.ndarray) -> np.ndarray:
    """Φ⁻¹(1 − p) of p-values in (0, 1]: standard normal while the p-values are uniform."""
    return special.ndtri(1.0 - np.clip(np.asarray(p, float), 1e-300, 1.0 - 1e-12))


def log_shift(p: np.ndarray, delta: float) -> np.ndarray:
    """ln f of Page's CUSUM on the normal scores of p-values: δ Φ⁻¹(1 − p) − δ²/2."""
    return delta * normal_scores(p) - 0.5 * delta * delta


def n_cusums(rule: RuleConfig) -> int:
    """CUSUMs the rule runs: the mixture, and Page's with ``shift_sigma`` > 0."""
    return 1 + (rule.shift_sigma > 0)


def log_bets(p: np.ndarray, rule: RuleConfig) -> np.ndarray:
    """ln f of every CUSUM of the rule, shape (n, :func:`n_cusums`)."""
    cols = [log_bet(p)]
    if rule.shift_sigma > 0:
        cols.append(log_shift(p, rule.shift_sigma))
    return np.stack(cols, axis=1)


def threshold(rule: RuleConfig, interval_min: float) -> float:
    """h = ln(windows in ``design_hours``) + ln(CUSUMs): the design false-alarm rate
    (module docstring)."""
    return math.log(rule.design_hours * 60.0 / float(interval_min) * n_cusums(rule))


def min_calibration(rule: RuleConfig, interval_min: float) -> int:
    """Fewest calibration windows per operating point for which the rule can reach h
    within ``max_delay_windows`` (module docstring): the smallest n with
    ``max_delay_windows · ln f(1 / (n + 1)) >= h`` (ln f(1/(n+1)) grows with n), by
    doubling and bisection."""
    h = threshold(rule, interval_min)

    def enough(n: int) -> bool:
        return rule.max_delay_windows * float(log_bet(1.0 / (n + 1))) >= h

    hi = 1
    while not enough(hi):
        hi *= 2
    lo = hi // 2
    while hi - lo > 1:  # enough(hi), not enough(lo) (or lo = 0)
        mid = (lo + hi) // 2
        lo, hi = (lo, mid) if enough(mid) else (mid, hi)
    return max(hi, 1)


def conformal_p(scores: np.ndarray, calibration: np.ndarray, u: np.ndarray) -> np.ndarray:
    """Smoothed conformal p-values of scores among calibration scores.

    Parameters
    ----------
    scores : ndarray, shape (m,)
    calibration : ndarray, shape (n,)
        Sorted ascending.
    u : ndarray, shape (m,)
        Uniform draws in [0, 1).

    Returns
    -------
    ndarray, shape (m,)
        In (0, 1].
    """
    n = calibration.size
    above = n - np.searchsorted(calibration, scores, side="right")
    equal = np.searchsorted(calibration, scores, side="right") - np.searchsorted(
        calibration, scores, side="left")
    return (above + u * (equal + 1)) / (n + 1)


def run_cusums(lf: np.ndarray, h: float, start: np.ndarray | float = 0.0,
               latch: bool = True) -> tuple[np.ndarray, list[int]]:
    """CUSUMs ``S = max(0, S + ln f)`` side by side, an alarm when any reaches ``h``.

    Parameters
    ----------
    lf : ndarray, shape (n, k)
        ln f of each CUSUM per window.
    h : float
    start : float or ndarray, shape (k,)
        Values before the first window.
    latch : bool
        Stop at the first alarm (the rest NaN); else restart every CUSUM at zero after it.

    Returns
    -------
    (ndarray, shape (n, k), list of int)
        The CUSUMs and the alarm windows.
    """
    n, k = lf.shape
    out = np.full((n, k), np.nan)
    s = np.broadcast_to(np.asarray(start, float), (k,)).copy()
    alarms = []
    for i in range(n):
        s = np.maximum(0.0, s + lf[i])
        out[i] = s
        if (s >= h).any():
            alarms.append(i)
            if latch:
                break
            s[:] = 0.0
    return out, alarms


def check_commissioning(points: np.ndarray, rule: RuleConfig, interval_min: float) -> None:
    """Refuse commissioning windows too few for the rule at any operating point.

    Raises
    ------
    ValueError
        Naming the operating point, the windows it has and the minimum.
    """
    need = 2 * max(rule.min_normal_windows, min_calibration(rule, interval_min))
    if len(points) == 0:
        raise ValueError("the stream has no commissioning windows (a period known healthy, "
                         f"at least {need} windows per operating point)")
    ops, counts = np.unique(points, axis=0, return_counts=True)
    for o, c in zip(ops, counts, strict=True):
        if c < need:
            raise ValueError(
                f"commissioning too short for the design of one false alarm per "
                f"{rule.design_hours:g} h: {c} windows at {o[0]:g} rpm, {o[1]:g} N m, at least "
                f"{need} needed ({min_calibration(rule, interval_min)} to calibrate, "
                f"{rule.min_normal_windows} for the normal behaviour, alternately)")


def judged_bets(p: np.ndarray, outside: np.ndarray, rule: RuleConfig) -> np.ndarray:
    """ln f of every CUSUM of the rule per window (:func:`~.rule.log_bets`), shape
    (n, k), 0 where the window is not judged (``outside`` has
    :attr:`~.normal.Outside.UNJUDGED`): the CUSUMs hold there, neither rising nor
    draining."""
    bets = log_bets(p, rule)
    bets[(np.asarray(outside) & Outside.UNJUDGED) != 0] = 0.0
    return bets


@dataclass
class Alarm:
    """An alarm and what the monitor says about it.

    Attributes
    ----------
    hour : float
        Operating hours of the window that raised it.
    index : int
        That window's index in the stream.
    rise_index : int
        First window of the CUSUM's rise that led to it.
    fault_at_alarm : str
        Named from the windows of the rise.
    fault : str
        Named from the windows of the rise up to ``confirm_h`` after the alarm.
    severity, severity_low, severity_high : float
        Estimate of ``fault``'s severity and its 90 % interval; of the temperature
        sensor's fault, the fitted temperature minus the reading [K], median and 5-95 %
        over the windows; of an unexplained change, the friction's relative change and
        its 90 % interval from the fit's profile [-]
        (:func:`swgmon.assessment.unexplained.profile_interval`; NaN where it has none).
    bridge : str or None
        The faulty bridge (``s0``..``s4``) where ``fault`` is a sensor fault that one
        bridge alone explains (:mod:`swgmon.assessment.sensor_check`).
    moved : list of [str, float]
        The features that moved most over the windows named from, with their mean
        z-score [σ] (:func:`moved_features`): what the alarm saw.
    hypotheses : list of [str, str, int or None, float]
        The candidates it was weighed against (:mod:`swgmon.assessment.hypotheses`):
        hypothesis, what it would name, its bridge, and the log posterior odds [nats]
        that the windows look healthy with its effect taken out
        (:func:`swgmon.assessment.hypotheses.log_odds`), the evidence the rule picks by;
        empty: none plausible.
    """

    hour: float
    index: int
    rise_index: int
    fault_at_alarm: str
    fault: str
    severity: float
    severity_low: float
    severity_high: float
    bridge: str | None = None
    moved: list[list] = field(default_factory=list)
    hypotheses: list[list] = field(default_factory=list)

    @property
    def sensor_fault(self) -> bool:
        """Whether the fault named is a sensor's, not the gear's: the temperature
        sensor's, a bridge's, or a sensor fault that no one bridge explains (a class of
        :data:`~swgsim.sensing.sensor_faults.SENSOR_FAULTS` named without a bridge)."""
        return (self.bridge is not None or self.fault == TEMPERATURE_SENSOR
                or is_sensor_fault(self.fault))

    @property
    def kind(self) -> str:
        """``sensor_fault``, ``unexplained_change`` (an even change of the friction,
        :func:`~swgmon.assessment.unexplained.fit_friction`) or ``gear_fault``."""
        return ("sensor_fault" if self.sensor_fault else
                "unexplained_change" if self.fault == UNEXPLAINED_CHANGE else "gear_fault")

    def as_dict(self) -> dict:
        """The ``summary.json`` entry (a severity or bound that is NaN: null)."""
        def finite(x: float) -> float | None:
            return float(x) if np.isfinite(x) else None

        return {"hour": self.hour, "fault": self.fault, "fault_at_alarm": self.fault_at_alarm,
                "severity": finite(self.severity), "severity_low": finite(self.severity_low),
                "severity_high": finite(self.severity_high), "bridge": self.bridge,
                "moved": [list(m) for m in self.moved],
                "hypotheses": [list(h) for h in self.hypotheses]}


def moved_features(z: np.ndarray, names: list[str], k: int = 3) -> list[list]:
    """Up to ``k`` features whose mean z-score over the windows lies farthest from zero,
    at least 1 σ (the first always): what an alarm saw, whatever it is named (a gear
    fault, a sensor's, an unexplained change).

    Parameters
    ----------
    z : ndarray, shape (n, F)
        The windows' z-scores against the gear's normal behaviour.
    names : list of str
        The features' names, F of them or more (:func:`learn.inputs.health.feature_names`).
    k : int

    Returns
    -------
    list of [str, float]
        Name and mean z-score [σ], largest magnitude first.
    """
    ok = ~np.isnan(z)
    with np.errstate(invalid="ignore"):  # a feature never read: NaN, as np.nanmean's
        mean = (np.where(ok, z, 0.0).sum(axis=0) / ok.sum(axis=0) if len(z)
                else np.zeros(z.shape[1]))
    top = np.argsort(-np.abs(np.nan_to_num(mean)))[:k]
    return [[names[j], round(float(mean[j]), 2)] for i, j in enumerate(top)
            if i == 0 or abs(mean[j]) >= 1.0]


__all__ = ["Alarm", "RuleConfig", "check_commissioning", "conformal_p", "judged_bets",
           "log_bet", "log_bets", "log_shift", "min_calibration", "moved_features", "n_cusums",
           "normal_scores", "run_cusums", "threshold"]
