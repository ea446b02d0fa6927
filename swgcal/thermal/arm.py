"""Joints not used in the fit: does an effect kept on one joint help the others?

Each joint of a log is calibrated on its own (:func:`swgcal.thermal.calibrate`). An effect
kept there is then carried to every other joint with the time constants it was fitted
with (its nonlinear parameters held; its gain and the other joint's base model refitted
on that joint's fit part, since the joints differ in size), and its error on that joint's
held-out part (validation and test, after the gap) compared with the base model's alone,
on the loop's evidence scale (:mod:`swgcal.loop`: 2 ln Λ = (n / τ_int) ln(RMSE_base² /
RMSE_with²), τ_int of the base's held-out residual). An effect holds for the arm when it
passes on most of the joints it was not fitted on [choice: a majority, as the joints
differ in size, load and place].
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any

import numpy as np

from ..core import fit_terms, integrated_autocorr_time
from ..loop import CalibrationResult, SelectionConfig

__all__ = ["transfer_effects"]


def _heldout_rmse(result: CalibrationResult, terms, starts, fixed) -> tuple[float, np.ndarray]:
    """RMSE on the held-out part of a model fitted on the fit part, and its residual."""
    p = result.problem
    f = fit_terms(terms, p.signals, p.y, p.split.fit, starts, fixed=fixed, uncertainty=False,
                  max_starts=1)
    idx = np.concatenate([p.split.validation, p.split.test])
    r = (p.y - f.predict(p.signals))[idx]
    return float(np.sqrt(np.mean(r * r))), r


def transfer_effects(results: Sequence[CalibrationResult],
                     config: SelectionConfig | None = None) -> list[dict[str, Any]]:
    """Carry every effect kept on one joint to the others (module docstring).

    Parameters
    ----------
    results : sequence of CalibrationResult
        One per joint (thermal problems), e.g. of the six joints of a log.
    config : SelectionConfig, optional
        Its ``min_heldout_evidence`` is the bar (10).

    Returns
    -------
    list of dict
        One per effect kept: ``effect``, ``from_joint``, ``nonlinear`` (the time constants
        carried), ``to`` (per other joint: ``joint``, ``rmse_base``, ``rmse_with`` [K] on
        its held-out part, ``evidence`` 2 ln Λ, ``passes``), ``passes_on`` (count),
        ``holds_for_arm`` (a majority of the others).
    """
    bar = (config or SelectionConfig()).min_heldout_evidence
    out = []
    for rj in results:
        for term in rj.effect_terms():
            theta = rj.final.thetas[rj.final.terms.index(term)]
            rows = []
            for rk in results:
                if rk is rj:
                    continue
                base = rk.base_model_final
                b, r_b = _heldout_rmse(rk, base.terms, [[base.thetas[0]]], [False])
                a, _ = _heldout_rmse(rk, (*base.terms, type(term)()),
                                     [[base.thetas[0]], [theta]], [False, True])
                tau = max(integrated_autocorr_time(r_b), 1.0)
                ev = float(r_b.size / tau * np.log(b * b / (a * a)))
                rows.append({"joint": rk.problem.meta.get("joint"), "rmse_base": b,
                             "rmse_with": a, "evidence": ev, "passes": ev > bar})
            n_pass = sum(r["passes"] for r in rows)
            out.append({"effect": term.name, "from_joint": rj.problem.meta.get("joint"),
                        "nonlinear": {p.name: float(v) for p, v in zip(term.nonlinear, theta,
                                                                        strict=True)},
                        "to": rows, "passes_on": n_pass,
                        "holds_for_arm": 2 * n_pass > len(rows)})
    return out
