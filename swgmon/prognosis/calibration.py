"""Calibration of the prognosis's interval (:mod:`.growth`) by conformal prediction across
lives, its lower and upper tails apart: split (one model, :func:`tail_scales`) or
cross-validated over gear folds (CV+, :func:`cv_plus_interval`)."""

from __future__ import annotations

import numpy as np

from swgmon.prognosis.growth import Prognosis
from swgsim.base.typed import check_range

__all__ = ["cv_plus_interval", "tail_scores", "tail_scales"]


def tail_scores(quantiles: np.ndarray, remaining_h: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Each prognosis's lower and upper score: how many of its lower log half-widths the
    true remaining life lies below the median, (ln m − ln r) / (ln m − ln q05), and how
    many upper ones above it, (ln r − ln m) / (ln q95 − ln m) (one of them negative).

    Parameters
    ----------
    quantiles : ndarray, shape (n, 3)
        Each prognosis's q05, median and q95 of the remaining hours, finite and > 0 [h].
    remaining_h : ndarray, shape (n,)
        The true remaining hours from each prognosis's hour [h] (floored at 1e-9 h).

    Returns
    -------
    (ndarray, ndarray)
        The lower and upper scores, shape (n,) each [-].
    """
    lq = np.log(np.asarray(quantiles, float).reshape(-1, 3))
    lt = np.log(np.maximum(np.asarray(remaining_h, float), 1e-9))
    return ((lq[:, 1] - lt) / np.maximum(lq[:, 1] - lq[:, 0], 1e-12),
            (lt - lq[:, 1]) / np.maximum(lq[:, 2] - lq[:, 1], 1e-12))


def tail_scales(prognoses: list[Prognosis], failure_hours: np.ndarray,
                coverage: float = 0.9, apart: bool = True) -> tuple[float, float]:
    """Split-conformal factors on the interval's lower and upper log half-widths.

    Each prognosis gives two scores: how many of its lower log half-widths the true
    remaining life lies below the median, (ln m − ln r) / (ln m − ln q05), and how many
    upper ones above it, (ln r − ln m) / (ln q95 − ln m) (one of them negative). Each
    factor is its scores' ⌈(n + 1)(1 + coverage)/2⌉-th smallest, so that each tail misses
    at most (1 − coverage)/2 and the interval covers at least ``coverage`` (conformalized
    quantile regression's tails calibrated apart: Romano, Patterson and Candès, NeurIPS
    2019, sec. 4; split conformal: Lei et al., JASA 113 (2018) 1094-1111). A factor below
    0 is taken as 0: the median stays inside. Calibrate across lives of the training
    gears, one prognosis per life (the lives are then exchangeable; windows of one life
    are not), never the held-out gear's; for a label-conditional interval, once per
    quarter of the true remaining share, on the prognoses of that quarter
    (:func:`~.inputs.calibrated_interval`).

    Parameters
    ----------
    prognoses : list of Prognosis
        Valid prognoses with finite, positive quantiles, made with factors 1.
    failure_hours : ndarray, shape (len(prognoses),)
        Each life's true failure hour [h].
    coverage : float
        Target coverage in (0, 1) (0.9: the 5-95 % interval).
    apart : bool
        True: the tails apart, which needs n >= 2/(1 − coverage) − 1 lives (19 at 0.9).
        False: one factor for both, the ⌈(n + 1) coverage⌉-th smallest of each
        prognosis's larger score (n >= 9 at 0.9): where too few lives hold the tails
        apart.

    Returns
    -------
    (float, float)
        ``PrognosisConfig.lower_scale`` and ``upper_scale`` [-], each >= 0 (equal when not
        ``apart``); inf when n is too small for ``coverage``.

    Raises
    ------
    ValueError
        Lengths differ, a prognosis not valid or without a finite interval, coverage out
        of range.
    """
    check_range(coverage, 0.0, 1.0, "prognosis.conformal.coverage", lo_open=True,
                hi_open=True)
    truth = np.asarray(failure_hours, float)
    if truth.shape != (len(prognoses),):
        raise ValueError(f"prognosis.conformal.failure_hours must have one hour per "
                         f"prognosis ({len(prognoses)}), got shape {truth.shape}")
    q = np.array([[p.remaining_h_q05, p.remaining_h_median, p.remaining_h_q95]
                  for p in prognoses], float).reshape(-1, 3)
    if not all(p.valid for p in prognoses) or not (np.isfinite(q).all() and (q > 0).all()):
        raise ValueError("prognosis.conformal.prognoses must be valid with finite, "
                         "positive quantiles")
    lower, upper = tail_scores(q, truth - np.array([p.hour for p in prognoses]))
    if not apart:
        rank = int(np.ceil((truth.size + 1) * coverage))
        k = float(np.sort(np.maximum(lower, upper))[rank - 1]) if rank <= truth.size \
            else float("inf")
        return max(k, 0.0), max(k, 0.0)
    rank = int(np.ceil((truth.size + 1) * (1.0 + coverage) / 2.0))
    if rank > truth.size:
        return float("inf"), float("inf")
    return (max(float(np.sort(lower)[rank - 1]), 0.0),
            max(float(np.sort(upper)[rank - 1]), 0.0))


def cv_plus_interval(raw: list[tuple[float, float, float] | None], scores: np.ndarray,
                     apart: bool, coverage: float = 0.9) -> tuple[float, float]:
    """One prognosis's interval by CV+ over gear folds: each calibration life's scores
    applied to the prognosis of the model fitted without that life's fold.

    Calibration life i of fold k(i) has scores (lᵢ, uᵢ) (:func:`tail_scores`, its
    prognosis read by the model without fold k(i)); the new prognosis read by that model
    has quantiles (q05ₖ, mₖ, q95ₖ). Its candidate ends are Lᵢ = exp(ln mₖ − lᵢ (ln mₖ −
    ln q05ₖ)) and Uᵢ = exp(ln mₖ + uᵢ (ln q95ₖ − ln mₖ)); the interval runs from the
    ⌊(n + 1)(1 − coverage)/2⌋-th smallest Lᵢ to the ⌈(n + 1)(1 + coverage)/2⌉-th smallest
    Uᵢ (tails apart), or, with one score for both tails (max(lᵢ, uᵢ)), from the
    ⌊(n + 1)(1 − coverage)⌋-th to the ⌈(n + 1) coverage⌉-th (Barber, Candès, Ramdas and
    Tibshirani, "Predictive inference with the jackknife+", Ann. Statist. 49 (2021)
    486-507, eqs. 6 and 10: CV+, coverage at least 1 − 2α over exchangeable folds; the
    jackknife+ with one gear a fold). A rank below 1 gives 0, above n inf. A fold whose
    model made no valid prognosis (or no finite positive median) gives its lives (0,
    inf), a q05 of 0 their L 0, an open q95 their U inf: the interval widens, never
    narrows, for it.

    Parameters
    ----------
    raw : list of (float, float, float) or None
        Per fold, its model's uncalibrated q05, median and q95 of the remaining hours
        [h]; None: no valid prognosis.
    scores : ndarray, shape (n, 3)
        Per calibration life: its fold's index into ``raw``, its lower and upper score.
    apart : bool
        The tails apart (n >= 19 at 0.9 gives finite ends) or one score for both.
    coverage : float
        Target coverage in (0, 1).

    Returns
    -------
    (float, float)
        The interval's ends [h] (0 and inf where too few lives).
    """
    sc = np.asarray(scores, float).reshape(-1, 3)
    n = sc.shape[0]
    q = np.array([r if r is not None else (np.nan,) * 3 for r in raw], float).reshape(-1, 3)
    q = q[sc[:, 0].astype(int)]
    med = np.isfinite(q[:, 1]) & (q[:, 1] > 0)
    ok_lo, ok_up = med & (q[:, 0] > 0), med & np.isfinite(q[:, 2])
    lq = np.log(np.where(np.isfinite(q) & (q > 0), q, 1.0))
    lo_s, up_s = sc[:, 1], sc[:, 2]
    if not apart:
        lo_s = up_s = np.maximum(lo_s, up_s)
    with np.errstate(over="ignore"):
        low = np.where(ok_lo, np.exp(lq[:, 1] - lo_s * (lq[:, 1] - lq[:, 0])), 0.0)
        up = np.where(ok_up, np.exp(lq[:, 1] + up_s * (lq[:, 2] - lq[:, 1])), np.inf)
    alpha = (1.0 - coverage) / (2.0 if apart else 1.0)
    k_lo, k_hi = int(np.floor((n + 1) * alpha + 1e-9)), int(np.ceil((n + 1) * (1 - alpha)
                                                                   - 1e-9))
    return (float(np.sort(low)[k_lo - 1]) if k_lo >= 1 else 0.0,
            float(np.sort(up)[k_hi - 1]) if k_hi <= n else float("inf"))
