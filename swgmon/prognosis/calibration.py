"""Calibration of the prognosis's interval (:mod:`.growth`) by split
conformal prediction across lives."""

from __future__ import annotations

import numpy as np

from swgmon.prognosis.growth import Prognosis
from swgsim.base.typed import check_range

__all__ = ["conformal_interval_scale"]


def conformal_interval_scale(prognoses: list[Prognosis], failure_hours: np.ndarray,
                             coverage: float = 0.9) -> float:
    """Split-conformal factor on the interval's log half-widths about the median.

    Each score is how many of its log half-widths the true failure lies from the median
    (the lower one below it, the upper above); the factor is the scores'
    ⌈(n + 1) coverage⌉-th smallest [split conformal, Lei et al., "Distribution-free
    predictive inference for regression", JASA 113 (2018) 1094-1111 [unverified:
    recalled]]. Calibrate across lives of the training gears, one prognosis per life (the
    lives are then exchangeable; windows of one life are not), never the held-out gear's.

    Parameters
    ----------
    prognoses : list of Prognosis
        Valid prognoses with finite, positive quantiles, made at ``interval_scale`` 1.
    failure_hours : ndarray, shape (len(prognoses),)
        Each life's true failure hour [h].
    coverage : float
        Target coverage in (0, 1) (0.9: the 5-95 % interval).

    Returns
    -------
    float
        ``PrognosisConfig.interval_scale`` [-]; inf when n is too small for ``coverage``.

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
    score = np.where(lt < lq[:, 1], (lq[:, 1] - lt) / (lq[:, 1] - lq[:, 0]),
                     (lt - lq[:, 1]) / (lq[:, 2] - lq[:, 1]))
    rank = int(np.ceil((score.size + 1) * coverage))
    return float(np.sort(score)[rank - 1]) if rank <= score.size else float("inf")
