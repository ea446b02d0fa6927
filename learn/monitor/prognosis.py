"""Prognosis after an alarm: the hours left until the named fault's severity reaches its
failure threshold, as a distribution (in the stream: :mod:`.stream_prognosis`).

The physics-based predictor (:func:`predict_growth`) takes the fault's growth law from
:mod:`swgsim.datasets.growth` (Paris' law for the cracks, Archard's law for the wave
generator's eccentricity and the flanks' wear) with its one unknown, the gear's factor
``s`` on Paris' C or on the wear coefficient. Under the duty the gear ran (each window's
input speed, acting load and grease temperature) the law gives the exposure X(t) the
gear took at s = 1: Paris' damage sum D (:func:`swgsim.datasets.growth.paris_damage`) or
the worn depth (:func:`swgsim.datasets.growth.archard_depth`). In a transformed severity u
both laws are straight lines in X [derived: the closed form of
:func:`swgsim.datasets.growth.paris_crack_depth` solved for a]:

* Archard: u = severity, u = u0 + s X / d1 (d1 the depth at severity 1,
  :data:`swgsim.datasets.growth.DEPTH_AT_ONE_M`);
* Paris (m ≠ 2): u = (severity d1)^(1 − m/2), u = u0 + (1 − m/2) (Y √π)^m s X; m = 2:
  u = ln(severity d1), u = u0 + (Y √π)^2 s X.

The likelihood of the monitor's severity estimates is Gaussian in severity, σ from each
estimate's 90 % interval (:meth:`learn.monitor.model.DiagnosisModel.estimate`, σ = its
width / 3.29), the model severity = u⁻¹(u0 + b s X). The unknown u0 (the severity at the
alarm, transformed) is integrated out by Laplace's method about its Gauss-Newton fit at
each s, and ln s gets a grid posterior whose prior is normal with the growth's per-gear
scatter (:attr:`swgsim.datasets.growth.RunToFailure.scatter`: the fleet the model was
trained on). [A weighted straight-line fit in u, with the intervals mapped to u, was
tried first: on root cracks with σ = 0.03 it overestimated the remaining hours by 17 %
(median of 20 lives at 60 % of the way) and its interval held 45 % of the true failure
hours, the transform's curvature biasing the noisy estimates.]
Monte-Carlo draws of (s, u0) give the exposure still needed to the failure threshold and,
through the future duty (the recorded one's mean exposure per hour, or a planned one the
user declares, repeated as a cycle), the remaining hours. Everything is vectorised; the
cost is O(windows + grid points × estimates + samples).

Assumptions: the estimates' errors are independent with the stated intervals (they are
not: neighbouring estimates share windows, so the posterior is too narrow unless widened:
``PrognosisConfig.interval_scale``, calibrated by split conformal across the training
gears' lives: :mod:`learn.monitor.prognosis_calibration`); the law and its exponent m are
right and only the scale is unknown; the future runs at the recorded duty's mean rate or
repeats the planned duty from its first block.

Two baselines take the same inputs and ignore the duty
(:mod:`learn.monitor.prognosis_baselines`): a weighted straight line of severity in
operating hours, and a Wiener process with drift in operating hours, no load covariate.

ProgPy (1.9) and SurPyval (0.25) were read and not used (docs/monitor.md says why).
"""

from __future__ import annotations

import dataclasses
import numbers
from dataclasses import dataclass, field

import numpy as np

from swgsim.base.typed import check_range
from swgsim.datasets.growth import (
    DEPTH_AT_ONE_M,
    LAWS,
    RunToFailure,
    archard_depth,
    check_to_failure,
    load_cycles,
    paris_damage,
)
from swgsim.datasets.schedule import LifeConfig
from swgsim.gear.faults import get_fault

__all__ = ["Duty", "DutyRange", "Prognosis", "PrognosisConfig", "Track", "check_track",
           "exposure", "from_samples", "hours_for_exposure", "not_valid", "not_yet_valid",
           "predict_growth", "severity_of", "transformed"]

#: z of a central 90 % interval of a normal distribution, its half-width in σ [-].
Z90 = 1.6448536269514722

#: Gauss-Newton steps of u0's fit at each grid point of ln s (6 [choice]: from the first
#: quarter's mean, 3, 6 and 12 steps gave the same quantiles to 1e-13 on synthetic root
#: crack and wear tracks as in tests/learn/test_prognosis.py).
GAUSS_NEWTON_STEPS = 6

#: Operating hours a lone recorded window holds (no interval to take the median of): the
#: data sets' recording interval (:attr:`~swgsim.datasets.schedule.LifeConfig.interval_min`).
LONE_WINDOW_H = LifeConfig.interval_min / 60.0


@dataclass(frozen=True)
class PrognosisConfig:
    """What the prognosis needs beyond its inputs (checks itself: :meth:`check`).

    Attributes
    ----------
    min_track_h : float
        Operating hours of severity estimates since the alarm before a prediction is
        valid, in (0, 1000] [h] (2 h [choice]: at the accelerated lives of
        :mod:`swgsim.datasets.growth`, about 1 % of a crack's life).
    min_estimates : int
        Severity estimates since the alarm before a prediction is valid, in [3, 10^6]
        (10 [choice]).
    n_samples : int
        Monte-Carlo samples of the remaining life, in [100, 10^6] (4000 [choice]: the 5 %
        quantile from 200 samples beyond it).
    n_grid : int
        Points of the grid posterior of ln s, in [21, 10001] (401 [choice]).
    log_scale_span : float
        Half-width of that grid around ln s = 0, in (0, 10] [-] (5: s within a factor
        e^5 = 148 of the growth's constants [choice]).
    interval_scale : float
        Factor on the interval's log half-widths about the median, in (0, 20] [-] (1: the
        posterior's own; :func:`~.prognosis_calibration.conformal_interval_scale` calibrates it).
    horizon_h : float
        Remaining hours beyond which a sample counts as "no failure in sight" (inf), in
        (0, 10^7] [h] (10^6 [choice]).
    max_bins : int
        Most groups of consecutive estimates the fit sees, in [8, 10^5] (256 [choice]): a
        longer track is fitted on each group's inverse-variance weighted mean severity and
        mean exposure, their weight the group's sum (exact for a law straight within a
        group; a 100 h track then costs what 256 estimates cost).
    to_failure : RunToFailure
        The growth's constants (:class:`swgsim.datasets.growth.RunToFailure`): the laws'
        m, Y, Δσ per N m, film exponent, the median C and wear coefficient (s = 1), the
        per-gear scatter (the prior σ of ln s) and the failure severities.
    """

    min_track_h: float = 2.0
    min_estimates: int = 10
    n_samples: int = 4000
    n_grid: int = 401
    log_scale_span: float = 5.0
    interval_scale: float = 1.0
    horizon_h: float = 1e6
    max_bins: int = 256
    to_failure: RunToFailure = field(default_factory=RunToFailure)

    def check(self) -> PrognosisConfig:
        """Refuse a field out of range in one line naming ``prognosis.<field>`` (the fault's
        own range of ``failure``: :func:`check_track`); return self. Raises ValueError."""
        for name, lo, hi in (("min_estimates", 3, 1e6), ("n_samples", 100, 1e6),
                             ("n_grid", 21, 10001), ("max_bins", 8, 1e5)):
            v = getattr(self, name)
            if isinstance(v, bool) or not isinstance(v, numbers.Integral):  # 1000.5, True
                raise ValueError(f"prognosis.{name} must be an integer, got {v!r}")
            check_range(v, lo, hi, f"prognosis.{name}")
        check_range(self.min_track_h, 0.0, 1000.0, "prognosis.min_track_h", "h", lo_open=True)
        check_range(self.log_scale_span, 0.0, 10.0, "prognosis.log_scale_span", lo_open=True)
        check_range(self.interval_scale, 0.0, 20.0, "prognosis.interval_scale", lo_open=True)
        check_range(self.horizon_h, 0.0, 1e7, "prognosis.horizon_h", "h", lo_open=True)
        unset = dataclasses.replace(self.to_failure, failure=None)
        for law, faults in LAWS.items():
            for fault in faults:  # the onset's severity is not the prognosis's: any > 0
                check_to_failure(unset, fault, law, 1e-9, "prognosis")
        if self.to_failure.failure is not None:
            top = max(get_fault(f).severity_range[1] for fs in LAWS.values() for f in fs)
            check_range(self.to_failure.failure, 0.0, top, "prognosis.to_failure.failure",
                        lo_open=True, why="within a fault's severity range")
        return self

    def threshold(self, fault: str) -> float:
        """The failure severity of ``fault`` (``to_failure``'s, by default
        :data:`swgsim.datasets.growth.FAILURE_SEVERITY`) [-]."""
        return self.to_failure.failure_severity(fault)


@dataclass(frozen=True, eq=False)
class Duty:
    """A duty as blocks, each holding an operating point, load and temperature.

    Attributes
    ----------
    minutes : ndarray, shape (K,)
        Operating minutes of each block, > 0 [min].
    n_in_rpm, t_acting_nm, temp_c : ndarray, shape (K,)
        Input speed [rpm], acting load [N m] and grease temperature [°C] of each block.
    """

    minutes: np.ndarray
    n_in_rpm: np.ndarray
    t_acting_nm: np.ndarray
    temp_c: np.ndarray

    @classmethod
    def from_windows(cls, hours: np.ndarray, n_in_rpm: np.ndarray, t_acting_nm: np.ndarray,
                     temp_c: np.ndarray) -> Duty:
        """The duty of windows at operating ``hours`` (shape (W,), increasing), each
        holding until the next; the last for the median interval [choice], a lone one
        for :data:`LONE_WINDOW_H`."""
        h = np.asarray(hours, float)
        dt = np.diff(h)
        last = float(np.median(dt)) if dt.size else LONE_WINDOW_H
        return cls(np.append(dt, last) * 60.0, np.asarray(n_in_rpm, float),
                   np.asarray(t_acting_nm, float), np.asarray(temp_c, float))

    def check(self, key: str) -> None:
        """Refuse blocks of unequal length, none, or a non-positive or non-finite
        duration, in one line naming ``key``. Raises ValueError."""
        arrays = [np.asarray(getattr(self, f.name), float) for f in dataclasses.fields(self)]
        k = arrays[0].shape
        if len(k) != 1 or k[0] == 0 or any(a.shape != k for a in arrays):
            raise ValueError(f"{key}: minutes, n_in_rpm, t_acting_nm and temp_c must be "
                             f"1-D of one length >= 1, got shapes {[a.shape for a in arrays]}")
        bad = ~np.isfinite(np.stack(arrays)).all(axis=0) | (arrays[0] <= 0)
        if bad.any():
            raise ValueError(f"{key}.minutes must be finite and > 0 min with finite speed, "
                             f"load and temperature; block {int(np.argmax(bad))} is not")


@dataclass(frozen=True)
class DutyRange:
    """The duty the model was trained on: (low, high) of input speed [rpm], acting load
    [N m] and grease temperature [°C] (e.g. :meth:`of` the training lives' windows)."""

    n_in_rpm: tuple[float, float]
    t_acting_nm: tuple[float, float]
    temp_c: tuple[float, float]

    @classmethod
    def of(cls, duty: Duty) -> DutyRange:
        """The range a duty spans (absolute speed and load)."""
        def span(a: np.ndarray) -> tuple[float, float]:
            return float(np.min(a)), float(np.max(a))
        return cls(span(np.abs(duty.n_in_rpm)), span(np.abs(duty.t_acting_nm)),
                   span(duty.temp_c))

    def check(self, duty: Duty, key: str) -> None:
        """Refuse a duty outside this range, one line naming ``<key>.<quantity>``."""
        units = {"n_in_rpm": "rpm", "t_acting_nm": "N m", "temp_c": "°C"}
        for name, unit in units.items():
            lo, hi = getattr(self, name)
            a = np.asarray(getattr(duty, name), float)
            a = a if name == "temp_c" else np.abs(a)
            worst = float(a[np.argmax(np.maximum(lo - a, a - hi))])
            check_range(worst, lo, hi, f"{key}.{name}", unit,
                        why="the duty the model was trained on")


@dataclass(frozen=True, eq=False)
class Track:
    """The monitor's severity estimates of one fault since its alarm.

    Attributes
    ----------
    hours : ndarray, shape (n,)
        Operating hour of each estimate, non-decreasing [h].
    severity, lo, hi : ndarray, shape (n,)
        The estimate and its 90 % interval [-] (:meth:`DiagnosisModel.estimate
        <learn.monitor.model.DiagnosisModel.estimate>`).
    """

    hours: np.ndarray
    severity: np.ndarray
    lo: np.ndarray
    hi: np.ndarray


@dataclass(frozen=True)
class Prognosis:
    """A prognosis at ``hour`` (the last estimate's) for ``fault``.

    Attributes
    ----------
    hour : float
        Operating hour of the prognosis [h].
    fault, method : str
        The named fault; ``growth``, ``linear`` or ``wiener``.
    valid : bool
        False before enough track (then every figure NaN and ``reason`` says why).
    reason : str
        "" or "prognosis not yet valid: ...".
    severity_now, threshold : float
        The last estimate and the failure severity [-].
    remaining_h_median, remaining_h_q05, remaining_h_q95 : float
        Quantiles of the remaining operating hours to the threshold [h] (inf: beyond
        ``PrognosisConfig.horizon_h``).
    failure_hour_median, failure_hour_q05, failure_hour_q95 : float
        The same as operating hours, ``hour`` + remaining [h].
    """

    hour: float
    fault: str
    method: str
    valid: bool
    reason: str
    severity_now: float
    threshold: float
    remaining_h_median: float = float("nan")
    remaining_h_q05: float = float("nan")
    remaining_h_q95: float = float("nan")
    failure_hour_median: float = float("nan")
    failure_hour_q05: float = float("nan")
    failure_hour_q95: float = float("nan")


# ------------------------------------------------------------------ inputs and refusals
def check_track(track: Track, fault: str, alarm_hour: float | None, threshold: float | None,
                cfg: PrognosisConfig) -> tuple[np.ndarray, ...]:
    """The track's hours, severity, lo, hi (each shape (n,)) and the threshold [-], after
    every refusal of a prognosis's inputs.

    Raises
    ------
    ValueError
        In one line naming the key: a fault without a growth law, no alarm (None), a
        malformed track, an estimate before the alarm hour, a threshold at or below the
        last estimate or beyond the fault's severity range.
    """
    if not any(fault in fs for fs in LAWS.values()):
        raise ValueError(f"prognosis.fault={fault} has no growth law; allowed: "
                         f"{sorted(f for fs in LAWS.values() for f in fs)}")
    if alarm_hour is None:
        raise ValueError("prognosis.alarm_hour: no alarm, no prognosis (it starts at the "
                         "alarm that named the fault)")
    check_range(alarm_hour, 0.0, np.inf, "prognosis.alarm_hour", "h")
    h, y, lo, hi = (np.asarray(a, float) for a in (track.hours, track.severity, track.lo,
                                                   track.hi))
    if h.ndim != 1 or h.size == 0 or any(a.shape != h.shape for a in (y, lo, hi)):
        raise ValueError("prognosis.track: hours, severity, lo and hi must be 1-D of one "
                         f"length >= 1, got shapes {[a.shape for a in (h, y, lo, hi)]}")
    if not np.isfinite(np.stack([h, y, lo, hi])).all() or np.any(np.diff(h) < 0) \
            or np.any(hi - lo <= 0):
        raise ValueError("prognosis.track must be finite, its hours non-decreasing and "
                         "each interval hi > lo")
    check_range(h.min(), alarm_hour, np.inf, "prognosis.track.hours", "h",
                why="no estimate before the alarm hour")
    thr = cfg.threshold(fault) if threshold is None else threshold
    key = "prognosis.to_failure.failure" if threshold is None else "prognosis.threshold"
    check_range(thr, y[-1], get_fault(fault).severity_range[1], key,
                lo_open=True, why=f"above the current severity, within {fault}'s range")
    return h, y, lo, hi, float(thr)


def not_yet_valid(h: np.ndarray, cfg: PrognosisConfig, alarm_hour: float) -> str:
    """Why the track (estimate hours ``h``, shape (n,)) is too short for a prediction
    (``cfg.min_track_h``, ``cfg.min_estimates``), or ""."""
    span = float(h[-1] - alarm_hour)
    if span < cfg.min_track_h or h.size < cfg.min_estimates:
        return (f"prognosis not yet valid: {span:.2f} h and {h.size} estimates since the "
                f"alarm, {cfg.min_track_h:g} h and {cfg.min_estimates} needed")
    return ""


def from_samples(hour: float, fault: str, method: str, now: float, thr: float,
                 remaining: np.ndarray, cfg: PrognosisConfig) -> Prognosis:
    """The valid prognosis from samples of the remaining hours (shape (N,), [h]), beyond
    ``cfg.horizon_h`` inf, its interval's log half-widths about the median times
    ``cfg.interval_scale``."""
    r = np.where(remaining > cfg.horizon_h, np.inf, np.maximum(remaining, 0.0))
    q05, med, q95 = np.quantile(r, [0.05, 0.5, 0.95], method="inverted_cdf")  # inf-safe
    if cfg.interval_scale != 1.0 and 0 < med < np.inf:
        k = cfg.interval_scale
        q05 = med * (q05 / med) ** k if q05 > 0 else 0.0
        q95 = med * (q95 / med) ** k
    q05, med, q95 = (float(q) for q in (q05, med, q95))
    return Prognosis(hour, fault, method, True, "", now, thr, med, q05, q95,
                     hour + med, hour + q05, hour + q95)


def not_valid(hour: float, fault: str, method: str, now: float, thr: float,
              reason: str) -> Prognosis:
    """The prognosis "not yet valid" at ``hour`` for ``reason`` (every figure NaN)."""
    return Prognosis(hour, fault, method, False, reason, now, thr)


# ------------------------------------------------------------------ the growth law
#: Smallest severity mapped to Paris' u (the start of u0's fit, the threshold) (1e-3:
#: 2 µm of a root crack) [choice: a mean estimate at or below 0 says "small", and u =
#: (severity d1)^(1 − m/2) has no value there].
SEVERITY_FLOOR = 1e-3


def _law(fault: str) -> str:
    """The growth law of ``fault`` (a key of :data:`LAWS`)."""
    return next(g for g, fs in LAWS.items() if fault in fs)


def transformed(fault: str, severity: np.ndarray, tf: RunToFailure) -> tuple[np.ndarray, float]:
    """The severity in which the fault's law is a straight line in the exposure.

    Parameters
    ----------
    fault : str
        A fault of :data:`swgsim.datasets.growth.LAWS`.
    severity : ndarray, shape (n,)
        Severity [-] (a crack's floored at :data:`SEVERITY_FLOOR`).
    tf : RunToFailure
        The law's constants.

    Returns
    -------
    u : ndarray, shape (n,)
        Archard: the severity; Paris: (severity d1)^(1 − m/2), ln(severity d1) for m = 2
        (module docstring) [derived].
    b : float
        du/dX per unit scale: u = u0 + b s X [-/exposure].
    """
    sev = np.asarray(severity, float)
    d1 = DEPTH_AT_ONE_M[fault]
    if _law(fault) == "archard":
        return sev, 1.0 / d1
    a = np.maximum(sev, SEVERITY_FLOOR) * d1
    k = (tf.shape_factor * np.sqrt(np.pi)) ** tf.paris_m
    if tf.paris_m == 2.0:
        return np.log(a), float(k)
    e = 1.0 - tf.paris_m / 2.0
    return a ** e, float(e * k)


def exposure(fault: str, duty: Duty, tf: RunToFailure) -> np.ndarray:
    """The exposure at s = 1 after each block of a duty, cumulative, shape (K,).

    Paris: the damage sum D (:func:`swgsim.datasets.growth.paris_damage`, two load cycles
    per input revolution, Δσ = ``stress_mpa_per_nm`` |load|) [m^(1 − m/2)]; Archard: the
    worn depth (:func:`swgsim.datasets.growth.archard_depth`) [m].
    """
    minutes = np.asarray(duty.minutes, float)
    if _law(fault) == "paris":
        cycles = load_cycles(duty.n_in_rpm, 1.0) * minutes
        return paris_damage(cycles, tf.stress_mpa_per_nm * np.abs(duty.t_acting_nm),
                            tf.paris_c, tf.paris_m)
    revs = np.abs(np.asarray(duty.n_in_rpm, float)) * minutes
    return archard_depth(duty.t_acting_nm, revs, duty.temp_c, tf.wear_coeff_m_per_nm_rev,
                         tf.film_exponent)


def hours_for_exposure(need: np.ndarray, duty: Duty, cum: np.ndarray) -> np.ndarray:
    """Operating hours for a duty, repeated as a cycle from its start, to add exposure.

    Parameters
    ----------
    need : ndarray, shape (N,)
        Exposure to add at s = 1 (≤ 0: none) [as :func:`exposure`].
    duty : Duty
        The future duty, K blocks.
    cum : ndarray, shape (K,)
        :func:`exposure` of ``duty``.

    Returns
    -------
    ndarray, shape (N,)
        Hours [h]: 0 where nothing is needed, inf where the duty adds no exposure.
    """
    cum_e = np.concatenate([[0.0], cum])
    cum_h = np.concatenate([[0.0], np.cumsum(duty.minutes) / 60.0])
    per_cycle = cum_e[-1]
    need = np.where(np.isnan(need), np.inf, need)
    if per_cycle <= 0:
        return np.where(need > 0, np.inf, 0.0)
    finite = np.isfinite(need) & (need > 0)
    x = np.where(finite, need, 0.0)
    n = np.floor(x / per_cycle)
    rem = x - n * per_cycle
    i = np.clip(np.searchsorted(cum_e, rem, side="left"), 1, cum_e.size - 1)  # block of rem
    de = cum_e[i] - cum_e[i - 1]
    frac = np.divide(rem - cum_e[i - 1], de, out=np.zeros_like(rem), where=de > 0)
    t = n * cum_h[-1] + cum_h[i - 1] + np.clip(frac, 0.0, 1.0) * (cum_h[i] - cum_h[i - 1])
    return np.where(finite, t, np.where(need > 0, np.inf, 0.0))


def _track_exposure(fault: str, hours: np.ndarray, recorded: Duty, windows_h: np.ndarray,
                    tf: RunToFailure) -> np.ndarray:
    """Exposure since the first recorded window at each estimate hour, shape (n,): each
    window's own grows over its interval (linear within it)."""
    cum = exposure(fault, recorded, tf)
    xp = np.append(windows_h, windows_h[-1] + recorded.minutes[-1] / 60.0)
    return np.interp(hours, xp, np.concatenate([[0.0], cum]))


def severity_of(fault: str, u: np.ndarray, tf: RunToFailure) -> tuple[np.ndarray, np.ndarray]:
    """The inverse of :func:`transformed`: severity [-] and d(severity)/du at ``u`` (any
    shape, both of its shape); a crack grown without bound (u ≤ 0 for m > 2) is clipped
    at 10^3 [choice: far beyond any failure severity, its slope then 0]."""
    v = np.asarray(u, float)
    if _law(fault) == "archard":
        return v, np.ones_like(v)
    d1, m = DEPTH_AT_ONE_M[fault], tf.paris_m
    if m == 2.0:
        sev = np.exp(np.minimum(v, np.log(1e3 * d1))) / d1
        return sev, sev
    e = 1.0 - m / 2.0
    v_cap = (1e3 * d1) ** e  # u of severity 10^3
    vc = np.maximum(v, v_cap) if e < 0 else np.minimum(v, v_cap)
    sev = vc ** (1.0 / e) / d1
    return sev, np.where(vc == v, sev / (e * vc), 0.0)


def _grid_posterior(ls: np.ndarray, y: np.ndarray, w: np.ndarray, x: np.ndarray,
                    fault: str, tf: RunToFailure) -> tuple[np.ndarray, ...]:
    """Log posterior of ln s at grid ``ls`` (shape (G,)), u0's fit and precision there,
    each shape (G,); y, w = 1/σ², x: the estimates, shape (n,) (module docstring)."""
    u, b = transformed(fault, y, tf)
    beta = b * np.exp(ls)[:, None]  # (G, 1)
    early = slice(0, max(3, y.size // 4))  # the start: the first quarter's mean [choice]
    u0 = transformed(fault, np.array([w[early] @ y[early] / w[early].sum()]), tf)[0] \
        - beta[:, 0] * (w[early] @ x[early] / w[early].sum())
    for _ in range(GAUSS_NEWTON_STEPS):
        sev, jac = severity_of(fault, u0[:, None] + beta * x, tf)  # (G, n)
        wj = w * jac
        u0 = u0 + (wj * (y - sev)).sum(axis=1) / np.maximum((wj * jac).sum(axis=1), 1e-300)
    sev, jac = severity_of(fault, u0[:, None] + beta * x, tf)
    info = np.maximum((w * jac ** 2).sum(axis=1), 1e-300)
    prior_sd = max(tf.scatter, 1e-3)  # scatter 0: the scale known [choice]
    logp = -0.5 * (w * (y - sev) ** 2).sum(axis=1) - 0.5 * np.log(info) \
        - 0.5 * (ls / prior_sd) ** 2
    return logp - logp.max(), u0, info


def _posterior_draws(y: np.ndarray, w: np.ndarray, x: np.ndarray, fault: str,
                     cfg: PrognosisConfig, rng: np.random.Generator
                     ) -> tuple[np.ndarray, np.ndarray]:
    """Draws of (s, u0), shapes (N,) each: the grid posterior of ln s over
    ±``log_scale_span``, then again on ``n_grid`` points over where it exceeds e^-25 of its
    peak (a cell beyond each end) [choice: a precise track's posterior is narrower than a
    coarse cell], u0 given s normal about its fit (Laplace's method)."""
    ls = np.linspace(-cfg.log_scale_span, cfg.log_scale_span, cfg.n_grid)
    logp, _, _ = _grid_posterior(ls, y, w, x, fault, cfg.to_failure)
    keep = np.flatnonzero(logp > -25.0)
    cell = ls[1] - ls[0]
    ls = np.linspace(ls[keep[0]] - cell, ls[keep[-1]] + cell, cfg.n_grid)
    logp, u0, info = _grid_posterior(ls, y, w, x, fault, cfg.to_failure)
    p = np.exp(logp)
    pick = rng.choice(ls.size, size=cfg.n_samples, p=p / p.sum())
    s = np.exp(ls[pick] + (ls[1] - ls[0]) * (rng.random(cfg.n_samples) - 0.5))
    return s, u0[pick] + rng.standard_normal(cfg.n_samples) / np.sqrt(info[pick])


def predict_growth(track: Track, fault: str, alarm_hour: float | None, recorded: Duty,
                   windows_h: np.ndarray, cfg: PrognosisConfig | None = None, *,
                   planned: Duty | None = None, trained: DutyRange | None = None,
                   threshold: float | None = None, seed: int = 0) -> Prognosis:
    """The physics-based prognosis: the fault's growth law, its scale from the track.

    Parameters
    ----------
    track : Track
        The severity estimates since the alarm, n of them.
    fault : str
        The alarm's fault, one of :data:`swgsim.datasets.growth.LAWS`.
    alarm_hour : float or None
        Operating hour of the alarm that named it [h]; None: no alarm (refused).
    recorded : Duty
        The windows' duty since the alarm (:meth:`Duty.from_windows`), W blocks.
    windows_h : ndarray, shape (W,)
        The operating hour of each recorded window [h].
    cfg : PrognosisConfig or None
        None: the defaults.
    planned : Duty or None
        A duty the user declares for the future, repeated from its first block; None: the
        recorded one's mean exposure per hour [choice: the recorded windows' order need
        not be a whole number of the duty's cycles].
    trained : DutyRange or None
        The duty the model was trained on; a planned duty outside it is refused.
    threshold : float or None
        Failure severity [-]; None: ``cfg.threshold(fault)``.
    seed : int
        Seed of the Monte-Carlo draws (same seed, same prognosis).

    Returns
    -------
    Prognosis
        ``method`` "growth"; not valid before ``cfg.min_track_h`` and ``min_estimates``.

    Raises
    ------
    ValueError
        Before any work, in one line naming the key: no alarm, an estimate before the
        alarm, a fault without a growth law, a threshold at or below the current
        severity, a duty malformed or a planned one outside ``trained``, a bad config.
    """
    cfg = (cfg or PrognosisConfig()).check()
    h, y, lo, hi, thr = check_track(track, fault, alarm_hour, threshold, cfg)
    recorded.check("prognosis.recorded")
    wh = np.asarray(windows_h, float)
    if wh.shape != np.shape(recorded.minutes) or np.any(np.diff(wh) <= 0) \
            or not wh[0] <= h[0]:
        raise ValueError(f"prognosis.windows_h must be one increasing hour per recorded "
                         f"window ({np.shape(recorded.minutes)}), the first at or before "
                         f"the first estimate ({h[0]:g} h), got shape {wh.shape}")
    if planned is not None:
        planned.check("prognosis.planned")
        if trained is not None:
            trained.check(planned, "prognosis.planned")
    if reason := not_yet_valid(h, cfg, alarm_hour):
        return not_valid(float(h[-1]), fault, "growth", float(y[-1]), thr, reason)
    tf = cfg.to_failure
    w = ((2.0 * Z90) / (hi - lo)) ** 2  # 1/σ² of each estimate
    x = _track_exposure(fault, h, recorded, wh, tf)
    if y.size > cfg.max_bins:  # groups of consecutive estimates (PrognosisConfig.max_bins)
        first = np.unique(np.linspace(0, y.size, cfg.max_bins, endpoint=False).astype(int))
        wsum = np.add.reduceat(w, first)
        y, x = np.add.reduceat(w * y, first) / wsum, np.add.reduceat(w * x, first) / wsum
        w = wsum
    s, u0 = _posterior_draws(y, w, x, fault, cfg, np.random.default_rng(seed))
    u_fail, b = transformed(fault, np.array([thr]), tf)
    u_fail = float(u_fail[0])
    need = (u_fail - u0) / (b * s) - x[-1]  # exposure still to come at s = 1
    if planned is None:  # the recorded duty's mean rate: its cycle's phase is unknown
        rec = exposure(fault, recorded, tf)[-1] / (np.sum(recorded.minutes) / 60.0)
        remaining = np.where(need > 0, need / rec if rec > 0 else np.inf, 0.0)
    else:
        remaining = hours_for_exposure(need, planned, exposure(fault, planned, tf))
    return from_samples(float(h[-1]), fault, "growth", float(y[-1]), thr, remaining, cfg)
