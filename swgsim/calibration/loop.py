"""The calibration loop: fit, diagnose, try every candidate effect, keep the best one if
it earns its place, repeat; then report the error before and after on test data.

Generic over the domain: a :class:`Problem` bundles the signals, the target, the
baseline terms, a library of candidate effects (term classes), the residual probes and
the held-out split. The friction side builds one with
:func:`swgsim.calibration.friction_problem`; a strain-side library plugs in the same way.

Acceptance rule (ARCHITECTURE.md, "Calibration loop"): a candidate is kept only if it
lowers the validation RMSE by more than ``min_rel_improvement`` (relative) *and* lowers
the BIC on the fit samples by more than ``-max_delta_bic``. Candidates are ranked by
validation RMSE. The loop stops when the best candidate fails the rule. After the loop
the final residual is diagnosed; if it is still structured the result says so
(``unexplained``) and describes the signature, whatever was added before.

Errors before and after are computed on the test samples, which neither the fit nor the
selection has seen, by the baseline and the final model refitted on fit + validation.
"""

from __future__ import annotations

import logging
import time
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from .core import FitResult, Term, fit_terms
from .diagnose import Diagnosis, Probe, diagnose
from .split import HeldOutSplit

log = logging.getLogger(__name__)

__all__ = ["Problem", "SelectionConfig", "CandidateScore", "Iteration", "CalibrationResult",
           "calibrate"]


@dataclass
class Problem:
    """Everything the loop needs, domain independent.

    Attributes
    ----------
    name : str
        Data name (file stem).
    kind : str
        ``"friction"`` or ``"strain"``.
    units : str
        Units of the target.
    signals : object
        Passed to terms and probes.
    y : ndarray, shape (n,)
        Target.
    t : ndarray, shape (n,)
        Time [s] (probes' halves, noise floor).
    baseline : tuple of Term
    library : mapping of str to Term class
        Candidate effects by key.
    probes : sequence of Probe
    split : HeldOutSplit
    meta : dict
        Anything to carry into the report.
    """

    name: str
    kind: str
    units: str
    signals: Any
    y: np.ndarray
    t: np.ndarray
    baseline: tuple[Term, ...]
    library: Mapping[str, type[Term]]
    probes: Sequence[Probe]
    split: HeldOutSplit
    meta: dict[str, Any] = field(default_factory=dict)


@dataclass(frozen=True)
class SelectionConfig:
    """Settings of the selection loop.

    Attributes
    ----------
    min_rel_improvement : float, default 0.02
        Required relative drop of the validation RMSE.
    max_delta_bic : float, default -10
        Required BIC change on the fit samples (more negative is better).
    max_iter : int, default 8
        At most this many effects are added.
    candidates : sequence of str, optional
        Library keys to try (default: the whole library).
    structure_threshold : float, default 0.03
        Probe score from which a residual counts as structured.
    max_rel_se, max_abs_corr : float
        Identifiability flags (see :func:`~swgsim.calibration.core.fit_terms`).
    max_starts : int, default 3
        Optimisations per candidate fit (best starting points).
    """

    min_rel_improvement: float = 0.02
    max_delta_bic: float = -10.0
    max_iter: int = 8
    candidates: Sequence[str] | None = None
    structure_threshold: float = 0.03
    max_rel_se: float = 0.5
    max_abs_corr: float = 0.98
    max_starts: int = 3

    def __post_init__(self) -> None:
        if not 0 <= self.min_rel_improvement < 1:
            raise ValueError("min_rel_improvement must be in [0, 1), got "
                             f"{self.min_rel_improvement}")
        if self.max_delta_bic > 0:
            raise ValueError(f"max_delta_bic must be <= 0, got {self.max_delta_bic}")
        if self.max_iter < 0:
            raise ValueError(f"max_iter must be >= 0, got {self.max_iter}")


@dataclass
class CandidateScore:
    """One candidate tried in one iteration.

    Attributes
    ----------
    name, kind : str
    val_rmse : float
        Validation RMSE with the candidate added [data units].
    rel_improvement : float
        1 − val_rmse / current validation RMSE.
    delta_bic : float
        BIC change on the fit samples.
    accepted : bool
    params : dict
        Derived parameters of the candidate (values only).
    fit : FitResult
    """

    name: str
    kind: str
    val_rmse: float
    rel_improvement: float
    delta_bic: float
    accepted: bool
    params: dict[str, float]
    fit: FitResult | None = None

    def as_dict(self) -> dict[str, Any]:
        return {"name": self.name, "kind": self.kind, "val_rmse": self.val_rmse,
                "rel_improvement": self.rel_improvement, "delta_bic": self.delta_bic,
                "accepted": self.accepted, "params": self.params}


@dataclass
class Iteration:
    """One pass of the loop: the model before it, the diagnosis, the ranked candidates."""

    index: int
    model: list[str]
    val_rmse: float
    bic: float
    diagnosis: Diagnosis
    candidates: list[CandidateScore]
    accepted: str | None

    def as_dict(self) -> dict[str, Any]:
        return {"index": self.index, "model": self.model, "val_rmse": self.val_rmse,
                "bic": self.bic, "diagnosis": self.diagnosis.as_dict(),
                "candidates": [c.as_dict() for c in self.candidates],
                "accepted": self.accepted}


@dataclass
class CalibrationResult:
    """Outcome of :func:`calibrate`.

    Attributes
    ----------
    problem : Problem
    config : SelectionConfig
    iterations : list of Iteration
    added : list of str
        Names of the accepted effects, in order.
    baseline_final, final : FitResult
        Baseline and final model refitted on fit + validation samples.
    rmse : dict
        ``{"fit"|"validation"|"test": {"before": x, "after": y}}`` [data units];
        fit/validation from the selection fits, test from the final refits.
    diag_before, diag_after : Diagnosis
        Residual diagnosis of the baseline and of the final model (fit + validation).
    unexplained : bool
        The final residual is still structured.
    residual_signature : str
    elapsed_s : float
    """

    problem: Problem
    config: SelectionConfig
    iterations: list[Iteration]
    added: list[str]
    baseline_final: FitResult
    final: FitResult
    rmse: dict[str, dict[str, float]]
    diag_before: Diagnosis
    diag_after: Diagnosis
    unexplained: bool
    residual_signature: str
    elapsed_s: float = 0.0

    @property
    def rmse_before(self) -> float:
        return self.rmse["test"]["before"]

    @property
    def rmse_after(self) -> float:
        return self.rmse["test"]["after"]

    def effect_terms(self) -> list[Term]:
        """Accepted effect terms of the final model, in order of acceptance."""
        by = {t.name: t for t in self.final.terms}
        return [by[n] for n in self.added]

    def predictions(self) -> tuple[np.ndarray, np.ndarray]:
        """Predictions of the baseline and the final model on all samples."""
        sig = self.problem.signals
        return self.baseline_final.predict(sig), self.final.predict(sig)


def _rmse(r: np.ndarray) -> float:
    return float(np.sqrt(np.mean(r * r))) if r.size else float("nan")


def _order(terms: Sequence[Term]) -> tuple[Term, ...]:
    """Transform terms first (they change what the others see), others in order."""
    return tuple([t for t in terms if t.is_transform] + [t for t in terms if not t.is_transform])


def _instance_name(kind: str, terms: Sequence[Term]) -> str:
    k = sum(1 for t in terms if t.kind == kind)
    return kind if k == 0 else f"{kind}#{k + 1}"


def calibrate(problem: Problem, config: SelectionConfig | None = None) -> CalibrationResult:
    """Run the calibration loop on a problem.

    Parameters
    ----------
    problem : Problem
    config : SelectionConfig, optional

    Returns
    -------
    CalibrationResult

    Raises
    ------
    KeyError
        ``config.candidates`` names an effect that is not in the library.
    """
    cfg = config or SelectionConfig()
    t_start = time.perf_counter()
    sig, y, sp = problem.signals, problem.y, problem.split
    keys = list(cfg.candidates) if cfg.candidates is not None else list(problem.library)
    unknown = [k for k in keys if k not in problem.library]
    if unknown:
        raise KeyError(f"candidates {unknown} not in the library {sorted(problem.library)}")
    fit_kw = dict(max_rel_se=cfg.max_rel_se, max_abs_corr=cfg.max_abs_corr,
                  max_starts=cfg.max_starts)

    def score(fit: FitResult) -> tuple[np.ndarray, float]:
        r = y - fit.predict(sig)
        return r, _rmse(r[sp.validation])

    current = fit_terms(_order(problem.baseline), sig, y, sp.fit, uncertainty=False, **fit_kw)
    baseline_sel = current
    r_cur, val_cur = score(current)
    iterations: list[Iteration] = []
    added: list[str] = []
    diag_idx = sp.fit
    for it in range(cfg.max_iter + 1):
        diag = diagnose(sig, problem.t, r_cur, diag_idx, problem.probes, problem.units,
                        cfg.structure_threshold)
        cands: list[CandidateScore] = []
        if it < cfg.max_iter:
            for key in keys:
                cls = problem.library[key]
                present = sum(1 for t in current.terms if t.kind == key)
                if present >= cls.repeatable:
                    continue
                term = cls.for_signals(sig, _instance_name(key, current.terms))
                if not term.applicable(sig):
                    continue
                terms = _order(list(current.terms) + [term])
                cur_th = {t.name: th for t, th in zip(current.terms, current.thetas)}
                starts = [[cur_th[t.name]] if t.name in cur_th else t.starts(sig, r_cur, sp.fit)
                          for t in terms]
                try:
                    f = fit_terms(terms, sig, y, sp.fit, starts, uncertainty=False, **fit_kw)
                except (ValueError, np.linalg.LinAlgError) as e:
                    log.warning("candidate %s failed: %s", term.name, e)
                    continue
                _, v = score(f)
                i = f.terms.index(term)
                cands.append(CandidateScore(
                    name=term.name, kind=key, val_rmse=v,
                    rel_improvement=1.0 - v / val_cur if val_cur > 0 else 0.0,
                    delta_bic=f.bic - current.bic, accepted=False,
                    params=term.derived(f.coefs[i], f.thetas[i]), fit=f))
            cands.sort(key=lambda c: c.val_rmse)
        best = cands[0] if cands else None
        ok = (best is not None and best.rel_improvement > cfg.min_rel_improvement
              and best.delta_bic < cfg.max_delta_bic)
        if ok:
            best.accepted = True
        iterations.append(Iteration(it, [t.name for t in current.terms], val_cur, current.bic,
                                    diag, cands, best.name if ok else None))
        log.info("%s iteration %d: val RMSE %.4g, best %s (%.4g, dBIC %.1f) -> %s",
                 problem.name, it, val_cur, best.name if best else None,
                 best.val_rmse if best else np.nan, best.delta_bic if best else np.nan,
                 "accepted" if ok else "stop")
        if not ok:
            break
        current = best.fit
        added.append(best.name)
        r_cur, val_cur = score(current)

    # final refits on fit + validation; test errors
    idx_fv = sp.fit_validation
    base_final = fit_terms(_order(problem.baseline), sig, y, idx_fv, **fit_kw)
    starts = [[th] for th in current.thetas]
    final = fit_terms(current.terms, sig, y, idx_fv, starts, **fit_kw)
    r_b = y - base_final.predict(sig)
    r_a = y - final.predict(sig)
    r_bs = y - baseline_sel.predict(sig)
    rmse = {
        "fit": {"before": _rmse(r_bs[sp.fit]), "after": _rmse(r_cur[sp.fit])},
        "validation": {"before": _rmse(r_bs[sp.validation]), "after": val_cur},
        "test": {"before": _rmse(r_b[sp.test]), "after": _rmse(r_a[sp.test])},
    }
    d_before = diagnose(sig, problem.t, r_b, idx_fv, problem.probes, problem.units,
                        cfg.structure_threshold)
    d_after = d_before if not added else diagnose(sig, problem.t, r_a, idx_fv, problem.probes,
                                                  problem.units, cfg.structure_threshold)
    res = CalibrationResult(
        problem=problem, config=cfg, iterations=iterations, added=added,
        baseline_final=base_final, final=final, rmse=rmse, diag_before=d_before,
        diag_after=d_after, unexplained=d_after.structured,
        residual_signature=d_after.signature, elapsed_s=time.perf_counter() - t_start)
    log.info("%s: test RMSE %.4g -> %.4g, added %s, unexplained %s", problem.name,
             rmse["test"]["before"], rmse["test"]["after"], added, res.unexplained)
    return res
