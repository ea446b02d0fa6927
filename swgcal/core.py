"""Separable least squares of a sum of model terms, with uncertainties.

The terms' forms (:class:`Param`, :class:`Term`, the design matrix) are defined in
:mod:`swgsim.gear.terms` (a simulator input as much as a fitted model) and re-exported here;
what only a fit needs (bounds, starts, probes, physical ranges) is added by
:class:`~swgcal.terms.FitTerm`, the class of every term this module fits.

A model is a sum of *terms*. Each term contributes columns ``X_j(θ_j)`` times linear
coefficients ``c_j`` to the prediction ``ŷ = Σ_j X_j(θ_j) c_j``; ``θ_j`` are its nonlinear
parameters (a ripple period, a time constant). A term may instead *transform* the
signals every later term sees (a lag of the velocity seen by the friction law). The
signals object is domain specific (friction: :class:`~swgsim.gear.friction.FrictionSignals`);
this module only calls term methods, so a strain-side library plugs in by defining its
own signals and terms.

Fitting is separable (variable projection, Golub & Pereyra 1973): for given θ the linear
coefficients are the exact linear least-squares solution, and θ is found by
:func:`scipy.optimize.least_squares` (trust region reflective, box bounds, log scale for
positive scale parameters) from several starts; linear coefficients within the terms'
:meth:`~swgcal.terms.FitTerm.linear_bounds` (:func:`solve_linear`), one left on a bound
flagged (:attr:`ParamEstimate.bound`). Uncertainties come from the Jacobian of
the full parameter vector at the optimum, ``cov = s² (JᵀJ)⁻¹ · τ_int``, where ``s²`` is
the residual variance and ``τ_int`` the integrated autocorrelation time of the residual
(Sokal 1997, automatic window c = 5): autocorrelated residuals carry fewer independent
samples than their count, and the plain Jacobian formula would be optimistic by about
``sqrt(τ_int)``. The correction is approximate (it treats the regressors as white).
"""

from __future__ import annotations

import dataclasses
import itertools
import logging
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from swgsim.base.lazy import lazy_module
from swgsim.gear.terms import Param, Term, design_matrix, evaluate_terms, linear_recurrence

from .terms import FitTerm

optimize = lazy_module("scipy.optimize")

log = logging.getLogger(__name__)

__all__ = [
    "Param",
    "Term",
    "FitTerm",
    "FitResult",
    "ParamEstimate",
    "fit_terms",
    "physical_check",
    "solve_linear",
    "evaluate_terms",
    "with_uncertainty",
    "integrated_autocorr_time",
    "linear_recurrence",
]


# ---------------------------------------------------------------------------------------
# helpers


def integrated_autocorr_time(r: np.ndarray, c: float = 5.0) -> float:
    """Integrated autocorrelation time τ_int = 1 + 2 Σ_k ρ_k of a series.

    Sokal's automatic window: the sum runs to the smallest lag M with M ≥ c τ_int(M)
    (Sokal 1997, "Monte Carlo methods in statistical mechanics"; also emcee's
    ``integrated_time``). White noise gives 1; AR(1) with coefficient ρ gives
    (1 + ρ) / (1 − ρ).

    Parameters
    ----------
    r : ndarray, shape (n,)
        Series in sample order.
    c : float, default 5
        Window constant.

    Returns
    -------
    float
        τ_int ≥ 1 [samples].
    """
    x = np.asarray(r, float) - np.mean(r)
    n = x.size
    if n < 8 or not np.any(x):
        return 1.0
    nfft = 1 << (2 * n - 1).bit_length()
    f = np.fft.rfft(x, nfft)
    acf = np.fft.irfft(f * np.conj(f), nfft)[:n]
    acf /= acf[0]
    taus = 2.0 * np.cumsum(acf) - 1.0
    m = np.arange(n)
    ok = m >= c * taus
    w = int(np.argmax(ok)) if ok.any() else n - 1
    return float(max(1.0, min(taus[w], n / 10.0)))


# ---------------------------------------------------------------------------------------
# results


@dataclass(frozen=True)
class ParamEstimate:
    """One reported parameter with its standard error and identifiability flag.

    Attributes
    ----------
    value, std : float
        Estimate and standard error (corrected for residual autocorrelation).
    flag : str
        ``""`` (pinned down), or why the data cannot pin it down: ``"weak (rel. s.e.
        0.8)"`` (relative standard error above ``max_rel_se``), ``"not determined
        (singular)"``.
    note : str
        A strong correlation with another parameter (``"correlated with paper_law.b0
        (r = -0.995)"``): the two trade off; informative even when both are pinned down.
    bound : str
        ``""``, ``"on its lower bound 0"`` (left on a bound of its fit) or ``"held at 24"``
        (equal bounds). A linear coefficient on a bound or held has s.e. 0 (the bound holds
        it; the others' covariance is conditional on it); a nonlinear one on its box's
        bound keeps the curvature's.
    """

    term: str
    name: str
    unit: str
    value: float
    std: float
    flag: str = ""
    note: str = ""
    bound: str = ""

    @property
    def identifiable(self) -> bool:
        return not self.flag

    @property
    def on_bound(self) -> bool:
        """Whether the fit left the parameter on a bound (not one held by equal bounds)."""
        return self.bound.startswith("on its")

    def as_dict(self) -> dict[str, Any]:
        return {"value": self.value, "std": self.std, "unit": self.unit,
                "identifiable": self.identifiable, "flag": self.flag, "note": self.note,
                "bound": self.bound}


@dataclass
class FitResult:
    """A fitted model: terms, parameters, covariance, scores.

    Attributes
    ----------
    thetas, coefs : tuple of ndarray
        Nonlinear and linear parameters per term [natural units].
    n, k : int
        Samples and parameters used in the fit.
    rss : float
        Residual sum of squares on the fit samples.
    sigma : float
        Residual standard deviation sqrt(rss / (n − k)).
    tau_int : float
        Integrated autocorrelation time of the fit residual [samples].
    bic : float
        n ln(rss / n) + k ln n (Schwarz 1978), Gaussian i.i.d. likelihood.
    estimates : list of ParamEstimate
        Reported (derived) parameters with standard errors and flags.
    cond : float
        Condition number of the column-scaled JᵀJ.
    """

    terms: tuple[Term, ...]
    thetas: tuple[np.ndarray, ...]
    coefs: tuple[np.ndarray, ...]
    n: int
    k: int
    rss: float
    sigma: float
    tau_int: float
    bic: float
    estimates: list[ParamEstimate] = field(default_factory=list)
    cond: float = float("nan")
    success: bool = True
    message: str = ""

    def predict(self, sig: Any) -> np.ndarray:
        """Model prediction on ``sig`` (all samples), shape (n,)."""
        return design_matrix(self.terms, sig, self.thetas) @ np.concatenate(
            [c for c in self.coefs] or [np.empty(0)])

    def estimates_of(self, term_name: str) -> dict[str, ParamEstimate]:
        return {e.name: e for e in self.estimates if e.term == term_name}


# ---------------------------------------------------------------------------------------
# fitting


def _solve_unbounded(x: np.ndarray, y: np.ndarray) -> np.ndarray:
    """Least squares by the column-scaled normal equations (:func:`solve_linear`)."""
    if x.shape[1] == 0:
        return np.empty(0)
    norms = np.sqrt(np.einsum("ij,ij->j", x, x))
    norms[norms == 0] = 1.0
    xs = x / norms
    g = xs.T @ xs
    w, v = np.linalg.eigh(g)
    keep = w > w[-1] * 1e-12
    c = v[:, keep] @ ((v[:, keep].T @ (xs.T @ y)) / w[keep])
    return c / norms


def solve_linear(x: np.ndarray, y: np.ndarray, lo: np.ndarray | None = None,
                 hi: np.ndarray | None = None) -> np.ndarray:
    """Least-squares coefficients of ``y ≈ x c``, optionally within bounds.

    Column-scaled normal equations by a symmetric eigendecomposition, pseudo-inverse cut at
    1e-12 of the largest eigenvalue (rank-deficient safe, accurate while cond(X) < 1e6;
    for few columns far faster than an SVD of the tall matrix). With a finite bound:
    coefficients with ``lo == hi`` held there, the others by BVLS (Stark & Parker 1995,
    :func:`scipy.optimize.lsq_linear`) on the k × k problem of the same normal equations.

    Parameters
    ----------
    x : ndarray, shape (m, k)
        Design matrix, one column per coefficient.
    y : ndarray, shape (m,)
        Target [data units].
    lo, hi : ndarray, shape (k,), optional
        Bounds, ``lo <= hi`` (``-inf``/``inf``: open) [the coefficients' units].

    Returns
    -------
    ndarray, shape (k,)

    Raises
    ------
    ValueError
        Bounds of the wrong shape, or a lower bound above its upper one.
    """
    k = x.shape[1]
    lo = np.full(k, -np.inf) if lo is None else np.asarray(lo, float)
    hi = np.full(k, np.inf) if hi is None else np.asarray(hi, float)
    if lo.shape != (k,) or hi.shape != (k,) or np.any(lo > hi):
        raise ValueError(f"linear bounds need shape ({k},) and lo <= hi, got {lo}, {hi}")
    held, free = lo == hi, lo != hi
    c = np.where(held, lo, 0.0)
    r = y - x[:, held] @ lo[held] if held.any() else y
    if free.any() and not np.isfinite(np.r_[lo[free], hi[free]]).any():
        c[free] = _solve_unbounded(x[:, free], r)
    elif free.any():  # ||x c - r||² = ||a c - b||² + const, a = W^½ Vᵀ of xᵀx = V W Vᵀ
        norms = np.sqrt(np.einsum("ij,ij->j", x[:, free], x[:, free]))
        xs = x[:, free] / np.where(norms == 0, 1.0, norms)
        norms[norms == 0] = 1.0
        w, v = np.linalg.eigh(xs.T @ xs)
        keep = w > w[-1] * 1e-12
        sw = np.sqrt(w[keep])
        sol = optimize.lsq_linear(sw[:, None] * v[:, keep].T, (v[:, keep].T @ (xs.T @ r)) / sw,
                                  bounds=(lo[free] * norms, hi[free] * norms), method="bvls")
        c[free] = np.clip(sol.x / norms, lo[free], hi[free])
    return c


def _linear_bounds(terms: Sequence[Term], sig: Any) -> tuple[np.ndarray, np.ndarray] | None:
    """The terms' linear bounds concatenated, or None where all are infinite."""
    b = [x for t in terms for x in (t.linear_bounds(sig) if hasattr(t, "linear_bounds")
                                    else [(-np.inf, np.inf)] * t.n_linear)]
    if len(b) != sum(t.n_linear for t in terms):
        raise ValueError("linear_bounds() must give one (lo, hi) per linear coefficient")
    lo, hi = (np.array([x[i] for x in b], float) for i in (0, 1))
    return (lo, hi) if np.isfinite(np.r_[lo, hi]).any() else None


def _pieces(v: np.ndarray, sizes: Sequence[int]) -> list[np.ndarray]:
    """``v`` cut into consecutive pieces of the given sizes."""
    ends = np.cumsum(sizes, dtype=int)
    return [v[e - n:e] for n, e in zip(sizes, ends, strict=True)]


class _Packer:
    """Map between the concatenated nonlinear parameters and the optimiser's space."""

    def __init__(self, terms: Sequence[Term], sig: Any) -> None:
        self.sizes = [t.n_nonlinear for t in terms]
        self.logs = np.array([p.log for t in terms for p in t.nonlinear], bool)
        b = [bd for t in terms for bd in t.bounds(sig)]
        if len(b) != int(np.sum(self.sizes)):
            raise ValueError("bounds() must give one (lo, hi) per nonlinear parameter")
        self.lo = np.array([x[0] for x in b], float)
        self.hi = np.array([x[1] for x in b], float)
        if np.any(self.lo[self.logs] <= 0):
            raise ValueError("log-scaled nonlinear parameters need positive lower bounds")

    def clip(self, theta: np.ndarray) -> np.ndarray:
        # keep strictly inside for the optimiser
        span = self.hi - self.lo
        return np.clip(theta, self.lo + 1e-9 * span, self.hi - 1e-9 * span)

    def to_u(self, theta: np.ndarray) -> np.ndarray:
        t = self.clip(np.asarray(theta, float))
        return np.where(self.logs, np.log(np.where(self.logs, t, 1.0)), t)

    def from_u_partial(self, u: np.ndarray, mask: np.ndarray) -> np.ndarray:
        lg = self.logs[mask]
        return np.where(lg, np.exp(np.where(lg, u, 0.0)), u)

    def u_bounds(self) -> tuple[np.ndarray, np.ndarray]:
        lo = np.where(self.logs, np.log(np.where(self.logs, self.lo, 1.0)), self.lo)
        hi = np.where(self.logs, np.log(np.where(self.logs, self.hi, 1.0)), self.hi)
        return lo, hi

    def split(self, theta: np.ndarray) -> list[np.ndarray]:
        return _pieces(np.asarray(theta, float), self.sizes)


def _start_vectors(terms: Sequence[Term], sig: Any, y: np.ndarray, idx: np.ndarray,
                   starts: Sequence[Sequence[np.ndarray]] | None, pk: _Packer
                   ) -> list[np.ndarray]:
    """Every combination of the terms' starting θ vectors (the first 64), concatenated
    and clipped inside the bounds; default starts: each term's :meth:`Term.starts` with a
    zero residual."""
    if starts is None:
        z = np.zeros_like(y)
        starts = [t.starts(sig, z, idx) for t in terms]
    combos = itertools.islice(itertools.product(
        *[list(s) if len(s) else [np.empty(0)] for s in starts]), 64)
    return [pk.clip(np.concatenate([np.asarray(c, float) for c in combo]))
            if pk.lo.size else np.empty(0) for combo in combos]


def _free_mask(terms: Sequence[Term], fixed: Sequence[bool] | None, n_nl: int) -> np.ndarray:
    """Which of the ``n_nl`` nonlinear parameters are optimised: all but those of the
    ``fixed`` terms."""
    free = np.ones(n_nl, bool)
    if fixed is not None:
        if len(fixed) != len(terms):
            raise ValueError(f"fixed needs one flag per term ({len(terms)}), got {len(fixed)}")
        if n_nl:
            free = np.concatenate([np.full(t.n_nonlinear, not bool(f))
                                   for t, f in zip(terms, fixed, strict=True)])
    return free


def _optimise(resid: Callable[[np.ndarray], tuple[np.ndarray, np.ndarray]], pk: _Packer,
              flat: Sequence[np.ndarray], free: np.ndarray, max_starts: int, max_nfev: int
              ) -> tuple[np.ndarray, str, bool]:
    """The nonlinear parameters: the ``max_starts`` starts of lowest RSS optimised over
    the ``free`` parameters (bounded trust-region least squares, log-scaled where the
    term says so), the best kept; (θ, optimiser message, success)."""
    n_nl = pk.lo.size
    best_theta, best_rss, msg, ok = None, np.inf, "linear", True
    if n_nl == 0 or not free.any():
        best_theta = flat[0] if n_nl else np.empty(0)
        msg = "no free nonlinear parameters"
    else:
        scored = sorted(((float(np.sum(resid(f)[0] ** 2)), i) for i, f in enumerate(flat)))
        lo_u, hi_u = pk.u_bounds()
        for _, i in scored[:max_starts]:
            base = flat[i]

            def full(u: np.ndarray, base: np.ndarray = base) -> np.ndarray:
                th = base.copy()
                th[free] = pk.from_u_partial(u, free)
                return th

            u0 = pk.to_u(base)[free]
            try:
                sol = optimize.least_squares(lambda u: resid(full(u))[0], u0,
                                    bounds=(lo_u[free], hi_u[free]), method="trf",
                                    x_scale="jac", max_nfev=max_nfev, diff_step=1e-5)
            except (np.linalg.LinAlgError, ValueError) as e:  # pragma: no cover
                log.debug("start %d failed: %s", i, e)
                continue
            rss = float(np.sum(sol.fun ** 2))
            if rss < best_rss:
                best_rss, best_theta, msg, ok = rss, full(sol.x), sol.message, sol.success
        if best_theta is None:  # pragma: no cover
            best_theta, msg, ok = flat[scored[0][1]], "all starts failed", False
    return best_theta, msg, ok


def _fit_result(terms: tuple[Term, ...], pk: _Packer, theta: np.ndarray,
                resid: Callable[[np.ndarray], tuple[np.ndarray, np.ndarray]], n: int,
                msg: str, ok: bool, n_held: int = 0) -> FitResult:
    """The fit at the nonlinear parameters ``theta`` on ``n`` samples: linear coefficients
    per term, RSS, σ, τ_int of the residual, BIC (no uncertainties yet; ``n_held``
    coefficients held by equal bounds are no parameters)."""
    r, c = resid(theta)
    k = int(c.size - n_held + pk.lo.size)
    if n <= k:
        raise ValueError(f"{n} fit samples for {k} parameters: need more samples")
    rss = float(np.sum(r * r))
    coefs = _pieces(np.asarray(c, float), [t.n_linear for t in terms])
    return FitResult(
        terms=terms, thetas=tuple(pk.split(theta)), coefs=tuple(coefs), n=n, k=k, rss=rss,
        sigma=float(np.sqrt(rss / (n - k))), tau_int=integrated_autocorr_time(r),
        bic=float(n * np.log(max(rss, 1e-300) / n) + k * np.log(n)), success=bool(ok),
        message=str(msg))


def fit_terms(
    terms: Sequence[Term],
    sig: Any,
    y: np.ndarray,
    idx: np.ndarray,
    starts: Sequence[Sequence[np.ndarray]] | None = None,
    *,
    max_starts: int = 3,
    max_nfev: int = 200,
    fixed: Sequence[bool] | None = None,
    max_rel_se: float = 0.5,
    max_abs_corr: float = 0.98,
    uncertainty: bool = True,
) -> FitResult:
    """Fit a sum of terms by separable least squares on the samples ``idx``.

    Parameters
    ----------
    terms : sequence of Term
        Model terms, applied in order (transform terms affect the terms after them).
    sig : object
        Signals passed to the terms (all samples: states integrate over the full series,
        only the target of the samples ``idx`` enters the fit).
    y : ndarray, shape (n,)
        Target [data units].
    idx : ndarray of int, shape (m,)
        Fit samples.
    starts : sequence, optional
        Per term, a list of starting θ vectors; default each term's :meth:`Term.starts`
        with a zero residual. Every combination is scored and the best ``max_starts``
        are optimised.
    max_nfev : int, default 200
        Function evaluations per optimisation.
    fixed : sequence of bool, optional
        Per term: hold its nonlinear parameters at the (first) start instead of
        optimising them (the linear coefficients of all terms are always refitted).
    max_rel_se : float, default 0.5
        Flag a reported parameter whose standard error exceeds this fraction of ``|value|``.
    max_abs_corr : float, default 0.98
        Note a reported parameter whose correlation with another exceeds this.
    uncertainty : bool, default True
        Compute standard errors (skip for fast candidate screening).

    Raises
    ------
    ValueError
        Fewer fit samples than parameters, or a non-finite target on the fit samples.
    """
    terms = tuple(terms)
    y = np.asarray(y, float)
    idx = np.asarray(idx)
    if not np.all(np.isfinite(y[idx])):
        raise ValueError("target has non-finite values on the fit samples")
    pk = _Packer(terms, sig)
    lb = _linear_bounds(terms, sig)
    cache: dict = {}

    def resid(theta_flat: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        th = pk.split(theta_flat)
        x = design_matrix(terms, sig, th, cache)[idx]
        c = _solve_unbounded(x, y[idx]) if lb is None else solve_linear(x, y[idx], *lb)
        return y[idx] - x @ c, c

    flat = _start_vectors(terms, sig, y, idx, starts, pk)
    free = _free_mask(terms, fixed, pk.lo.size)
    best_theta, msg, ok = _optimise(resid, pk, flat, free, max_starts, max_nfev)
    res = _fit_result(terms, pk, best_theta, resid, int(idx.size), msg, ok,
                      0 if lb is None else int(np.sum(lb[0] == lb[1])))
    if uncertainty:
        _uncertainty(res, sig, idx, max_rel_se, max_abs_corr, cache)
    return res


def with_uncertainty(result: FitResult, sig: Any, idx: np.ndarray, max_rel_se: float = 0.5,
                     max_abs_corr: float = 0.98, tau_int: float | None = None) -> FitResult:
    """Copy of ``result`` with standard errors and identifiability flags (see
    :func:`fit_terms`); ``idx`` must be the samples it was fitted on. ``tau_int``
    overrides the autocorrelation time used to inflate the covariance [samples]."""
    res = dataclasses.replace(result, estimates=[])
    if tau_int is not None:
        res.tau_int = float(max(tau_int, 1.0))
    _uncertainty(res, sig, np.asarray(idx), max_rel_se, max_abs_corr, {})
    return res


def _uncertainty(res: FitResult, sig: Any, idx: np.ndarray, max_rel_se: float,
                 max_abs_corr: float, cache: dict) -> None:
    """Covariance of the raw parameters, delta method to the reported ones, flags."""
    terms, thetas, coefs = res.terms, list(res.thetas), list(res.coefs)
    c_all = np.concatenate(coefs) if coefs else np.empty(0)
    lb = _linear_bounds(terms, sig)
    bound_of = _bound_notes(terms, sig, c_all, thetas, lb)
    x = design_matrix(terms, sig, thetas, cache)[idx]
    cols = [x]
    for j, t in enumerate(terms):
        for m in range(t.n_nonlinear):
            th0 = thetas[j][m]
            h = 1e-4 * max(abs(th0), 1e-12) if t.nonlinear[m].log else 1e-4 * max(
                abs(th0), 1e-3)
            preds = []
            for s in (+1, -1):
                th = [a.copy() for a in thetas]
                th[j][m] = th0 + s * h
                preds.append(design_matrix(terms, sig, th, cache)[idx] @ c_all)
            cols.append(((preds[0] - preds[1]) / (2 * h))[:, None])
    jac = np.hstack(cols)  # (m, n_lin + n_nl): d prediction / d raw parameter
    # a coefficient held by equal bounds or by an active one varies no more: no variance
    held = np.zeros(c_all.size, bool) if lb is None else (lb[0] == lb[1]) | np.isclose(
        c_all, lb[0], 1e-9, 1e-12) | np.isclose(c_all, lb[1], 1e-9, 1e-12)
    fitted = np.r_[~held, np.ones(jac.shape[1] - c_all.size, bool)]
    cov_raw, res.cond = _raw_covariance(jac, fitted, res.sigma, res.tau_int)
    # order of raw parameters: all linear (term order), then all nonlinear (term order)
    raw_values = np.concatenate([c_all] + [np.asarray(t, float) for t in thetas])

    def derived_vec(v: np.ndarray) -> tuple[list[tuple[str, str, str]], np.ndarray]:
        parts = _pieces(v, [t.n_linear for t in terms] + [t.n_nonlinear for t in terms])
        cs, ts = parts[:len(terms)], parts[len(terms):]
        names, vals = [], []
        for t, cc, tt in zip(terms, cs, ts, strict=True):
            units = t.derived_units()
            for k, val in t.derived(cc, tt).items():
                names.append((t.name, k, units.get(k, "")))
                vals.append(val)
        return names, np.array(vals, float)

    names, d0 = derived_vec(raw_values)
    g = np.zeros((d0.size, raw_values.size))
    sd_raw = np.sqrt(np.maximum(np.diag(cov_raw), 0))
    for i in range(raw_values.size):
        h = max(1e-6 * abs(raw_values[i]), 1e-3 * sd_raw[i], 1e-12)
        vp, vm = raw_values.copy(), raw_values.copy()
        vp[i] += h
        vm[i] -= h
        g[:, i] = (derived_vec(vp)[1] - derived_vec(vm)[1]) / (2 * h)
    cov_d = g @ cov_raw @ g.T
    sd = np.sqrt(np.maximum(np.diag(cov_d), 0))
    with np.errstate(invalid="ignore", divide="ignore"):
        corr = cov_d / np.outer(sd, sd)
    est = []
    for i, (tn, pn, unit) in enumerate(names):
        flag, note = "", ""
        rel = sd[i] / abs(d0[i]) if d0[i] != 0 else np.inf
        if bound_of.get((tn, pn), "").startswith("held"):
            rel = 0.0
        if not np.isfinite(sd[i]):
            flag = "not determined (singular)"
        elif rel > max_rel_se:
            flag = f"weak (rel. s.e. {rel:.2g})"
        row = np.abs(np.nan_to_num(corr[i]))
        row[i] = 0
        j = int(np.argmax(row)) if row.size else 0
        if row.size and row[j] > max_abs_corr:
            note = f"correlated with {names[j][0]}.{names[j][1]} (r = {corr[i, j]:+.3f})"
        est.append(ParamEstimate(tn, pn, unit, float(d0[i]), float(sd[i]), flag, note,
                                 bound_of.get((tn, pn), "")))
    res.estimates = est


def _raw_covariance(jac: np.ndarray, fitted: np.ndarray, sigma: float, tau: float
                    ) -> tuple[np.ndarray, float]:
    """``σ² τ (JᵀJ)⁻¹`` over the ``fitted`` columns of ``jac`` (zero elsewhere; unbounded
    along directions the data do not determine), and cond of the column-scaled JᵀJ."""
    js = jac[:, fitted]
    scale = np.sqrt(np.sum(js * js, axis=0))
    scale[scale == 0] = 1.0
    js = js / scale
    u, sv, vt = np.linalg.svd(js.T @ js)
    ok = sv > sv[0] * 1e-12
    inv = (vt.T / np.where(ok, sv, np.inf)) @ u.T + 1e20 * vt[~ok].T @ vt[~ok]
    cov = np.zeros((fitted.size, fitted.size))
    cov[np.ix_(fitted, fitted)] = inv / np.outer(scale, scale) * sigma ** 2 * tau
    return cov, float(sv[0] / sv[-1]) if sv[-1] > 0 else float("inf")


def _bound_notes(terms: Sequence[Term], sig: Any, c_all: np.ndarray,
                 thetas: Sequence[np.ndarray], lb: tuple[np.ndarray, np.ndarray] | None
                 ) -> dict[tuple[str, str], str]:
    """(term, raw parameter) -> :attr:`ParamEstimate.bound`: a linear one within 1e-9
    (relative) of a bound, a nonlinear one within 1e-4 of its box's width."""
    out = [""] * c_all.size
    for i, (v, lo, hi) in enumerate(zip(c_all, *lb, strict=True) if lb is not None else ()):
        on = [w for w, b in (("lower", lo), ("upper", hi)) if np.isclose(v, b, 1e-9, 1e-12)]
        out[i] = f"held at {lo:.4g}" if lo == hi else (
            f"on its {on[0]} bound {v:.4g}" if on else "")
    pk = _Packer(terms, sig)
    th = np.concatenate([np.asarray(t, float) for t in thetas] or [np.empty(0)])
    u = np.where(pk.logs, np.log(np.where(pk.logs, np.maximum(th, 1e-300), 1.0)), th)
    lo_u, hi_u = pk.u_bounds()
    tol = np.where(np.isfinite(hi_u - lo_u), 1e-4 * (hi_u - lo_u), 0.0)
    out += [f"on its lower bound {a:.4g}" if uu - ul <= d else
            f"on its upper bound {b:.4g}" if uh - uu <= d else ""
            for uu, ul, uh, d, a, b in zip(u, lo_u, hi_u, tol, pk.lo, pk.hi, strict=True)]
    keys = [(t.name, q.name) for t in terms for q in t.linear] + [
        (t.name, q.name) for t in terms for q in t.nonlinear]
    return {k: b for k, b in zip(keys, out, strict=True) if b}


def physical_check(fit: FitResult) -> list[str]:
    """Why a fitted model is not physical: each parameter the fit left on a bound
    (:attr:`swgcal.core.ParamEstimate.bound`) and each outside its physical range with its
    source (:meth:`swgcal.terms.FitTerm.range_violations`).

    Parameters
    ----------
    fit : FitResult
        With uncertainties (its ``estimates``).

    Returns
    -------
    list of str
        E.g. ``"first_order.r_th_k_per_w = 0 K/W on its lower bound 0"``; empty: physical.
    """
    out = []
    for t in fit.terms:
        est = fit.estimates_of(t.name)
        out += [f"{t.name}.{k} = {e.value:.4g} {e.unit} {e.bound}"
                for k, e in est.items() if e.on_bound]
        out += [f"{t.name}.{v}" for v in t.range_violations({k: e.value for k, e in est.items()})]
    return out
