"""Calibration of the prognosis's interval (:mod:`.growth`) by split conformal prediction
across lives, its lower and upper tails apart."""

from __future__ import annotations

import numpy as np

from swgmon.prognosis.growth import Prognosis
from swgsim.base.typed import check_range

__all__ = ["tail_scales"]


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
    left = truth - np.array([p.hour for p in prognoses])
    lq = np.log(q)
    lt = np.log(np.maximum(left, 1e-9))
    lower = (lq[:, 1] - lt) / np.maximum(lq[:, 1] - lq[:, 0], 1e-12)
    upper = (lt - lq[:, 1]) / np.maximum(lq[:, 2] - lq[:, 1], 1e-12)
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
