"""Does an even change of friction explain an alarm? The hypothesis that keeps a
re-greasing nobody declared, or grease running in again, from being named a gear fault:
:func:`fit_friction` fits a factor on the friction (and a rate) to the windows since an
alarm (:class:`FrictionFit`); where it is significant and no gear fault's signature fits
better, the alarm is named :data:`~swgmon.detection.rule.UNEXPLAINED_CHANGE` with what moved.
Design: docs/monitor/assessment.md, "The monitor checks its temperature sensor" (a
recurring unexplained change) and docs/monitor.md, "The monitor".
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from swgmon.assessment.sensor_check import NamingConfig
from swgmon.detection.normal import Conditions, NormalBehaviour

#: Factors on the friction :func:`fit_friction` tries: 1/3 to 3, in steps of about 1 %.
FRICTION_FACTORS = np.exp(np.linspace(np.log(1 / 3), np.log(3.0), 221))
#: Rates of change of the factor's logarithm :func:`fit_friction` tries [1/h]: to ±0.15/h,
#: fresh grease running in again (excess friction up to 0.5 over 4 h or more, the
#: families' ranges, swgmon/evaluation/families.py), in steps of 0.01/h.
FRICTION_RATES = np.linspace(-0.15, 0.15, 31)


@dataclass(frozen=True)
class FrictionFit:
    """The hypothesis "the friction changed evenly" fitted to the windows since an alarm
    (:func:`fit_friction`).

    Attributes
    ----------
    factor : float
        The fitted factor on the friction in force at the last window [-].
    z : ndarray, shape (n, F)
        The windows' z-scores with it.
    reduction : float
        How much it lowers Σ z² over the windows (χ² with one degree of freedom where the
        friction did not change, two with a rate).
    rate_per_h : float or None
        The fitted rate of change of the factor's logarithm [1/h]; None: not fitted.
    low, high : float
        The factor's 90 % interval (:func:`profile_interval`); NaN where the fit's
        profile has no curvature to tell it.
    """

    factor: float
    z: np.ndarray
    reduction: float
    rate_per_h: float | None = None
    low: float = float("nan")
    high: float = float("nan")

    def plausible(self, naming: NamingConfig | None = None) -> bool:
        """Significant (:meth:`~.sensor_check.NamingConfig.least_reduction` of one
        parameter, three with a rate): where the efficiency's spread is small (a joint at a
        steady temperature), a change of 1 % is many of them (the friction tracking's lag
        behind a re-greasing running in again, tiny_real_day gear 3)."""
        return self.reduction >= (naming or NamingConfig()).least_reduction(
            1 if self.rate_per_h is None else 3)


def profile_interval(log_factor: np.ndarray, total: np.ndarray) -> tuple[float, float]:
    """The 90 % interval of a factor from the profile of Σ z² over ``log_factor`` (shape
    (m,), increasing, m >= 3; ``total`` the same shape): a parabola fitted to the profile
    around its least, Σ z² ≈ min + (x − x̂)² / σ², and x̂ ± 1.645 σ, as factors.

    Wilks' theorem: twice the log-likelihood ratio, here the rise of Σ z² over unit-variance
    z-scores, is χ² with one degree of freedom, so the 90 % interval is where the rise is
    below 2.706 = 1.645². The windows are taken as independent: windows that share a
    thermal state are not, so the interval is a lower bound on the width. A profile with
    no upward curvature gives NaN, NaN.
    """
    x, y = np.asarray(log_factor, float), np.asarray(total, float)
    k = int(np.argmin(y))
    lo, hi = max(0, k - 2), min(len(x), k + 3)
    if hi - lo < 3:
        return float("nan"), float("nan")
    a, b, _ = np.polyfit(x[lo:hi], y[lo:hi], 2)
    if not a * np.ptp(x[lo:hi]) ** 2 > 1e-9 * (1.0 + abs(y[k])):  # flat: rounding's curve
        return float("nan"), float("nan")
    centre, half = -b / (2 * a), 1.6448536269514722 / np.sqrt(a)
    return float(np.exp(centre - half)), float(np.exp(centre + half))


def fit_friction(normal: NormalBehaviour, feats: np.ndarray, points: np.ndarray,
                 cond: Conditions | None, friction: np.ndarray, index: np.ndarray,
                 hours: np.ndarray | None = None, naming: NamingConfig | None = None
                 ) -> FrictionFit:
    """Fit the hypothesis "the friction changed evenly" (re-greasing, another grease, a
    seal): one factor on the loss torque at every operating point, on a logarithmic grid
    (:data:`FRICTION_FACTORS`), and with ``hours`` a rate at which its logarithm changes
    (:data:`FRICTION_RATES`: fresh grease running in again) from a window on (the
    change's step; the windows before it as they were), chosen to leave Σ z² over the
    windows smallest. A gear fault that changes friction changes it unevenly (reduced
    damping lowers the viscous term only, more at light loads,
    :mod:`swgmon.detection.normal`) and moves the bridges too, so neither factor nor rate
    explains it.

    Parameters
    ----------
    normal : NormalBehaviour
    feats : ndarray, shape (n, F)
    points : ndarray, shape (n, 2)
    cond : Conditions or None
    friction : ndarray, shape (n,)
        The friction factor in force at each window.
    index : ndarray of int, shape (n,)
    hours : ndarray, shape (n,), optional
        The windows' operating hours [h]; None: one factor over all windows, no step, no
        rate.
    naming : NamingConfig, optional
        Its ``friction_refine``: the factors and rates the grid's best is refined with.

    Returns
    -------
    FrictionFit
        The factor at the last window.
    """
    n, m = len(feats), len(FRICTION_FACTORS)
    z = normal.z_over_friction(feats, points, cond,
                               friction[None, :] * FRICTION_FACTORS[:, None], index)
    s = np.sum(z ** 2, axis=2)  # (factor, window)
    one = int(np.argmin(np.abs(FRICTION_FACTORS - 1.0)))
    if hours is None:
        k = int(np.argmin(s.sum(axis=1)))
        return FrictionFit(float(FRICTION_FACTORS[k]), z[k], float(s[one].sum() - s[k].sum()),
                           None, *profile_interval(np.log(FRICTION_FACTORS), s.sum(axis=1)))
    step = np.log(FRICTION_FACTORS[1] / FRICTION_FACTORS[0])
    dt = np.asarray(hours, float) - float(hours[-1])
    before = np.concatenate([[0.0], np.cumsum(s[one])])[:n]  # windows before the step
    best = (float(s[one].sum()), one, 0, 0.0, np.full(n, one))  # no change (NaN: none)
    for rate in FRICTION_RATES.tolist():
        k = np.clip(np.arange(m)[:, None] + np.rint(rate * dt / step).astype(int)[None, :],
                    0, m - 1)  # (factor at the last window, window)
        after = np.cumsum(s[k, np.arange(n)][:, ::-1], axis=1)[:, ::-1]  # from window j on
        tot = before[None, :] + after  # (factor, step window)
        i, j = np.unravel_index(int(np.argmin(tot)), tot.shape)
        if tot[i, j] < best[0]:
            best = (float(tot[i, j]), int(i), int(j), rate, k[i])
    _, i, j, rate, _ = best
    return _refined(normal, feats, points, cond, friction, index, dt, j,
                    float(FRICTION_FACTORS[i]), rate, float(s[one].sum()),
                    (naming or NamingConfig()).friction_refine)


def _refined(normal: NormalBehaviour, feats, points, cond, friction, index, dt, j: int,
             factor: float, rate: float, s_one: float, refine: int) -> FrictionFit:
    """:func:`fit_friction`'s grid best refined without the grid's steps: ``refine``
    factors within one step of ``factor`` and rates within one step of ``rate``, the
    factor at each window from the step ``j`` on ``factor · exp(rate · dt)`` exactly. Where
    the efficiency's spread is small a grid step is several of it: a re-greasing of +33 %
    moved the bench's efficiency by 119 σ, so the grid's 1 % was 3.6 σ, and the fit left
    the hour after the alarm with a median p-value of 0.14 (bench gear 3, family
    ``regrease``, design seed 101), naming a gear fault."""
    n = len(feats)
    step = float(np.log(FRICTION_FACTORS[1] / FRICTION_FACTORS[0]))
    fs = factor * np.exp(step * np.linspace(-1.0, 1.0, refine))
    rs = rate + (FRICTION_RATES[1] - FRICTION_RATES[0]) * np.linspace(-1.0, 1.0, refine)
    combos = np.stack(np.meshgrid(fs, rs, indexing="ij"), axis=-1).reshape(-1, 2)  # (m, 2)
    after = np.arange(j, n)
    fr = (friction[after][None, :] * combos[:, :1]
          * np.exp(combos[:, 1:] * dt[after][None, :]))  # (combo, window)
    za = normal.z_over_friction(feats[after], points[after],
                                None if cond is None else cond[after], fr, index[after])
    sa = np.sum(za ** 2, axis=(1, 2))
    z0 = normal.z(feats[:j], points[:j], None if cond is None else cond[:j], friction[:j],
                  index[:j])
    b = int(np.argmin(sa))
    total = float(np.sum(z0 ** 2) + sa[b])
    at_rate = sa.reshape(refine, refine)[:, b % refine]  # the profile at the best rate
    return FrictionFit(float(combos[b, 0]), np.concatenate([z0, za[b]]), s_one - total,
                       float(combos[b, 1]), *profile_interval(np.log(fs), at_rate))


__all__ = ["FRICTION_FACTORS", "FRICTION_RATES", "FrictionFit", "fit_friction",
           "profile_interval"]
