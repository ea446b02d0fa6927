"""Scores of remaining-life predictions against the true failure, one short numpy function
each (the prognosis's evaluation: :mod:`swgmon.evaluation.prognosis_evaluation`).

Sources: A. Saxena, J. Celaya, B. Saha, S. Saha and K. Goebel, "Metrics for offline
evaluation of prognostic performance", International Journal of Prognostics and Health
Management 1 (2010) 001 (relative accuracy, the alpha-lambda performance, the prognostic
horizon; time normalised between the first prediction t_P and the end of life t_EoL);
A. Saxena, K. Goebel, D. Simon and N. Eklund, "Damage propagation modeling for aircraft
engine run-to-failure simulation", PHM 2008 (the PHM08 challenge's asymmetric score, its
13 and 10 in cycles, taken here in operating hours [choice]). The 90 % interval's coverage
and width are the usual prediction-interval coverage probability (PICP) and mean width.
"""

from __future__ import annotations

import numpy as np

from swgsim.base.typed import check_range

__all__ = ["PHM08_EARLY", "PHM08_LATE", "alpha_lambda", "at_lambda", "change_response",
           "interval_hit", "phm08_score", "prognostic_horizon", "relative_accuracy",
           "remaining_fraction", "share_bucket", "share_bucket_label", "share_buckets"]

#: a1 of the PHM08 score for early predictions (d < 0) and a2 for late ones [h] (13 and 10
#: cycles, Saxena et al. 2008; one operating hour for one cycle [choice]).
PHM08_EARLY, PHM08_LATE = 13.0, 10.0


def _same(true_h: np.ndarray, pred_h: np.ndarray, key: str) -> tuple[np.ndarray, np.ndarray]:
    t, p = np.asarray(true_h, float), np.asarray(pred_h, float)
    if t.shape != p.shape:
        raise ValueError(f"{key}: true and predicted must have one shape, got {t.shape} "
                         f"and {p.shape}")
    return t, p


def relative_accuracy(true_h: np.ndarray, pred_h: np.ndarray) -> np.ndarray:
    """Relative accuracy RA = 1 − abs(r* − r) / r* (Saxena et al. 2010, sec. 5.2).

    Parameters
    ----------
    true_h, pred_h : ndarray, shape (n,)
        True remaining hours r* (> 0) and the predicted (median) r [h].

    Returns
    -------
    ndarray, shape (n,)
        RA [-]: 1 for a perfect prediction, below 0 beyond twice off; −inf for an infinite
        prediction.

    Raises
    ------
    ValueError
        Shapes differ, or a true remaining life not > 0.
    """
    t, p = _same(true_h, pred_h, "relative_accuracy")
    if np.any(~(t > 0)):
        raise ValueError("relative_accuracy: the true remaining hours must be > 0")
    with np.errstate(invalid="ignore"):
        return np.where(np.isinf(p), -np.inf, 1.0 - np.abs(t - p) / t)


def alpha_lambda(true_h: np.ndarray, pred_h: np.ndarray, alpha: float = 0.2) -> np.ndarray:
    """Whether each prediction lies in the alpha cone, abs(r − r*) <= alpha r* (Saxena
    et al. 2010, sec. 5.2: the alpha-lambda accuracy at t_λ; here the point prediction,
    the median, judged [choice: the interval's mass within the cone is not kept]).

    Parameters
    ----------
    true_h, pred_h : ndarray, shape (n,)
        True remaining hours r* (>= 0) and the predicted r [h].
    alpha : float
        Half-width of the cone as a share of r*, in (0, 1] (0.2: the issue's).

    Returns
    -------
    ndarray of bool, shape (n,)

    Raises
    ------
    ValueError
        Shapes differ, or alpha out of range.
    """
    check_range(alpha, 0.0, 1.0, "prognosis.scores.alpha", lo_open=True)
    t, p = _same(true_h, pred_h, "alpha_lambda")
    return np.abs(p - t) <= alpha * t


def phm08_score(true_h: np.ndarray, pred_h: np.ndarray) -> np.ndarray:
    """The PHM08 challenge's asymmetric score of each prediction, d = r − r*: exp(−d/13) − 1
    early (d < 0), exp(d/10) − 1 late (Saxena et al. 2008): a late prediction costs more.

    Parameters
    ----------
    true_h, pred_h : ndarray, shape (n,)
        True and predicted remaining hours [h].

    Returns
    -------
    ndarray, shape (n,)
        Score [-], 0 for a perfect prediction, >= 0 always; inf for an infinite one.

    Raises
    ------
    ValueError
        Shapes differ.
    """
    t, p = _same(true_h, pred_h, "phm08_score")
    d = p - t
    with np.errstate(over="ignore", invalid="ignore"):
        return np.where(d < 0, np.expm1(-d / PHM08_EARLY), np.expm1(d / PHM08_LATE))


def interval_hit(true_h: np.ndarray, lo_h: np.ndarray, hi_h: np.ndarray) -> np.ndarray:
    """Whether the true remaining hours lie in each interval [lo, hi] (the mean of it is the
    interval's coverage, PICP).

    Parameters
    ----------
    true_h, lo_h, hi_h : ndarray, shape (n,)
        True remaining hours and each interval's ends (hi may be inf) [h].

    Returns
    -------
    ndarray of bool, shape (n,)

    Raises
    ------
    ValueError
        Shapes differ.
    """
    t, lo = _same(true_h, lo_h, "interval_hit")
    _, hi = _same(true_h, hi_h, "interval_hit")
    return (lo <= t) & (t <= hi)


def remaining_fraction(hour: np.ndarray, start_h: np.ndarray, failure_h: np.ndarray
                       ) -> np.ndarray:
    """The share of a prognosis's span still to come, (t_EoL − t) / (t_EoL − t_start).

    Parameters
    ----------
    hour, start_h, failure_h : ndarray, shape (n,)
        Hour of each prediction, the start of its span (the alarm) and the true failure
        (t_EoL) [h]; failure after the start.

    Returns
    -------
    ndarray, shape (n,)
        [-]; 1 at the start, 0 at failure.
    """
    h, s, f = (np.asarray(x, float) for x in (hour, start_h, failure_h))
    return (f - h) / (f - s)


def share_buckets(count: int) -> list[str]:
    """The labels of ``count`` (>= 1) equal buckets of the remaining-life share, [lo, hi)
    and the last [lo, 1], e.g. ``[0.25, 0.5)`` (``PrognosisTargets.share_buckets``; 4:
    quarters)."""
    return [f"[{i / count:g}, {(i + 1) / count:g}{']' if i == count - 1 else ')'}"
            for i in range(count)]


def share_bucket(fraction: float | np.ndarray, count: int) -> np.ndarray:
    """The index of each remaining-life fraction's bucket (:func:`share_buckets`), the
    last holding 1; -1 outside [0, 1]. Shape as ``fraction``."""
    f = np.asarray(fraction, float)
    k = np.minimum(np.floor(f * count), count - 1).astype(int)
    return np.where((f >= 0) & (f <= 1), k, -1)


def share_bucket_label(fraction: np.ndarray, count: int) -> np.ndarray:
    """The label of each remaining-life fraction's bucket (:func:`share_buckets`, of
    ``count``); empty outside [0, 1]. Shape as ``fraction``, str."""
    return np.array([*share_buckets(count), ""], dtype=object)[share_bucket(fraction, count)]


def prognostic_horizon(hour: np.ndarray, true_h: np.ndarray, pred_h: np.ndarray,
                       failure_h: float, alpha: float = 0.2) -> float:
    """The prognostic horizon PH = t_EoL − t_i (Saxena et al. 2010, sec. 5.1): t_i the first
    prediction from which every later one lies within ± alpha (t_EoL − t_P) of the true
    remaining life, t_P the first prediction [choice: the band on the prognosis's span, not
    on the whole life from hour 0 (commissioning is no part of a fault's life); "every
    later one" is stricter than the paper's first entry into the band].

    Parameters
    ----------
    hour, true_h, pred_h : ndarray, shape (n,)
        Hours of one life's predictions (increasing), the true and the predicted remaining
        hours [h].
    failure_h : float
        The true failure hour t_EoL [h].
    alpha : float
        The band's half-width as a share of t_EoL − t_P, in (0, 1].

    Returns
    -------
    float
        PH [h]; 0 where the last prediction is outside the band or there is none.

    Raises
    ------
    ValueError
        Shapes differ, hours not increasing, alpha out of range.
    """
    check_range(alpha, 0.0, 1.0, "prognosis.scores.alpha", lo_open=True)
    h = np.asarray(hour, float)
    t, p = _same(true_h, pred_h, "prognostic_horizon")
    if h.shape != t.shape or np.any(np.diff(h) <= 0):
        raise ValueError("prognostic_horizon: hour must be increasing, one per prediction")
    if h.size == 0:
        return 0.0
    inside = np.abs(p - t) <= alpha * (failure_h - h[0])
    out = np.flatnonzero(~inside)
    first = 0 if out.size == 0 else out[-1] + 1
    return 0.0 if first >= h.size else float(failure_h - h[first])


def at_lambda(hour: np.ndarray, failure_h: float, lam: float = 0.5) -> int | None:
    """The prediction judged at t_λ = t_P + λ (t_EoL − t_P) (Saxena et al. 2010, sec. 5.2;
    t_P the first prediction): the last one at or before t_λ [choice].

    Parameters
    ----------
    hour : ndarray, shape (n,)
        Hours of one life's predictions, increasing [h].
    failure_h : float
        The true failure hour t_EoL [h].
    lam : float
        λ, in [0, 1] (0.5: half-way).

    Returns
    -------
    int or None
        Its index; None without predictions or with the first at or after failure.

    Raises
    ------
    ValueError
        λ out of range.
    """
    check_range(lam, 0.0, 1.0, "prognosis.scores.lam")
    h = np.asarray(hour, float)
    if h.size == 0 or h[0] >= failure_h:
        return None
    t_lam = h[0] + lam * (failure_h - h[0])
    return int(np.searchsorted(h, t_lam, side="right")) - 1


def change_response(hour: np.ndarray, changed_h: np.ndarray, twin_h: np.ndarray,
                    change_h: float, law_sign: float, within_h: float = 24.0
                    ) -> tuple[bool | None, float]:
    """Whether the predicted failure moved the way the growth law says after a change of
    duty: one life with the change against its twin without it (the same gear, seed and
    onset), paired prognoses at the same hours [choice: against the twin, so that what the
    track would have done anyway cancels].

    Parameters
    ----------
    hour : ndarray, shape (n,)
        Hours of the paired prognoses, increasing, both valid [h].
    changed_h, twin_h : ndarray, shape (n,)
        The predicted failure hour (median) of the life with the change and of its twin [h].
    change_h : float
        Operating hour of the change [h].
    law_sign : float
        The sign of the change of the failure hour the law implies: -1 for a heavier
        payload or a hotter joint (earlier), +1 for a lighter or cooler one.
    within_h : float
        Hours after the change within which the prediction must have moved, > 0 [h] (24,
        issue 47).

    Returns
    -------
    moved : bool or None
        The last paired prognosis up to ``within_h`` after the change lies on the law's
        side of the twin's (strictly); None without a paired prognosis after the change.
    lag_h : float
        Hours from the change to the first paired prognosis from which every later one up to
        ``within_h`` lies on that side; NaN where ``moved`` is not True.

    Raises
    ------
    ValueError
        Shapes differ, hours not increasing, ``law_sign`` not ±1, ``within_h`` not positive.
    """
    check_range(within_h, 0.0, np.inf, "prognosis.scores.within_h", lo_open=True)
    if law_sign not in (-1.0, 1.0):
        raise ValueError(f"prognosis.scores.law_sign must be -1 or 1, got {law_sign}")
    h, a, b = (np.asarray(x, float) for x in (hour, changed_h, twin_h))
    if a.shape != b.shape:
        raise ValueError(f"change_response: the changed life's and the twin's predictions "
                         f"must have one shape, got {a.shape} and {b.shape}")
    if h.shape != a.shape or np.any(np.diff(h) <= 0):
        raise ValueError("change_response: hour must be increasing, one per prognosis")
    after = (h > change_h) & (h <= change_h + within_h)
    if not after.any():
        return None, float("nan")
    right = law_sign * (a[after] - b[after]) > 0
    if not right[-1]:
        return False, float("nan")
    wrong = np.flatnonzero(~right)
    first = 0 if wrong.size == 0 else wrong[-1] + 1
    return True, float(h[after][first] - change_h)
