"""Commissioning's laws: how a gear's health features follow the operating variables,
fitted from the joint's own windows (:mod:`.normal` uses them; its module docstring gives
the physics and the sources).

* the bridges' span and zero drift per K (:func:`bridge_drift`) and each feature's own
  slope per K left after them (:func:`feature_slopes`);
* the loss torque's law A_n φ(T) + B_n τ per input speed, the friction factor's law φ
  (:class:`TemperatureLaw`: exponential, linear or saturating) learnt where commissioning
  saw the joint cool (:func:`loss_model`, :func:`cools`), over a single warm-up bounded
  by it and kept with its bounds;
* the load curves: quadratics in the acting torque at each speed (:func:`load_curves`);
* without a temperature reading, the directions in which commissioning's warm-ups moved
  the z-scores at each point (:func:`warm_up_directions`).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from swgsim.gear.thermal import REF_TEMP_C

from .features import N_HARMONICS

__all__ = ["BLOCK", "EFFICIENCY", "FACTOR_FLOOR", "LAW_CURVATURES", "LAW_FACTORS_40C",
           "MIN_SPREAD_K", "SIGNIFICANT", "TemperatureLaw", "WARM_UP_AVERAGE", "best_law",
           "bridge_drift", "cools", "feature_slopes", "load_curves", "loss_coefficients",
           "loss_model", "poly", "warm_up_directions"]

#: Per-bridge block of health features: offset, H amplitudes, log10 RMS of the rest.
BLOCK = N_HARMONICS + 2
EFFICIENCY = 5 * BLOCK

#: Curvatures b [1/K] of the friction factor's law (:class:`TemperatureLaw`) that
#: commissioning chooses from (:func:`best_law`), in steps of 0.0025 1/K: b < 0 a fall
#: that levels off as the grease thins (at 1 − a/b; the viscosity law's exponential is
#: a = b, levelling off at 0), b = 0 a linear fall, b > 0 one that steepens.
LAW_CURVATURES = np.linspace(-0.15, 0.05, 81)
#: The factor at 40 °C, φ(40 °C), that sets a law's slope a for each curvature: 0.3 to 1,
#: every ratio a sound joint's friction has there (0.63 the catalogue's viscosity law,
#: Harmonic Drive engineering data: no-load running torque over temperature), in steps
#: of 0.0025 (learnt from the joint's own windows, not the catalogue's law).
LAW_FACTORS_40C = np.linspace(0.3, 1.0, 281)
#: Least friction factor a law may give within commissioning's temperatures [-].
FACTOR_FLOOR = 0.05
#: Least temperature spread of commissioning to fit the temperature terms [K].
MIN_SPREAD_K = 2.0
#: Consecutive windows of an operating point whose z-scores :func:`warm_up_directions`
#: averages before it looks for directions: 7, as many as the running median of the
#: temperature the bridges say (:data:`learn.monitor.sensor_check.VIRTUAL_WINDOWS`), which
#: divides a window-to-window scatter's variance by 7 while a warm-up, slow, keeps its
#: direction [choice; chosen on the design seeds, robot_joint gear 1, family ``sensor``].
WARM_UP_AVERAGE = 7
#: An amplitude enters the fit of its bridge's gain when its mean is this many standard
#: deviations above zero (its log is then well defined).
SIGNIFICANT = 20.0


def _growth(b: np.ndarray | float, x: np.ndarray | float) -> np.ndarray:
    """(exp(b x) − 1) / b, x where b = 0 (the law's shape, rising with x for any b)."""
    b, x = np.asarray(b, float), np.asarray(x, float)
    safe = np.where(b == 0.0, 1.0, b)
    return np.where(b == 0.0, x, np.expm1(b * x) / safe)


@dataclass(frozen=True)
class TemperatureLaw:
    """The friction factor's temperature law commissioning learnt (:func:`best_law`):
    φ(T) = 1 + a (exp(b ΔT) − 1) / b with ΔT = T − 20 °C (1 + a ΔT where b = 0): one
    monotone family that holds the exponential (viscosity) law (a = b), the linear one
    (b = 0), ones that level off at 1 − a/b (b < 0) and ones that steepen (b > 0).
    Beyond commissioning's temperatures [lo, hi] it is continued along its tangent (no
    curvature commissioning did not see), and it never falls under :data:`FACTOR_FLOOR`.

    Parameters
    ----------
    a : float
        Slope at 20 °C [1/K] (negative: friction falls as the joint warms).
    b : float
        Curvature [1/K].
    lo, hi : float
        Commissioning's least and greatest temperature [°C].
    """

    a: float = 0.0
    b: float = 0.0
    lo: float = -np.inf
    hi: float = np.inf

    def factor(self, temp: np.ndarray) -> np.ndarray:
        """φ at the temperatures ``temp`` [°C], the shape of ``temp`` [-]."""
        t = np.asarray(temp, float)
        edge = np.clip(t, self.lo, self.hi)
        x = edge - REF_TEMP_C
        slope = self.a * np.exp(self.b * x)  # dφ/dT at the edge
        return np.maximum(1.0 + self.a * _growth(self.b, x) + slope * (t - edge),
                          FACTOR_FLOOR)


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


def bridge_drift(feats: np.ndarray, inv: np.ndarray, dt: np.ndarray
                  ) -> tuple[np.ndarray, np.ndarray]:
    """γ_c and ζ_c of the five bridges (module docstring of :mod:`.normal`): the gain from
    the significant amplitudes' logs (means over :data:`SIGNIFICANT` standard deviations),
    the zero from the offsets, by least squares pooled over points.

    Parameters
    ----------
    feats : ndarray, shape (n, F)
        Commissioning's health features (:data:`BLOCK` per bridge, then the efficiency).
    inv : ndarray of int, shape (n,)
        Each window's operating point.
    dt : ndarray, shape (n,)
        Each window's temperature less its point's mean [K].

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
            sig = a.mean(axis=0) > SIGNIFICANT * a.std(axis=0, ddof=1)
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
               ops: np.ndarray, inv: np.ndarray
               ) -> tuple[np.ndarray, TemperatureLaw, tuple | None]:
    """(A, B) per point and the joint's friction factor law φ(T) (:class:`TemperatureLaw`):
    the loss torque τ (1/η − 1) ≈ A φ(T) + B τ by least squares over the windows at the
    point's speed (module docstring of :mod:`.normal`), (a, b) the pair of the grid
    (:data:`LAW_CURVATURES`, :data:`LAW_FACTORS_40C`) that fits commissioning best.

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

    Returns
    -------
    (ndarray, TemperatureLaw, tuple or None)
        A [N m] and B [-] per point, shape (P, 2); the law (φ = 1 without temperature);
        where the law is only bounded, the laws at its bounds, ((A, B), law) and
        ((A, B), φ = 1), else None.
    """
    tq = np.abs(torque)
    loss = tq * (1.0 / np.clip(eta, 1e-6, 1.0) - 1.0)
    flat = TemperatureLaw()
    if temp is None:
        return loss_coefficients(loss, tq, np.ones(len(eta)), ops, inv)[0], flat, None
    law = best_law(loss, tq, temp, ops, inv)
    coef = loss_coefficients(loss, tq, law.factor(temp), ops, inv)[0]
    if cools(temp):
        return coef, law, None
    bare = loss_coefficients(loss, tq, np.ones(len(eta)), ops, inv)[0]
    return coef, law, ((coef, law), (bare, flat))  # one warm-up: what it showed, and none


def best_law(loss: np.ndarray, tq: np.ndarray, temp: np.ndarray, ops: np.ndarray,
             inv: np.ndarray) -> TemperatureLaw:
    """The law of the grid whose loss fit (:func:`loss_coefficients`) leaves the least
    squared residual over every candidate at once: for a curvature b and a slope a the
    fit at each speed is a 2×2 least-squares problem whose normal equations are sums
    over the windows linear and quadratic in a, so each curvature costs one pass.
    Candidates whose factor falls under :data:`FACTOR_FLOOR` within commissioning's
    temperatures are not tried.

    Parameters
    ----------
    loss, tq, temp : ndarray, shape (n,)
        Each window's loss torque [N m], acting torque's magnitude [N m] and temperature
        [°C].
    ops : ndarray, shape (P, 2)
    inv : ndarray of int, shape (n,)
        As :func:`loss_coefficients`.

    Returns
    -------
    TemperatureLaw
        The best law, continued along its tangent beyond commissioning's temperatures.
    """
    lo, hi = float(np.min(temp)), float(np.max(temp))
    b = LAW_CURVATURES[:, None]  # (B, 1)
    g = _growth(b, temp[None, :] - REF_TEMP_C)  # (B, n)
    a = (LAW_FACTORS_40C[None, :] - 1.0) / _growth(b, 20.0)  # (B, K)
    ok = 1.0 + a * _growth(b, hi - REF_TEMP_C) >= FACTOR_FLOOR
    sse = np.zeros(a.shape)
    for n in np.unique(ops[:, 0]):
        ks = np.flatnonzero(ops[:, 0] == n)
        m = np.isin(inv, ks)
        gm, y, t = g[:, m], loss[m], tq[m]
        s = {k: v[:, None] for k, v in (("g", gm.sum(1)), ("gg", (gm * gm).sum(1)),
                                        ("gt", gm @ t), ("gy", gm @ y))}
        pp = m.sum() + 2.0 * a * s["g"] + a * a * s["gg"]  # Σ φ², Σ φ τ, Σ φ y
        pt, py = t.sum() + a * s["gt"], y.sum() + a * s["gy"]
        if np.unique(ops[ks, 1]).size < 2:  # one load: the loss's level only
            sse += y @ y - py * py / pp
        else:
            tt, ty = t @ t, t @ y
            det = pp * tt - pt * pt
            c_a, c_b = (py * tt - pt * ty) / det, (pp * ty - pt * py) / det
            sse += y @ y - c_a * py - c_b * ty
    j, k = np.unravel_index(np.argmin(np.where(ok, sse, np.inf)), sse.shape)
    return TemperatureLaw(float(a[j, k]), float(LAW_CURVATURES[j]), lo, hi)


def cools(temp: np.ndarray) -> bool:
    """Whether commissioning's temperature (windows in time order) falls by at least
    :data:`MIN_SPREAD_K` below an earlier reading somewhere (a cold start): only then can
    the friction's temperature law be told from a slow drift in time (run-in), which over
    a single warm-up falls as the temperature rises.

    Parameters
    ----------
    temp : ndarray, shape (n,)
        Commissioning's temperatures [°C], in time order.

    Returns
    -------
    bool
        True where some reading lies :data:`MIN_SPREAD_K` [K] or more below an earlier one.
    """
    return bool(np.max(np.maximum.accumulate(temp) - temp) >= MIN_SPREAD_K)


def loss_coefficients(loss: np.ndarray, tq: np.ndarray, phi: np.ndarray, ops: np.ndarray,
                       inv: np.ndarray) -> tuple[np.ndarray, float]:
    """(A, B) per point for the friction factors ``phi`` of the windows: loss ≈ A φ + B τ
    by least squares over the windows at each speed (A alone where the speed has one load).

    Parameters
    ----------
    loss : ndarray, shape (n,)
        Each window's loss torque τ (1/η − 1) [N m].
    tq : ndarray, shape (n,)
        Each window's acting torque's magnitude τ [N m].
    phi : ndarray, shape (n,)
        Each window's friction factor φ(T) (:meth:`TemperatureLaw.factor`) [-].
    ops : ndarray, shape (P, 2)
        The operating points (input speed [rpm], torque [N m]).
    inv : ndarray of int, shape (n,)
        Each window's operating point.

    Returns
    -------
    (ndarray, float)
        A [N m] and B [-] per point, shape (P, 2); the sum of squared residuals [N² m²].
    """
    out, sse = np.zeros((len(ops), 2)), 0.0
    for n in np.unique(ops[:, 0]):
        ks = np.flatnonzero(ops[:, 0] == n)
        m = np.isin(inv, ks)
        x = np.stack([phi[m], tq[m]], axis=1)
        if np.unique(ops[ks, 1]).size < 2:  # one load: the loss's level only
            coef = np.array([phi[m] @ loss[m] / (phi[m] @ phi[m]), 0.0])
        else:
            coef = np.linalg.lstsq(x, loss[m], rcond=None)[0]
        sse += float(np.sum((x @ coef - loss[m]) ** 2))
        out[ks] = coef
    return out, sse


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


def warm_up_directions(z: np.ndarray, inv: np.ndarray, k: int
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
    slow ones: the same test on running means of :data:`WARM_UP_AVERAGE` consecutive
    windows of the point, edge (1 + sqrt(F' L / m))² / L (the overlapping means taken as
    m / L independent ones, F' the features left). Behind a robot link the first are the
    torque ripple, which scatters every bridge's orders 2 and 4 together from window to
    window (one acting torque, its phase against the window's start drawn anew; robot_joint
    gear 1, family ``sensor``, scored seed 0), larger than a warm-up: without the slow
    ones every later cold start, which moves s1_h2, s3_h2 and the efficiency, was alarmed
    as a root crack (docs/monitor.md, "Scored under every family"). Where no slow one
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
        avg = max(1, min(WARM_UP_AVERAGE, m // 3))
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

