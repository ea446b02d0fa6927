"""The inputs and outputs of the prognosis after an alarm (:mod:`.growth`): its config,
the duty, the severity track, the prognosis, and the refusals of the inputs and the
prognosis made from Monte-Carlo samples that every predictor shares
(:mod:`.baselines`)."""

from __future__ import annotations

import dataclasses
import numbers
from dataclasses import dataclass, field

import numpy as np

from swgsim.base.typed import check_range
from swgsim.datasets.growth import LAWS, RunToFailure, check_to_failure
from swgsim.datasets.schedule import LifeConfig
from swgsim.gear.faults import get_fault

__all__ = ["LONE_WINDOW_H", "Duty", "DutyRange", "Prognosis", "PrognosisConfig", "Track",
           "calibrated_interval", "check_track", "from_samples", "not_valid",
           "not_yet_valid", "scaled_interval", "share_hull"]


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
    lower_scale, upper_scale : tuple of float
        Factors on the interval's lower and upper log half-widths about the median, each
        in [0, 20] [-], calibrated apart (CQR-style, :func:`~.calibration.tail_scales`):
        one pair for every prognosis, or one per equal bucket of the *true* remaining
        share, as many as 20 (:func:`~.scores.share_buckets`; label-conditional,
        :func:`calibrated_interval`).
        (1,), (1,): the posterior's own interval.
    max_correlation : float
        Largest lag-1 autocorrelation of the estimates' errors the fit takes, in [0, 0.99]
        [-] (0.95 [choice]: an effective sample size of at least n/39); 0: the estimates
        taken as independent (:func:`.growth.residual_correlation`).
    in_sight_h : float
        Remaining hours beyond which a sample counts as "no failure in sight" (inf), in
        (0, 10^7] [h] (10^6 [choice]).
    max_bins : int
        Most groups of consecutive estimates the fit sees, in [8, 10^5] (256 [choice]): a
        longer track is fitted on each group's inverse-variance weighted mean severity and
        mean exposure, their weight the group's sum (exact for a law straight within a
        group; a 100 h track then costs what 256 estimates cost).
    severity_floor : float
        Smallest severity mapped to Paris' u (the start of u0's fit, the threshold), in
        (0, 0.1] [-] (1e-3: 2 µm of a root crack [choice: a mean estimate at or below 0
        says "small", and u = (severity d1)^(1 − m/2) has no value there]).
    gauss_newton_steps : int
        Gauss-Newton steps of u0's fit at each grid point of ln s, in [1, 100] (6
        [choice]: from the first quarter's mean, 3, 6 and 12 steps gave the same quantiles
        to 1e-13 on synthetic root crack and wear tracks as in tests/learn/test_prognosis.py).
    paris_m_sd : float
        σ of the normal prior on a crack's Paris m about ``to_failure.paris_m``, in
        [0, 2] [-]; 0 (default): m known (:func:`.growth._paris_laws`). 0.5 [choice:
        steels' m spans about 2-4, Barsom and Rolfe [unverified: recalled]] learns m
        from the track's curvature, at about 5 times the cost; not the default while
        the monitor's estimates bend the track (docs/monitor/prognosis.md, "Paris' m
        learnt").
    paris_m_points : int
        Points of m's grid over the prior's ±2σ, in [1, 41] (9 [choice]: a step of σ/2).
    failure_ratios : tuple of float
        Severities at which earlier gears of the lot failed, over the threshold, each in
        (0, 10] [-] (a teardown's record of failed units); each Monte-Carlo sample fails
        at the threshold times one of them drawn at random among those above the last
        estimate (the gear has not failed yet: the empirical distribution conditioned on
        survival, Meeker and Escobar, *Statistical Methods for Reliability Data*, 1998,
        sec. 3.5 [unverified: recalled]). Empty (default): the threshold is the failure.
    to_failure : RunToFailure
        The growth's constants (:class:`swgsim.datasets.growth.RunToFailure`): the laws'
        m (a crack's the prior's mean), Y, Δσ per N m, film exponent, the median C and
        wear coefficient (s = 1), the per-gear scatter (the prior σ of ln s) and the
        failure severities.
    """

    min_track_h: float = 2.0
    min_estimates: int = 10
    n_samples: int = 4000
    n_grid: int = 401
    log_scale_span: float = 5.0
    lower_scale: tuple[float, ...] = (1.0,)
    upper_scale: tuple[float, ...] = (1.0,)
    max_correlation: float = 0.95
    in_sight_h: float = 1e6
    max_bins: int = 256
    severity_floor: float = 1e-3
    gauss_newton_steps: int = 6
    paris_m_sd: float = 0.0
    paris_m_points: int = 9
    failure_ratios: tuple[float, ...] = ()
    to_failure: RunToFailure = field(default_factory=RunToFailure)

    def check(self, where: str = "prognosis") -> PrognosisConfig:
        """Refuse a field out of range in one line naming ``<where>.<field>`` (the fault's
        own range of ``failure``: :func:`check_track`); return self.

        Parameters
        ----------
        where : str
            Full name of the config for messages (``prognosis``,
            ``prognosis.study.prognosis``).

        Returns
        -------
        PrognosisConfig
            ``self``.

        Raises
        ------
        ValueError
            A field outside its range (the ranges in the attributes above).
        """
        for name, lo, hi in (("min_estimates", 3, 1e6), ("n_samples", 100, 1e6),
                             ("n_grid", 21, 10001), ("max_bins", 8, 1e5),
                             ("gauss_newton_steps", 1, 100), ("paris_m_points", 1, 41)):
            v = getattr(self, name)
            if isinstance(v, bool) or not isinstance(v, numbers.Integral):  # 1000.5, True
                raise ValueError(f"{where}.{name} must be an integer, got {v!r}")
            check_range(v, lo, hi, f"{where}.{name}")
        check_range(self.min_track_h, 0.0, 1000.0, f"{where}.min_track_h", "h", lo_open=True)
        check_range(self.log_scale_span, 0.0, 10.0, f"{where}.log_scale_span", lo_open=True)
        check_range(self.max_correlation, 0.0, 0.99, f"{where}.max_correlation")
        check_range(self.paris_m_sd, 0.0, 2.0, f"{where}.paris_m_sd")
        for name in ("lower_scale", "upper_scale"):
            k = getattr(self, name)
            if isinstance(k, (str, bytes)) or not isinstance(k, (tuple, list)) \
                    or not 1 <= len(k) <= 20 or len(k) != len(self.lower_scale):
                raise ValueError(f"{where}.{name} must be a list of 1 to 20 factors (one "
                                 f"per equal bucket of the true remaining share), as many "
                                 f"as lower_scale; got {k!r}")
            for i, v in enumerate(k):
                check_range(v, 0.0, 20.0, f"{where}.{name}[{i}]")
        check_range(self.in_sight_h, 0.0, 1e7, f"{where}.in_sight_h", "h", lo_open=True)
        if isinstance(self.failure_ratios, (str, bytes)) \
                or not isinstance(self.failure_ratios, (tuple, list)):
            raise ValueError(f"{where}.failure_ratios must be a list of ratios, got "
                             f"{self.failure_ratios!r}")
        for i, v in enumerate(self.failure_ratios):
            check_range(v, 0.0, 10.0, f"{where}.failure_ratios[{i}]", lo_open=True)
        check_range(self.severity_floor, 0.0, 0.1, f"{where}.severity_floor", lo_open=True)
        unset = dataclasses.replace(self.to_failure, failure=None)
        for law, faults in LAWS.items():
            for fault in faults:  # the onset's severity is not the prognosis's: any > 0
                check_to_failure(unset, fault, law, 1e-9, where)
        if self.to_failure.failure is not None:
            top = max(get_fault(f).severity_range[1] for fs in LAWS.values() for f in fs)
            check_range(self.to_failure.failure, 0.0, top, f"{where}.to_failure.failure",
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
        """The duty of recorded windows, each holding until the next.

        Parameters
        ----------
        hours : ndarray, shape (W,)
            Operating hour of each window, increasing [h].
        n_in_rpm, t_acting_nm, temp_c : ndarray, shape (W,)
            Each window's input speed [rpm], acting load [N m], grease temperature [°C].

        Returns
        -------
        Duty
            W blocks; the last for the median interval [choice], a lone one for
            :data:`LONE_WINDOW_H`.
        """
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

    def refuse_outside(self, duty: Duty, key: str) -> None:
        """Refuse a duty outside this range, one line naming ``<key>.<quantity>`` (not a
        config's ``check``: the range judges another object)."""
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
        <swgmon.assessment.model.DiagnosisModel.estimate>`).
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
        ``PrognosisConfig.in_sight_h``).
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
    """The track and the threshold after every refusal of a prognosis's inputs.

    Parameters
    ----------
    track : Track
        The severity estimates since the alarm, n of them.
    fault : str
        The alarm's fault, one of :data:`swgsim.datasets.growth.LAWS`.
    alarm_hour : float or None
        Operating hour of the alarm [h]; None: no alarm (refused).
    threshold : float or None
        Failure severity [-]; None: ``cfg.threshold(fault)`` (refused under the key
        ``prognosis.to_failure.failure``).
    cfg : PrognosisConfig

    Returns
    -------
    tuple of ndarray and float
        The track's hours [h], severity, lo, hi [-] (each shape (n,)) and the threshold [-].

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
    """Why a track is too short for a prediction, or "".

    Parameters
    ----------
    h : ndarray, shape (n,)
        The estimates' operating hours [h].
    cfg : PrognosisConfig
        Its ``min_track_h`` and ``min_estimates``.
    alarm_hour : float
        Operating hour of the alarm [h].

    Returns
    -------
    str
        "prognosis not yet valid: ..." with the hours and estimates had and needed, or "".
    """
    span = float(h[-1] - alarm_hour)
    if span < cfg.min_track_h or h.size < cfg.min_estimates:
        return (f"prognosis not yet valid: {span:.2f} h and {h.size} estimates since the "
                f"alarm, {cfg.min_track_h:g} h and {cfg.min_estimates} needed")
    return ""


def from_samples(hour: float, fault: str, method: str, now: float, thr: float,
                 remaining: np.ndarray, cfg: PrognosisConfig, alarm_hour: float
                 ) -> Prognosis:
    """The valid prognosis from samples of the remaining hours.

    Parameters
    ----------
    hour : float
        Operating hour of the prognosis [h].
    fault, method : str
        The named fault and the predictor's name.
    now, thr : float
        The last severity estimate and the failure severity [-].
    remaining : ndarray, shape (N,)
        Samples of the remaining operating hours [h]; beyond ``cfg.in_sight_h`` inf.
    cfg : PrognosisConfig
        Its ``in_sight_h``, ``lower_scale`` and ``upper_scale``.
    alarm_hour : float
        Operating hour of the alarm the prognosis follows [h] (its predicted share picks
        the interval scale).

    Returns
    -------
    Prognosis
        Median, and the 5 % and 95 % quantiles calibrated by ``cfg.lower_scale`` and
        ``cfg.upper_scale`` (:func:`calibrated_interval`).
    """
    r = np.where(remaining > cfg.in_sight_h, np.inf, np.maximum(remaining, 0.0))
    q05, med, q95 = np.quantile(r, [0.05, 0.5, 0.95], method="inverted_cdf")  # inf-safe
    q05, q95 = calibrated_interval(float(q05), float(med), float(q95), hour - alarm_hour,
                                   cfg.lower_scale, cfg.upper_scale)
    q05, med, q95 = (float(q) for q in (q05, med, q95))
    return Prognosis(hour, fault, method, True, "", now, thr, med, q05, q95,
                     hour + med, hour + q05, hour + q95)


def scaled_interval(q05: float, med: float, q95: float, lower: float, upper: float
                    ) -> tuple[float, float]:
    """The interval with its lower and upper log half-widths about the median times
    ``lower`` and ``upper`` [h] (unchanged where the median is 0 or inf)."""
    if not 0 < med < np.inf:
        return q05, q95
    return (med * (q05 / med) ** lower if q05 > 0 else 0.0), med * (q95 / med) ** upper


def calibrated_interval(q05: float, med: float, q95: float, elapsed_h: float,
                        lower: tuple[float, ...], upper: tuple[float, ...]
                        ) -> tuple[float, float]:
    """The prognosis's interval, calibrated conditional on the true remaining share.

    With one pair of factors, :func:`scaled_interval`. With one pair per bucket of
    :func:`~.scores.share_buckets` (as many as the factors), a remaining life r belongs to
    the set where it lies inside the interval scaled by the factors of *its own* bucket:
    its share r / (elapsed + r) is a known function of the candidate (label-conditional,
    "Mondrian" conformal prediction: Vovk, Gammerman and Shafer, "Algorithmic Learning in a
    Random World", Springer 2005, ch. 4.5; Sadinle, Lei and Wasserman, JASA 114 (2019)
    223-234). Bucket b holds r in [s0 e / (1 - s0), s1 e / (1 - s1)); the set is the union
    of each bucket's range cut by its scaled interval, returned as its hull. The median's
    bucket is never empty (factors >= 0 keep the median inside), so neither is the set.

    Parameters
    ----------
    q05, med, q95 : float
        The posterior's quantiles of the remaining hours [h] (q95 may be inf).
    elapsed_h : float
        Operating hours since the alarm the prognosis follows, >= 0 [h].
    lower, upper : tuple of float
        ``PrognosisConfig.lower_scale`` and ``upper_scale`` [-].

    Returns
    -------
    (float, float)
        The interval's ends [h].
    """
    if len(lower) == 1:
        return scaled_interval(q05, med, q95, lower[0], upper[0])
    return share_hull([scaled_interval(q05, med, q95, lo, hi)
                       for lo, hi in zip(lower, upper, strict=True)], elapsed_h)


def share_hull(intervals: list[tuple[float, float]], elapsed_h: float) -> tuple[float, float]:
    """The hull of the remaining lives r that lie inside the interval of their own bucket
    of the true remaining share (:func:`calibrated_interval`'s set).

    Parameters
    ----------
    intervals : list of (float, float)
        Per bucket of :func:`~.scores.share_buckets` (as many as given), the interval of
        the remaining hours calibrated on that bucket [h]; one at least must hold r in
        its own bucket (each holding the median does).
    elapsed_h : float
        Operating hours since the alarm the prognosis follows, >= 0 [h].

    Returns
    -------
    (float, float)
        The hull's ends [h].
    """
    e, k = max(float(elapsed_h), 0.0), len(intervals)
    ends = []
    for b, (lo, hi) in enumerate(intervals):
        s0, s1 = b / k, (b + 1) / k
        r0 = s0 * e / (1.0 - s0)
        r1 = np.inf if b == k - 1 else s1 * e / (1.0 - s1)
        if max(lo, r0) <= min(hi, r1):
            ends.append((max(lo, r0), min(hi, r1)))
    return min(a for a, _ in ends), max(z for _, z in ends)


def not_valid(hour: float, fault: str, method: str, now: float, thr: float,
              reason: str) -> Prognosis:
    """The prognosis "not yet valid".

    Parameters
    ----------
    hour : float
        Operating hour of the prognosis [h].
    fault, method : str
        The named fault and the predictor's name.
    now, thr : float
        The last severity estimate and the failure severity [-].
    reason : str
        Why (:func:`not_yet_valid`).

    Returns
    -------
    Prognosis
        ``valid`` False, every figure NaN.
    """
    return Prognosis(hour, fault, method, False, reason, now, thr)
