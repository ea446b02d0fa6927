"""Commissioning's laws: how a gear's health features follow the operating variables,
fitted from the joint's own windows (:mod:`.normal` uses them; its module docstring gives
the physics and the sources).

* the bridges' span and zero drift per K (:func:`bridge_drift`) and each feature's own
  slope per K left after them (:func:`feature_slopes`);
* the loss torque's law per input speed, a load-independent part falling with the
  temperature by any monotone law and a part proportional to the load
  (:class:`LossLaw`), learnt where commissioning saw the joint cool (:func:`loss_model`,
  :func:`cools`), over a single warm-up bounded by it and kept with its bounds;
* the load curves: quadratics in the acting torque at each speed (:func:`load_curves`);
* without a temperature reading, the directions in which commissioning's warm-ups moved
  the z-scores at each point (:func:`warm_up_directions`);
* for the ablation of all the above (the benchmark of issue 83), a generic regression of
  every feature on the acting load and the temperature per input speed
  (:func:`generic_laws`).
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from learn.inputs.health import N_HARMONICS
from swgsim.base.lazy import lazy_module
from swgsim.base.typed import allowed

optimize = lazy_module("scipy.optimize")  # at the first fit, not at an app's start

__all__ = ["BLOCK", "EFFICIENCY", "LawFit", "LossLaw", "bridge_drift", "cools",
           "feature_slopes", "generic_laws", "load_curves", "loss_model", "poly",
           "warm_up_directions", "generic_inputs"]

#: Per-bridge block of health features: offset, H amplitudes, log10 RMS of the rest.
BLOCK = N_HARMONICS + 2
EFFICIENCY = 5 * BLOCK

@dataclass
class LawFit:
    """The numbers the normal behaviour's laws are fitted with (issue 84: every constant
    on record): ``normal.fit`` of ``swgsim-monitor`` and ``monitor.study.normal.fit`` of
    the evaluation, logged with every run. Design and sources: docs/monitor/detection.md,
    "The normal behaviour's laws".

    Attributes
    ----------
    segment_k : float
        Width of the loss law's temperature segments over commissioning's temperatures
        [K], in (0, 50] (:class:`LossLaw`): its range in as many equal segments as come
        nearest this width, at least one (5 [choice: 5 K and 2.5 K fitted the design
        seeds' lives alike: bench, gear 3, families ``friction_law`` and ``trace``, seeds
        100-104]).
    smoothing : float
        Weight of the penalty on unequal slopes of neighbouring segments, relative to the
        segments' own weight in the fit [-], in [0, 1] (1e-3 [choice]): it decides only a
        slope the windows do not (a segment a speed did not run in).
    factor_floor : float
        Least share of its value at commissioning's coldest that the load-independent
        loss keeps when its law is carried beyond commissioning's temperatures [-], in
        [0, 1) (0.05 [choice]).
    generic_degree : int
        The generic regression's polynomial degree in the load and the temperature
        (:func:`generic_laws`), in [1, 3] (2 [choice: a quadratic, as the load curves
        are]).
    generic_alpha : float
        Its ridge penalty on standardised terms, in [0, 1e3] (1 [choice: it only steadies
        a term commissioning barely varied]).
    min_spread_k : float
        Least temperature spread of commissioning to fit the temperature terms, and the
        least fall below an earlier reading for commissioning to have cooled
        (:func:`cools`) [K], in [0, 50] (2, ten times the reading's uncertainty of 0.2 K,
        ``normal.temperature_uncertainty_k``).
    warm_up_average : int
        Consecutive windows of an operating point whose z-scores
        :func:`warm_up_directions` averages before it looks for slow directions, in
        [1, 99] (7, as many as the running median of the temperature the bridges say,
        ``naming.virtual_windows``: it divides a window-to-window scatter's variance by 7
        while a warm-up, slow, keeps its direction [choice; chosen on the design seeds,
        robot_joint gear 1, family ``sensor``]).
    significant_sd : float
        An amplitude enters the fit of its bridge's gain (:func:`bridge_drift`) when its
        mean is this many standard deviations above zero (its log is then well defined),
        in [1, 1e3] (20 [choice]).
    """

    segment_k: float = field(default=5.0, metadata=allowed(0.0, 50.0, lo_open=True,
                                                           unit="K"))
    smoothing: float = field(default=1e-3, metadata=allowed(0.0, 1.0))
    factor_floor: float = field(default=0.05, metadata=allowed(0.0, 1.0, hi_open=True))
    generic_degree: int = field(default=2, metadata=allowed(1, 3))
    generic_alpha: float = field(default=1.0, metadata=allowed(0.0, 1e3))
    min_spread_k: float = field(default=2.0, metadata=allowed(0.0, 50.0, unit="K"))
    warm_up_average: int = field(default=7, metadata=allowed(1, 99))
    significant_sd: float = field(default=20.0, metadata=allowed(1.0, 1e3))


@dataclass(frozen=True)
class LossLaw:
    """The loss torque's law at each operating point, learnt at commissioning
    (:func:`loss_model`): L(T, τ) = D + Σ_j E_j h_j(T) + B τ, the load-independent part
    D + Σ_j E_j h_j(T) a continuous piecewise-linear function of the temperature over
    commissioning's range cut at :attr:`knots` (h_j the ramp over segment j: 0 below it,
    its width above), never rising with the temperature (E_j <= 0): any monotone law, its
    own per input speed. Beyond commissioning's temperatures the end segments' slopes go
    on (no curvature commissioning did not see), and the load-independent part keeps at
    least :attr:`floor` of D.

    Parameters
    ----------
    coef : ndarray, shape (P, K + 2)
        Per operating point: D [N m] (the load-independent loss at ``knots[0]``), the
        slopes E_1..E_K [N m/K] and B [-]; K = 0 without a temperature law.
    floor : float
        Least share of D the load-independent part keeps beyond commissioning's
        temperatures [-] (:attr:`LawFit.factor_floor`).
    knots : ndarray, shape (K + 1,) or (0,)
        The segments' ends [°C]; empty without a temperature law.
    """

    coef: np.ndarray
    floor: float
    knots: np.ndarray = field(default_factory=lambda: np.zeros(0))

    def ramps(self, temp: np.ndarray) -> np.ndarray:
        """h_j at the temperatures ``temp`` (n,) [°C], shape (n, K) [K]: each segment's
        ramp, the end segments' going on beyond the range."""
        t, k = np.asarray(temp, float), self.knots
        h = np.clip(t[:, None] - k[None, :-1], 0.0, np.diff(k)[None, :])
        h[:, -1] += np.maximum(t - k[-1], 0.0)
        h[:, 0] += np.minimum(t - k[0], 0.0)
        return h

    def predict(self, i: np.ndarray, tq: np.ndarray, temp: np.ndarray | None) -> np.ndarray:
        """The loss torque [N m] of windows at points ``i`` (n,), acting torques' magnitudes
        ``tq`` (n,) [N m] and temperatures ``temp`` (n,) [°C] (None: at ``knots[0]``),
        shape (n,)."""
        c = self.coef[i]
        free = c[:, 0]
        if temp is not None and self.knots.size:
            free = np.maximum(free + np.sum(self.ramps(temp) * c[:, 1:-1], axis=1),
                              self.floor * free)
        return free + c[:, -1] * tq


def poly(x: np.ndarray, y: np.ndarray, degree: int) -> np.ndarray:
    """Coefficients (c0, c1, c2) of y ≈ c0 + c1 x + c2 x² of at most ``degree`` (and one
    less than the points), by least squares, for each column of y.

    Parameters
    ----------
    x : ndarray, shape (k,)
        The abscissae (here the acting torque [N m]).
    y : ndarray, shape (k, F)
        The values, one column per feature (in the feature's unit).
    degree : int
        Highest power fitted, at most 2.

    Returns
    -------
    ndarray, shape (3, F)
        c0, c1, c2 per column (in y's unit per power of x's); the powers above the degree
        fitted zero.
    """
    deg = min(degree, len(x) - 1)
    v = np.vander(x, deg + 1, increasing=True)  # (k, deg + 1)
    coef = np.linalg.lstsq(v, y, rcond=None)[0]
    return np.vstack([coef, np.zeros((2 - deg, y.shape[1]))])


def bridge_drift(feats: np.ndarray, inv: np.ndarray, dt: np.ndarray, significant_sd: float
                 ) -> tuple[np.ndarray, np.ndarray]:
    """γ_c and ζ_c of the five bridges (module docstring of :mod:`.normal`): the gain from
    the significant amplitudes' logs (means over ``significant_sd`` standard deviations),
    the zero from the offsets, by least squares pooled over points.

    Parameters
    ----------
    feats : ndarray, shape (n, F)
        Commissioning's health features (:data:`BLOCK` per bridge, then the efficiency).
    inv : ndarray of int, shape (n,)
        Each window's operating point.
    dt : ndarray, shape (n,)
        Each window's temperature less its point's mean [K].
    significant_sd : float
        :attr:`LawFit.significant_sd`.

    Returns
    -------
    (ndarray, ndarray)
        γ [1/K] and ζ [mV/V per K] of each bridge, shape (5,) each; zero where ``dt`` is.
    """
    gain, zero = np.zeros(5), np.zeros(5)
    d2 = float(dt @ dt)
    if d2 <= 0:
        return gain, zero
    for c in range(5):
        j0 = c * BLOCK
        amp = feats[:, j0 + 1:j0 + BLOCK - 1]
        num = den = 0.0
        for k in np.unique(inv):
            m = inv == k
            a = amp[m]
            sig = a.mean(axis=0) > significant_sd * a.std(axis=0, ddof=1)
            if sig.any():  # Σ_j Σ_i ΔT_i (ln a_ij − mean_i ln a_ij) over Σ_j Σ_i ΔT_i²
                la = np.log(a[:, sig])
                num += float(dt[m] @ (la - la.mean(axis=0)).sum(axis=1))
                den += float(dt[m] @ dt[m]) * int(sig.sum())
        gain[c] = num / den if den > 0 else 0.0
        off = feats[:, j0]
        resid = np.zeros(len(off))
        for k in np.unique(inv):
            m = inv == k
            resid[m] = off[m] - off[m].mean() - gain[c] * off[m].mean() * dt[m]
        zero[c] = float(dt @ resid) / d2
    return gain, zero


def feature_slopes(feats: np.ndarray, inv: np.ndarray, dt: np.ndarray) -> np.ndarray:
    """Per point, each feature's least-squares slope on ΔT (features with the bridges'
    gain and zero drift taken out); the efficiency's columns zero (its loss law has the
    temperature).

    Parameters
    ----------
    feats : ndarray, shape (n, F)
        Commissioning's health features, the bridges' drift taken out.
    inv : ndarray of int, shape (n,)
        Each window's operating point, 0 to P − 1.
    dt : ndarray, shape (n,)
        Each window's temperature less its point's mean [K].

    Returns
    -------
    ndarray, shape (P, F)
        Slopes [the feature's unit per K]; zero at a point without temperature spread.
    """
    n_p = int(inv.max()) + 1
    out = np.zeros((n_p, feats.shape[1]))
    for k in range(n_p):
        m = inv == k
        x = dt[m] - dt[m].mean()
        if float(x @ x) > 0:
            out[k] = x @ (feats[m] - feats[m].mean(axis=0)) / float(x @ x)
    out[:, EFFICIENCY:] = 0.0
    return out


def loss_model(eta: np.ndarray, torque: np.ndarray, temp: np.ndarray | None,
               ops: np.ndarray, inv: np.ndarray, fit: LawFit
               ) -> tuple[LossLaw, tuple | None]:
    """The loss torque's law (:class:`LossLaw`) fitted to commissioning's windows: at each
    input speed the loss τ (1/η − 1) by least squares over its windows with the slopes
    bounded (friction does not rise with the temperature; module docstring of
    :mod:`.normal`), the temperature's range cut into segments of about
    ``fit.segment_k``.

    Where commissioning did not cool (:func:`cools`) the law that fits is not the
    friction's alone: a run-in lowers the loss while the joint warms, so the law is no
    steeper than the fitted one, and no flatter than none (friction does not rise over
    commissioning on a sound joint). Then the fitted law is kept (what commissioning saw),
    and the laws at both bounds, fitted to the same windows, are returned as its
    uncertainty.

    Parameters
    ----------
    eta : ndarray, shape (n,)
        Each window's efficiency [-].
    torque : ndarray, shape (n,)
        Each window's acting output torque τ [N m] (its magnitude used).
    temp : ndarray, shape (n,), or None
        Each window's temperature [°C], in time order; None: no temperature law.
    ops : ndarray, shape (P, 2)
        The operating points (input speed [rpm], torque [N m]).
    inv : ndarray of int, shape (n,)
        Each window's operating point.
    fit : LawFit
        The segments' width, the slopes' tie, the floor and the least cooling.

    Returns
    -------
    (LossLaw, tuple or None)
        The law; where it is only bounded, the laws at its bounds (the fitted one, and
        one without temperature), else None.
    """
    tq = np.abs(torque)
    loss = tq * (1.0 / np.clip(eta, 1e-6, 1.0) - 1.0)
    flat = _fit_law(loss, tq, None, ops, inv, np.zeros(0), fit)
    if temp is None:
        return flat, None
    lo, hi = float(np.min(temp)), float(np.max(temp))
    knots = np.linspace(lo, hi, max(1, int(round((hi - lo) / fit.segment_k))) + 1)
    law = _fit_law(loss, tq, temp, ops, inv, knots, fit)
    return law, (None if cools(temp, fit.min_spread_k) else (law, flat))


def _fit_law(loss: np.ndarray, tq: np.ndarray, temp: np.ndarray | None, ops: np.ndarray,
             inv: np.ndarray, knots: np.ndarray, fit: LawFit) -> LossLaw:
    """The :class:`LossLaw` on ``knots`` fitted to the windows' losses, speed by speed
    (B only where the speed ran at two loads or more), the slopes <= 0 (bounded-variable
    least squares, :func:`scipy.optimize.lsq_linear`) and neighbouring slopes tied by
    ``fit.smoothing``."""
    k = max(knots.size - 1, 0)
    shell = LossLaw(np.zeros((len(ops), k + 2)), fit.factor_floor, knots)
    out = shell.coef
    for n in np.unique(ops[:, 0]):
        ks = np.flatnonzero(ops[:, 0] == n)
        m = np.isin(inv, ks)
        loads = np.unique(ops[ks, 1]).size > 1
        cols = [np.ones(int(m.sum()))]
        if k:
            cols += list(shell.ramps(temp[m]).T)
        if loads:
            cols.append(tq[m])
        x, y = np.stack(cols, axis=1), loss[m]
        lower, upper = np.full(x.shape[1], -np.inf), np.full(x.shape[1], np.inf)
        upper[1:k + 1] = 0.0  # the slopes: friction does not rise with the temperature
        if k > 1:  # neighbouring slopes alike where the windows do not say otherwise
            w = np.sqrt(fit.smoothing * np.mean(np.sum(x[:, 1:k + 1] ** 2, axis=0)))
            d = np.zeros((k - 1, x.shape[1]))
            d[np.arange(k - 1), np.arange(1, k)] = -w
            d[np.arange(k - 1), np.arange(2, k + 1)] = w
            x, y = np.vstack([x, d]), np.r_[y, np.zeros(k - 1)]
        c = optimize.lsq_linear(x, y, bounds=(lower, upper), method="bvls").x
        out[ks, :k + 1] = c[:k + 1]
        out[ks, -1] = c[-1] if loads else 0.0
    return shell


def cools(temp: np.ndarray, min_fall_k: float) -> bool:
    """Whether commissioning's temperature (windows in time order) falls by at least
    ``min_fall_k`` below an earlier reading somewhere (a cold start): only then can
    the friction's temperature law be told from a slow drift in time (run-in), which over
    a single warm-up falls as the temperature rises.

    Parameters
    ----------
    temp : ndarray, shape (n,)
        Commissioning's temperatures [°C], in time order.
    min_fall_k : float
        The least fall [K] (:attr:`LawFit.min_spread_k`).

    Returns
    -------
    bool
        True where some reading lies ``min_fall_k`` or more below an earlier one.
    """
    return bool(np.max(np.maximum.accumulate(temp) - temp) >= min_fall_k)


def load_curves(feats: np.ndarray, inv: np.ndarray, ops: np.ndarray,
                 ref_torque: np.ndarray) -> np.ndarray:
    """Per point, the quadratics in τ of the load curves at its speed (module docstring of
    :mod:`.normal`): squared amplitudes, offsets (a line), residual power; the
    efficiency's and the twist's columns zero (the efficiency has its loss law).

    Parameters
    ----------
    feats : ndarray, shape (n, F)
        Commissioning's health features, temperature-corrected.
    inv : ndarray of int, shape (n,)
        Each window's operating point.
    ops : ndarray, shape (P, 2)
        The operating points (input speed [rpm], torque [N m]).
    ref_torque : ndarray, shape (P,)
        Each point's mean acting torque [N m].

    Returns
    -------
    ndarray, shape (P, 3, F)
        c0, c1, c2 of each curve (its quantity's unit per N m to the power).
    """
    n_p, n_f = len(ops), feats.shape[1]
    y = np.zeros((n_p, n_f))
    for k in range(n_p):
        f = feats[inv == k]
        for c in range(5):
            j0 = c * BLOCK
            y[k, j0] = f[:, j0].mean()
            y[k, j0 + 1:j0 + BLOCK - 1] = (f[:, j0 + 1:j0 + BLOCK - 1] ** 2).mean(axis=0)
            y[k, j0 + BLOCK - 1] = (10.0 ** (2 * f[:, j0 + BLOCK - 1])).mean()
    out = np.zeros((n_p, 3, n_f))
    offsets = [c * BLOCK for c in range(5)]
    for n in np.unique(ops[:, 0]):
        ks = np.flatnonzero(ops[:, 0] == n)
        x = np.abs(ref_torque[ks])
        coef = poly(x, y[ks], 2)  # (3, F): squared amplitudes, residual power
        coef[:, offsets] = poly(x, y[ks][:, offsets], 1)  # offsets: a line
        out[ks] = coef
    out[:, :, EFFICIENCY:] = 0.0  # the efficiency has its loss model; twist: none
    return out


def warm_up_directions(z: np.ndarray, inv: np.ndarray, k: int, average: int
                       ) -> tuple[np.ndarray, np.ndarray]:
    """Per operating point, the directions in which commissioning's z-scores varied
    together beyond noise, and their range: what a joint without a temperature reading
    saw its warm-ups do (the bridges' span and zero drift move every bridge alike, the
    grease's viscosity the efficiency, module docstring of :mod:`.normal`), and what
    else moved its features together.

    First, at most ``k`` directions of the windows themselves: those whose eigenvalue of
    the windows' covariance lies above the largest a covariance of independent
    unit-variance features has, the Marchenko-Pastur edge (1 + sqrt(F / m))² for m
    windows of F features (V. A. Marchenko and L. A. Pastur, Math. USSR-Sbornik 1(4),
    1967; I. M. Johnstone, Ann. Statist. 29(2), 2001, for the largest eigenvalue's spike):
    on the bench's joint without a sensor (gear 3, family ``sensor``) the two largest were
    3.3-5.3 against an edge of 3.1, the warm-ups. Then, in what those leave, at most ``k``
    slow ones: the same test on running means of ``average`` consecutive
    windows of the point, edge (1 + sqrt(F' L / m))² / L (the overlapping means taken as
    m / L independent ones, F' the features left). Behind a robot link the first are the
    torque ripple, which scatters every bridge's orders 2 and 4 together from window to
    window (one acting torque, its phase against the window's start drawn anew; robot_joint
    gear 1, family ``sensor``, scored seed 0), larger than a warm-up: without the slow
    ones every later cold start, which moves s1_h2, s3_h2 and the efficiency, was alarmed
    as a root crack (docs/monitor/evaluation.md, "Scored under every family"). Where no slow one
    counts (a joint at a steady temperature) the result is the first alone, shape (P, k,
    F), as before the slow ones were added. The range along a direction is that of the
    windows themselves.

    Parameters
    ----------
    z : ndarray, shape (n, F)
        Commissioning's z-scores (features at the reference condition, standardised per
        point), each point's windows in time order.
    inv : ndarray of int, shape (n,)
        Each window's point.
    k : int
        Most directions per point of each kind.
    average : int
        Windows per running mean (:attr:`LawFit.warm_up_average`).

    Returns
    -------
    (ndarray, ndarray)
        Orthonormal directions, shape (P, K, F), K = ``k`` plus the most slow ones a point
        has (zero rows where a point has fewer), and commissioning's range along each,
        shape (P, K, 2).
    """
    n_p, n_f = int(inv.max()) + 1, z.shape[1]
    each = []  # per point: (first (j, F), slow (i, F))
    for p in range(n_p):
        zp = z[inv == p]
        m = len(zp)
        if m < 3:
            each.append((np.zeros((0, n_f)), np.zeros((0, n_f))))
            continue
        first = _beyond_noise(zp - zp.mean(axis=0), m, k)
        rest = zp - (zp @ first.T) @ first  # in the complement of the first
        avg = max(1, min(average, m // 3))
        run = np.cumsum(np.vstack([np.zeros(n_f), rest]), axis=0)
        means = (run[avg:] - run[:-avg]) / avg  # running means (m - avg + 1, F)
        each.append((first, _beyond_noise(means - means.mean(axis=0), m / avg, k, avg,
                                          n_f - len(first))))
    n_k = k + max(len(slow) for _, slow in each)
    dirs, rng = np.zeros((n_p, n_k, n_f)), np.zeros((n_p, n_k, 2))
    for p, (first, slow) in enumerate(each):
        if len(first) + len(slow) == 0:
            continue
        zp = z[inv == p]
        for row, d in zip((*range(len(first)), *range(k, k + len(slow))), (*first, *slow),
                          strict=True):
            u = zp @ d
            dirs[p, row], rng[p, row] = d, [u.min(), u.max()]
    return dirs, rng


def _beyond_noise(x: np.ndarray, m: float, k: int, avg: int = 1, dim: int | None = None
                  ) -> np.ndarray:
    """At most ``k`` leading principal directions of ``x`` (rows: windows, or running
    means of ``avg`` windows; centred) whose eigenvalue lies above the Marchenko-Pastur
    edge (1 + sqrt(dim / m))² / avg of ``m`` independent windows' worth of ``dim``
    unit-variance features, shape (j, F), j <= k."""
    dim = x.shape[1] if dim is None else dim
    _, s, vt = np.linalg.svd(x, full_matrices=False)
    edge = (1.0 + np.sqrt(dim / m)) ** 2 / avg
    return vt[:k][s[:k] ** 2 / (len(x) - 1) > edge]



def generic_laws(feats: np.ndarray, inv: np.ndarray, ops: np.ndarray, torque: np.ndarray,
                 temp: np.ndarray | None, fit: LawFit) -> list:
    """The ablation of the laws above: per input speed, one generic regression of every
    feature on the acting load (and the temperature, where commissioning fitted its
    terms), scikit-learn's polynomial of degree ``fit.generic_degree``, standardised, and
    ridge regression (penalty ``fit.generic_alpha``); no drift, loss or load law, no
    friction factor. The normal behaviour "with a generic regression" of the benchmark
    (:class:`~.normal.NormalConfig` ``laws``).

    Parameters
    ----------
    feats : ndarray, shape (n, F)
        Commissioning's features.
    inv : ndarray of int, shape (n,)
        Each window's operating point (a row of ``ops``).
    ops : ndarray, shape (P, 2)
        The operating points (input speed [rpm], torque [N m]).
    torque : ndarray, shape (n,)
        Each window's acting load [N m] (its magnitude used).
    temp : ndarray, shape (n,), or None
        Each window's temperature [°C]; None: the load alone.
    fit : LawFit
        The polynomial's degree and the ridge penalty.

    Returns
    -------
    list of sklearn Pipeline, length P
        The regression of each point (one shared by the points of a speed); its inputs
        :func:`generic_inputs`.
    """
    from sklearn.linear_model import Ridge  # heavy: at the first fit, not at an app's start
    from sklearn.pipeline import make_pipeline
    from sklearn.preprocessing import PolynomialFeatures, StandardScaler

    x = generic_inputs(torque, temp)
    out: list = [None] * len(ops)
    for n in np.unique(ops[:, 0]):
        pts = np.flatnonzero(ops[:, 0] == n)
        m = np.isin(inv, pts)
        model = make_pipeline(PolynomialFeatures(fit.generic_degree, include_bias=False),
                              StandardScaler(), Ridge(alpha=fit.generic_alpha))
        model.fit(x[m], feats[m])
        for k in pts:
            out[k] = model
    return out


def generic_inputs(torque: np.ndarray, temp: np.ndarray | None) -> np.ndarray:
    """The generic regression's inputs: the acting load's magnitude [N m] and the
    temperature [°C] where given, shape (n, 1) or (n, 2)."""
    cols = [np.abs(np.asarray(torque, float))]
    if temp is not None:
        cols.append(np.asarray(temp, float))
    return np.stack(cols, axis=1)
