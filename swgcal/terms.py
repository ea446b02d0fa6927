"""Model terms as the calibration fits them: a simulator form plus the fit's vocabulary.

A term's form (its parameters, columns or transform, reported parameters) is the
simulator's (:class:`swgsim.gear.terms.Term`: friction effects in :mod:`swgsim.gear.friction`,
evaluated by the dynamics). What only a fit needs lives here, on :class:`FitTerm`:
box bounds and starting values of the nonlinear parameters, how many instances a model
may hold, the residual signature and the diagnosis probes the term should explain, and
the physical ranges outside which a fit is not accepted as the effect. A fitted effect
subclasses its form and :class:`FitTerm` (:mod:`swgcal.friction.library`); a term only
the calibration uses (the strain side, :mod:`swgcal.strain.effects`) subclasses
:class:`FitTerm` alone.
"""

from __future__ import annotations

from typing import Any

import numpy as np

from swgsim.gear.terms import Term

__all__ = ["FitTerm"]


class FitTerm(Term):
    """A :class:`swgsim.gear.terms.Term` with what its fit needs. Subclass and override.

    Attributes
    ----------
    repeatable : int
        How many instances a model may hold (1: once).
    signature : str
        How the term shows in the residual of a model without it.
    probes : tuple of str
        Names of the diagnosis probes whose structure it should explain.
    ranges : dict of str to (float, float, str)
        Physical range of a :meth:`~swgsim.gear.terms.Term.derived` parameter,
        ``name -> (low, high, source)`` in the parameter's unit (bounds inclusive;
        ``-inf``/``inf`` for an open side). A fit outside the range is not accepted as
        this effect (:meth:`range_violations`): the term would be absorbing something
        else.
    acts_on : tuple of str
        A transform's (``is_transform``) library kinds whose columns it changes; while the
        model holds none of them the loop tries it together with a fresh instance of each
        (alone it would change nothing). Empty: the term is tried alone.
    """

    repeatable: int = 1
    acts_on: tuple[str, ...] = ()
    signature: str = ""
    probes: tuple[str, ...] = ()
    ranges: dict[str, tuple[float, float, str]] = {}

    def bounds(self, sig: Any) -> list[tuple[float, float]]:
        """Box bounds of the nonlinear parameters [their units], data dependent."""
        return []

    def linear_bounds(self, sig: Any) -> list[tuple[float, float]]:
        """Bounds of the linear coefficients [their units], data dependent: a physical
        sign or range the fit may not leave (:func:`swgcal.core.solve_linear`); equal
        bounds hold a coefficient at their value. Default unbounded (the fast unbounded
        solve, unchanged)."""
        return [(-np.inf, np.inf)] * self.n_linear

    def starts(self, sig: Any, residual: np.ndarray, idx: np.ndarray) -> list[np.ndarray]:
        """Starting values of the nonlinear parameters (may use the current residual)."""
        return [np.empty(0)]

    def range_violations(self, values: dict[str, float]) -> list[str]:
        """Derived parameters outside their physical range (:attr:`ranges`).

        Parameters
        ----------
        values : dict of str to float
            Derived parameters (:meth:`~swgsim.gear.terms.Term.derived`), in
            :meth:`~swgsim.gear.terms.Term.derived_units`.

        Returns
        -------
        list of str
            One phrase per violation, e.g. ``"t_lag_s = 0.6 s outside [0.0001, 0.05] s
            (Al-Bender et al. 2005)"``; empty when every ranged parameter is inside.
        """
        units = self.derived_units()
        out = []
        for name, (lo, hi, src) in self.ranges.items():
            if name not in values:
                continue
            v = float(values[name])
            if not lo <= v <= hi:
                u = units.get(name, "")
                u = f" {u}" if u and u != "-" else ""
                out.append(f"{name} = {v:.3g}{u} outside [{lo:g}, {hi:g}]{u} ({src})")
        return out
