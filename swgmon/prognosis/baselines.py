"""Baselines of the prognosis (:mod:`.growth`) on the same inputs, blind
to the duty: a straight line of severity in operating hours (:func:`predict_linear`) and a
Wiener process with drift in operating hours without a load covariate
(:func:`predict_wiener`)."""

from __future__ import annotations

import numpy as np

from swgmon.prognosis.growth import (
    Z90,
    Prognosis,
    PrognosisConfig,
    Track,
    check_track,
    from_samples,
    not_valid,
    not_yet_valid,
)
from swgsim.base.typed import check_range

__all__ = ["predict_linear", "predict_wiener"]


def predict_linear(track: Track, fault: str, alarm_hour: float | None,
                   cfg: PrognosisConfig | None = None, *, threshold: float | None = None,
                   seed: int = 0) -> Prognosis:
    """Baseline: a straight line of severity in operating hours, extrapolated.

    The line is a weighted least-squares fit (weights from the 90 % intervals, as
    :func:`predict_growth`); its Gaussian posterior is sampled, a draw that does not rise
    never fails (inf). Blind to the duty. Parameters, returns and raises as
    :func:`predict_growth` (``method`` "linear").
    """
    cfg = (cfg or PrognosisConfig()).check()
    h, y, lo, hi, thr = check_track(track, fault, alarm_hour, threshold, cfg)
    if reason := not_yet_valid(h, cfg, alarm_hour):
        return not_valid(float(h[-1]), fault, "linear", float(y[-1]), thr, reason)
    w = ((2.0 * Z90) / (hi - lo)) ** 2
    t = h - h[-1]  # the intercept is the level now
    a = np.stack([np.ones_like(t), t], axis=1)  # (n, 2)
    cov = np.linalg.pinv(a.T @ (w[:, None] * a))
    coef = cov @ (a.T @ (w * y))
    draws = np.random.default_rng(seed).multivariate_normal(coef, cov, cfg.n_samples)
    level, slope = draws[:, 0], draws[:, 1]
    remaining = np.where(slope > 0, (thr - level) / np.where(slope > 0, slope, 1.0), np.inf)
    return from_samples(float(h[-1]), fault, "linear", float(y[-1]), thr, remaining, cfg,
                        alarm_hour)


def predict_wiener(track: Track, fault: str, alarm_hour: float | None,
                   cfg: PrognosisConfig | None = None, *, threshold: float | None = None,
                   bin_h: float = 1.0, seed: int = 0) -> Prognosis:
    """Baseline: a Wiener process with drift in operating hours, no load covariate.

    The estimates are averaged per ``bin_h`` operating hours since the alarm (in (0, 100]
    h; 1 h [choice]: fewer, less noisy steps); drift μ = the mean's rise per hour, σ² the
    steps' variance per hour about it; the remaining hours to a rise of d = threshold −
    the last bin's mean are inverse Gaussian, mean d/μ, shape d²/σ² [the first passage of
    a Wiener process with drift, e.g. Chhikara and Folks, "The Inverse Gaussian
    Distribution" (1989) [unverified: recalled]], sampled with :data:`scipy.stats.invgauss`.
    A drift ≤ 0 never fails (inf). Parameters, returns and raises as
    :func:`predict_growth` (``method`` "wiener").
    """
    from scipy.stats import invgauss

    cfg = (cfg or PrognosisConfig()).check()
    h, y, lo, hi, thr = check_track(track, fault, alarm_hour, threshold, cfg)
    check_range(bin_h, 0.0, 100.0, "prognosis.wiener.bin_h", "h", lo_open=True)
    if reason := not_yet_valid(h, cfg, alarm_hour):
        return not_valid(float(h[-1]), fault, "wiener", float(y[-1]), thr, reason)
    k = np.floor((h - alarm_hour) / bin_h).astype(int)
    _, first, count = np.unique(k, return_index=True, return_counts=True)
    tm = np.add.reduceat(h, first) / count
    ym = np.add.reduceat(y, first) / count
    n = cfg.n_samples
    if tm.size < 3:
        return not_valid(float(h[-1]), fault, "wiener", float(y[-1]), thr,
                        f"prognosis not yet valid: {tm.size} bins of {bin_h:g} h, 3 needed")
    dt, dy = np.diff(tm), np.diff(ym)
    mu = dy.sum() / dt.sum()
    var = max(float(np.mean((dy - mu * dt) ** 2 / dt)), 1e-12)
    d = thr - ym[-1]
    if mu <= 0:
        remaining = np.full(n, np.inf)
    elif d <= 0:
        remaining = np.zeros(n)
    else:
        shape = d ** 2 / var
        remaining = invgauss(mu=(d / mu) / shape, scale=shape).rvs(
            size=n, random_state=np.random.default_rng(seed))
    return from_samples(float(h[-1]), fault, "wiener", float(y[-1]), thr, remaining, cfg,
                        alarm_hour)
