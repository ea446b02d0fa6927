"""Statistics a reader can trust, for a benchmark of lives (issue 83): every figure per
family and held-out gear instance, with its uncertainty from the lives themselves.

* :func:`alarm_share`: the share of healthy lives with any gear-fault alarm, with its
  Clopper-Pearson interval (an exact binomial interval: Clopper and Pearson 1934,
  Biometrika 26(4):404; scipy's ``binomtest(...).proportion_ci(method="exact")``).
* :func:`alarm_rate`: false alarms per 1000 h, pooled over the lives, with the worst single
  life beside it (a rate per 1000 h hides a storm in one life).
* :func:`conditional_delay`: the conditional average delay to detect, CADD = E[τ − ν | τ >=
  ν] over the faulty lives detected after their onset ν (Kenett and Pollak's conditional
  expected delay; Tartakovsky, Nikiforov and Basseville, *Sequential Analysis*, 2014,
  sec. 6.2), with a bootstrap interval over the lives.
* :func:`life_bootstrap`: a percentile bootstrap interval of a ratio of sums (e.g.
  prognosis coverage: covered prognoses over prognoses) that resamples whole lives (a
  cluster bootstrap: neighbouring windows of one life are not independent; Field and
  Welsh, JRSS B 69(3):369, 2007), through ``scipy.stats.bootstrap``.
* :func:`matched_threshold`: the threshold at which a statistic's alarms on healthy design
  lives come at a given rate per 1000 h, so that methods are compared at one false-alarm
  rate (matched ARL0: Montgomery, *Introduction to Statistical Quality Control*, 7th ed.,
  sec. 9.1, the in-control average run length).
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

__all__ = ["Interval", "alarm_rate", "alarm_share", "conditional_delay", "life_bootstrap",
           "matched_threshold", "upcrossings"]

@dataclass(frozen=True)
class Interval:
    """A figure with its interval (at the study's confidence level).

    Attributes
    ----------
    value : float
        The point estimate (NaN where there is nothing to estimate).
    low, high : float
        The interval's bounds (NaN where there is nothing to estimate).
    n : int
        Lives it rests on.
    """

    value: float
    low: float
    high: float
    n: int


def alarm_share(alarmed: Sequence[bool], *, level: float) -> Interval:
    """The share of lives with an alarm and its Clopper-Pearson interval.

    Parameters
    ----------
    alarmed : sequence of bool, shape (L,)
        Per life: whether it had any gear-fault alarm.
    level : float
        Two-sided confidence level, in (0, 1) (``BenchmarkConfig.level``).

    Returns
    -------
    Interval
        k / L and the exact binomial interval; NaN for no lives. With 0 of 20 the upper
        bound at level 0.95 is 1 − 0.025^(1/20) = 0.168.
    """
    from scipy.stats import binomtest

    a = np.asarray(alarmed, dtype=bool)
    if a.size == 0:
        return Interval(np.nan, np.nan, np.nan, 0)
    k = int(a.sum())
    ci = binomtest(k, int(a.size)).proportion_ci(confidence_level=level, method="exact")
    return Interval(k / a.size, float(ci.low), float(ci.high), int(a.size))


def alarm_rate(alarms: Sequence[int], hours: Sequence[float]) -> tuple[float, float, int]:
    """False alarms per 1000 h pooled over lives, and the worst single life's.

    Parameters
    ----------
    alarms : sequence of int, shape (L,)
        Alarms of each healthy life, >= 0.
    hours : sequence of float, shape (L,)
        Each life's monitored hours, > 0 [h].

    Returns
    -------
    pooled : float
        1000 Σ alarms / Σ hours [per 1000 h] (NaN for no lives).
    worst : float
        The largest single life's 1000 alarms / hours [per 1000 h] (NaN for no lives).
    worst_alarms : int
        That life's alarms.

    Raises
    ------
    ValueError
        Shapes that differ, negative alarms or hours that are not positive.
    """
    a, h = np.asarray(alarms, dtype=float), np.asarray(hours, dtype=float)
    if a.shape != h.shape or a.ndim != 1:
        raise ValueError(f"alarms and hours must share a shape (L,), got {a.shape}, {h.shape}")
    if a.size == 0:
        return np.nan, np.nan, 0
    if np.any(a < 0) or not np.all(h > 0):
        raise ValueError("alarms must be >= 0 and hours > 0")
    per = 1000.0 * a / h
    i = int(np.argmax(per))
    return float(1000.0 * a.sum() / h.sum()), float(per[i]), int(a[i])


def conditional_delay(delays_h: Sequence[float], n_boot: int = 2000, seed: int = 0, *,
                      level: float) -> Interval:
    """The conditional average delay to detect over the lives detected after onset, with a
    percentile bootstrap interval over those lives.

    Parameters
    ----------
    delays_h : sequence of float, shape (L,)
        Per faulty life: alarm hour minus onset hour [h]; NaN for a life never detected,
        negative for one whose first alarm came before the onset (neither enters).
    n_boot : int
        Bootstrap resamples, >= 100.
    seed : int
        Seed of the resampling.
    level : float
        Two-sided confidence level, in (0, 1) (``BenchmarkConfig.level``).

    Returns
    -------
    Interval
        Mean delay [h] of the lives with delay >= 0, its interval (NaN with fewer than two
        such lives), and their count.
    """
    d = np.asarray(delays_h, dtype=float)
    d = d[np.isfinite(d) & (d >= 0)]
    if d.size == 0:
        return Interval(np.nan, np.nan, np.nan, 0)
    if d.size < 2 or np.ptp(d) == 0:
        return Interval(float(d.mean()), float(d.mean()), float(d.mean()), int(d.size))
    lo, hi = _bootstrap((d,), lambda x, axis=-1: np.mean(x, axis=axis), n_boot, seed,
                        level=level)
    return Interval(float(d.mean()), lo, hi, int(d.size))


def life_bootstrap(numerator: Sequence[float], denominator: Sequence[float],
                   n_boot: int = 2000, seed: int = 0, *, level: float) -> Interval:
    """A ratio of sums over lives, Σ num / Σ den, with a percentile bootstrap interval
    that resamples whole lives.

    Parameters
    ----------
    numerator, denominator : sequence of float, shape (L,)
        Per life, e.g. its covered prognoses and its prognoses; denominators >= 0 with a
        positive sum.
    n_boot, seed : int
        See :func:`conditional_delay`.
    level : float
        Two-sided confidence level, in (0, 1) (``PrognosisTargets.level`` l, or 2 l − 1:
        each end a one-sided bound at l).

    Returns
    -------
    Interval
        The pooled ratio and its interval (the point itself with fewer than two lives).

    Raises
    ------
    ValueError
        Shapes that differ, a negative denominator or none positive.
    """
    num, den = np.asarray(numerator, dtype=float), np.asarray(denominator, dtype=float)
    if num.shape != den.shape or num.ndim != 1:
        raise ValueError(f"numerator and denominator must share a shape (L,), got "
                         f"{num.shape}, {den.shape}")
    if np.any(den < 0) or not den.sum() > 0:
        raise ValueError("denominator must be >= 0 with a positive sum")
    value = float(num.sum() / den.sum())
    if num.size < 2:
        return Interval(value, value, value, int(num.size))

    def ratio(a, b, axis=-1):
        with np.errstate(invalid="ignore", divide="ignore"):
            return np.sum(a, axis=axis) / np.sum(b, axis=axis)

    lo, hi = _bootstrap((num, den), ratio, n_boot, seed, paired=True, level=level)
    return Interval(value, lo, hi, int(num.size))


def _bootstrap(data: tuple, statistic, n_boot: int, seed: int,
               paired: bool = False, *, level: float) -> tuple[float, float]:
    """``scipy.stats.bootstrap``'s percentile interval at ``level``."""
    from scipy.stats import bootstrap

    if n_boot < 100:
        raise ValueError(f"n_boot must be >= 100, got {n_boot}")
    res = bootstrap(data, statistic, n_resamples=int(n_boot), confidence_level=level,
                    method="percentile", paired=paired, vectorized=True,
                    random_state=np.random.default_rng(int(seed)))
    return float(res.confidence_interval.low), float(res.confidence_interval.high)


def upcrossings(statistic: np.ndarray, threshold: float) -> int:
    """Alarms of a chart on one life: the times its statistic crosses the threshold from
    below (a first sample above it counts; NaN is below).

    Parameters
    ----------
    statistic : ndarray, shape (W,)
        The chart's statistic at each window.
    threshold : float

    Returns
    -------
    int
    """
    above = np.nan_to_num(np.asarray(statistic, dtype=float), nan=-np.inf) > threshold
    return int(above[0]) + int(np.sum(above[1:] & ~above[:-1])) if above.size else 0


def matched_threshold(statistics: Sequence[np.ndarray], hours: Sequence[float],
                      per_1000h: float) -> float:
    """A threshold at which the charts' alarms on healthy lives come at most at
    ``per_1000h`` per 1000 h (:func:`upcrossings`, pooled over the lives), found by
    bisection over the statistics' values. Upcrossings are nearly but not strictly
    monotone in the threshold (raising it can split one excursion in two), so it is the
    lowest such value where the count falls monotonically, as on a chart's tail.

    Parameters
    ----------
    statistics : sequence of ndarray, each shape (W_l,)
        A chart's statistic on each healthy (design) life.
    hours : sequence of float, shape (L,)
        Each life's monitored hours, > 0 [h].
    per_1000h : float
        The target rate, >= 0 [per 1000 h] (the monitor's, measured on the same lives).

    Returns
    -------
    float
        A threshold among the statistics' values (the largest finite value when even it
        alarms too often: no alarm is then possible at a lower rate).

    Raises
    ------
    ValueError
        No lives, lengths that differ, hours not positive, a negative target.
    """
    h = np.asarray(hours, dtype=float)
    if len(statistics) == 0 or len(statistics) != h.size or not np.all(h > 0):
        raise ValueError("statistics and hours must name the same lives, hours > 0")
    if not per_1000h >= 0:
        raise ValueError(f"per_1000h must be >= 0, got {per_1000h}")
    allowed = per_1000h * h.sum() / 1000.0
    values = np.unique(np.concatenate([np.asarray(s, float) for s in statistics]))
    values = values[np.isfinite(values)]
    lo, hi = 0, values.size - 1  # the alarm count falls as the threshold rises
    while lo < hi:  # smallest index whose count is within the allowance
        mid = (lo + hi) // 2
        if sum(upcrossings(s, values[mid]) for s in statistics) <= allowed:
            hi = mid
        else:
            lo = mid + 1
    return float(values[lo])
