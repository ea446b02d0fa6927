"""Model terms: named parameters, the term interface, evaluation of a sum of terms.

Used by the simulator (friction effects as an input of the dynamics,
:mod:`swgsim.gear.friction`) and by the calibration, which fits such sums
(:mod:`swgcal.core`) and adds what only a fit needs (bounds, starts, probes, physical
ranges: :class:`swgcal.terms.FitTerm`).

A model is a sum of *terms*. Each term contributes columns ``X_j(θ_j)`` times linear
coefficients ``c_j`` to the prediction ``ŷ = Σ_j X_j(θ_j) c_j``; ``θ_j`` are its nonlinear
parameters (a ripple period, a time constant). A term may instead *transform* the
signals every later term sees (a lag of the velocity seen by the friction law). The
signals object is domain specific; the fitting (:mod:`swgcal.core`) only
calls term methods, so each side (friction, strain) plugs in by defining its own signals
and terms.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np

__all__ = ["Param", "Term", "design_matrix", "evaluate_terms", "linear_recurrence"]


# ---------------------------------------------------------------------------------------
# terms


@dataclass(frozen=True)
class Param:
    """A named parameter of a term.

    Attributes
    ----------
    name : str
        Identifier, unique within the term.
    unit : str
        Unit, e.g. ``"N m"``, ``"rad"``, ``"-"``.
    description : str
        One line.
    log : bool
        Nonlinear parameters only: a positive scale parameter (a time constant, a
        period; a fit optimises its logarithm).
    """

    name: str
    unit: str = "-"
    description: str = ""
    log: bool = False


class Term:
    """One additive term (or signal transform) of a model. Subclass and override.

    Attributes
    ----------
    kind : str
        Library key (``"stribeck"``); the instance ``name`` adds ``#2`` for a repeat.
    linear : tuple of Param
        Coefficients of the columns returned by :meth:`columns`.
    nonlinear : tuple of Param
        Parameters entering the columns nonlinearly.
    is_transform : bool
        True: the term has no columns and changes the signals later terms see
        (:meth:`transform`).
    description, source : str
        What the term models and where its form comes from.
    """

    kind: str = "term"
    linear: tuple[Param, ...] = ()
    nonlinear: tuple[Param, ...] = ()
    is_transform: bool = False
    description: str = ""
    source: str = ""

    def __init__(self, name: str | None = None) -> None:
        self.name = name or self.kind

    def __repr__(self) -> str:
        return f"{type(self).__name__}(name={self.name!r})"

    # -- to override -------------------------------------------------------------------
    @classmethod
    def for_signals(cls, sig: Any, name: str | None = None) -> Term:
        """Instance suited to these signals (e.g. with or without a load column)."""
        return cls(name)

    def applicable(self, sig: Any) -> bool:
        """Whether the term can be evaluated on these signals (e.g. a load column)."""
        return True

    def columns(self, sig: Any, theta: np.ndarray) -> np.ndarray:
        """Design columns, shape (n, len(linear))."""
        raise NotImplementedError

    def transform(self, sig: Any, theta: np.ndarray) -> Any:
        """Signals seen by later terms (``is_transform`` terms only)."""
        return sig

    def derived(self, coef: np.ndarray, theta: np.ndarray) -> dict[str, float]:
        """Reported parameters (default: the raw ones, :meth:`to_params`). Override for
        amplitude/phase."""
        return self.to_params(coef, theta)

    def derived_units(self) -> dict[str, str]:
        """Units of :meth:`derived` entries."""
        return {p.name: p.unit for p in (*self.linear, *self.nonlinear)}

    def primary(self) -> tuple[str, ...]:
        """Names of the derived parameters that characterise the effect."""
        return tuple(self.derived_units())

    def options(self) -> dict[str, Any]:
        """Constructor options other than the name (e.g. ``use_load``), for specs."""
        return {}

    def required_options(self) -> tuple[str, ...]:
        """Options a spec must give (no safe default, e.g. the calibrated range)."""
        return ()

    # -- generic -----------------------------------------------------------------------
    @property
    def n_linear(self) -> int:
        return len(self.linear)

    @property
    def n_nonlinear(self) -> int:
        return len(self.nonlinear)

    def raw_names(self) -> list[str]:
        return [p.name for p in self.linear] + [p.name for p in self.nonlinear]

    def from_params(self, params: dict[str, float]) -> tuple[np.ndarray, np.ndarray]:
        """(coef, theta) from a mapping of raw parameter names to values.

        Raises
        ------
        KeyError
            A raw parameter is missing; the message lists the expected names.
        """
        missing = [n for n in self.raw_names() if n not in params]
        if missing:
            raise KeyError(f"effect {self.kind!r} needs parameters {self.raw_names()}, "
                           f"missing {missing}")
        extra = sorted(set(params) - set(self.raw_names()))
        if extra:
            raise KeyError(f"effect {self.kind!r} has no parameters {extra}; "
                           f"expected {self.raw_names()}")
        coef = np.array([float(params[p.name]) for p in self.linear])
        theta = np.array([float(params[p.name]) for p in self.nonlinear])
        return coef, theta

    def to_params(self, coef: np.ndarray, theta: np.ndarray) -> dict[str, float]:
        """Raw parameter mapping (inverse of :meth:`from_params`)."""
        out = {p.name: float(v) for p, v in zip(self.linear, coef, strict=True)}
        out.update({p.name: float(v) for p, v in zip(self.nonlinear, theta, strict=True)})
        return out

    def predict(self, sig: Any, coef: np.ndarray, theta: np.ndarray) -> np.ndarray:
        """Contribution ``columns(sig, theta) @ coef``, shape (n,)."""
        return self.columns(sig, np.asarray(theta, float)) @ np.asarray(coef, float)


# ---------------------------------------------------------------------------------------
# evaluation


def design_matrix(terms: Sequence[Term], sig: Any, thetas: Sequence[np.ndarray],
            cache: dict | None = None) -> np.ndarray:
    """Design matrix of a sum of terms: the columns of all terms side by side,
    transform terms applied in order to the signals every later term sees.

    Parameters
    ----------
    terms : sequence of Term
    sig : object
        Signals of the terms' side (e.g. :class:`swgsim.gear.friction.FrictionSignals`).
    thetas : sequence of ndarray
        Nonlinear parameters per term (empty arrays where none).
    cache : dict, optional
        Column cache keyed by term, θ and the transforms before it (cleared above 256
        entries); reused across calls of one fit.

    Returns
    -------
    ndarray, shape (n, Σ n_linear)
    """
    s = sig
    tkey: tuple = ()
    mats = []
    n = None
    for i, (term, th) in enumerate(zip(terms, thetas, strict=True)):
        th = np.asarray(th, float)
        if term.is_transform:
            s = term.transform(s, th)
            tkey = tkey + (i, th.tobytes())
            continue
        if term.n_linear == 0:
            continue
        key = (i, id(term), th.tobytes(), tkey)
        if cache is not None and key in cache:
            cols = cache[key]
        else:
            cols = np.asarray(term.columns(s, th), float)
            if cols.ndim == 1:
                cols = cols[:, None]
            if cache is not None:
                if len(cache) > 256:
                    cache.clear()
                cache[key] = cols
        n = cols.shape[0]
        mats.append(cols)
    if not mats:
        return np.zeros((n or 0, 0))
    return np.hstack(mats)


def evaluate_terms(terms: Sequence[Term], sig: Any, coefs: Sequence[np.ndarray],
                   thetas: Sequence[np.ndarray]) -> np.ndarray:
    """Prediction of a sum of terms with given parameters (transform terms first).

    Parameters
    ----------
    terms : sequence of Term
    sig : object
        Signals.
    coefs, thetas : sequence of ndarray
        Linear and nonlinear parameters per term (empty arrays where none).

    Returns
    -------
    ndarray, shape (n,)
    """
    c = [np.asarray(x, float) for x in coefs]
    return design_matrix(terms, sig, [np.asarray(x, float) for x in thetas]) @ (
        np.concatenate(c) if c else np.empty(0))


def linear_recurrence(a: np.ndarray, b: np.ndarray, x0: float = 0.0) -> np.ndarray:
    """Solve ``x_k = a_k x_{k-1} + b_k`` for all k at once (``x_{-1} = x0``).

    Vectorised by a doubling (Hillis-Steele) scan over the affine maps
    ``x -> a_k x + b_k``: log2(n) numpy passes instead of a Python loop, exact up to
    round-off. Used for states integrated along irregularly sampled series (presliding
    state, first-order lags).

    Parameters
    ----------
    a, b : ndarray, shape (n,)
        Coefficients of the recurrence.
    x0 : float, default 0
        State before the first sample.

    Returns
    -------
    ndarray, shape (n,)
        The states ``x_0 .. x_{n-1}``.
    """
    a = np.array(a, dtype=float)
    b = np.array(b, dtype=float)
    if a.shape != b.shape or a.ndim != 1:
        raise ValueError(f"a and b must be 1-D of equal shape, got {a.shape} and {b.shape}")
    n = a.size
    shift = 1
    while shift < n:
        # compose map k-shift (applied first) with map k: x -> a_k (a_j x + b_j) + b_k
        b[shift:] = a[shift:] * b[:-shift] + b[shift:]
        a[shift:] = a[shift:] * a[:-shift]
        shift *= 2
    return a * x0 + b
