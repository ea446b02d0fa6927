"""The calibration loop: fit, diagnose, try every candidate effect, keep the best one if
it earns its place, repeat; then report the error before and after on test data.

Generic over the domain: each data kind builds a :class:`Problem`
(:func:`swgcal.friction.build_problem`, ...) and calls :func:`select_effects` in its
``calibrate`` step (a :class:`CalibrationResult`). A candidate is accepted on held-out and
fit evidence on one scale (2 ln B above 10, with the effective sample count n / τ_int),
well-determined parameters and a physical range (:class:`SelectionConfig`). The rule, its
sources, stopping and pairs: docs/calibration.md, "The acceptance rule in full".
"""

from __future__ import annotations

import dataclasses
import logging
import time
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from swgsim.base.typed import allowed, check_ranges

from .core import FitResult, Term, fit_terms, with_uncertainty
from .diagnose import WHITENESS_RATIO, Diagnosis, Probe, diagnose, whiteness
from .split import HeldOutSplit

log = logging.getLogger(__name__)

__all__ = ["Problem", "SelectionConfig", "CandidateScore", "Iteration", "CalibrationResult",
           "select_effects", "refit_final", "gain_floor", "paired_gain", "check_candidates",
           "IMPLAUSIBLE_PREFIX"]

#: Status of a candidate rejected for a parameter outside its physical range, before them.
IMPLAUSIBLE_PREFIX = "rejected: outside its physical range: "
#: How the final verdict's signature notes such a candidate.
_IMPLAUSIBLE_NOTE = ". A library candidate outside its physical range"


@dataclass
class Problem:
    """Everything the loop needs, domain independent.

    Attributes
    ----------
    name, kind, units : str
        Data name (file stem); ``"friction"``, ``"strain"`` or ``"thermal"``; the target's.
    signals : object
        Passed to terms and probes.
    y : ndarray, shape (n,)
        Target.
    t : ndarray, shape (n,)
        Time [s] (probes' halves, noise floor).
    library : mapping of str to Term class
        Candidate effects by key.
    meta : dict
        Anything to carry into the report.
    screen_jointly : bool, default False
        Refit the current model's nonlinear parameters with each candidate (from their
        values) instead of holding them: effects that trade off against the base's own.
    resolution : float, default 0
        The sensor's resolution in the target's units (a quantisation step; 0 where not
        known): no effect is kept whose held-out gain is below it (:func:`gain_floor`).
    """

    name: str
    kind: str
    units: str
    signals: Any
    y: np.ndarray
    t: np.ndarray
    base_model: tuple[Term, ...]
    library: Mapping[str, type[Term]]
    probes: Sequence[Probe]
    split: HeldOutSplit
    meta: dict[str, Any] = field(default_factory=dict)
    screen_jointly: bool = False
    resolution: float = 0.0


@dataclass(frozen=True)
class SelectionConfig:
    """Settings of the selection loop. Each numeric setting declares its allowed range
    once (:func:`swgsim.base.typed.allowed`), checked on construction; apps read the
    defaults and ranges from here.

    Attributes
    ----------
    min_rel_improvement : float, default 0
        Optional floor on the relative drop of the validation RMSE (a practical size
        below which an effect is not wanted, whatever the evidence); 0: none, the rule
        rests on evidence alone (docs/calibration.md, "The acceptance rule in full").
    max_delta_bic : float, default -10
        Required BIC change on the fit samples (more negative is better): fit evidence,
        −ΔBIC ≈ 2 ln B (Kass & Raftery 1995).
    min_heldout_evidence : float, default 10
        Required held-out evidence 2 ln Λ_val (twice the validation log-likelihood ratio,
        effective samples), on the same 2 ln B scale ("very strong" above 10).
    max_iter : int, default 12
        At most this many accepted steps (a pair counts once).
    candidates : sequence of str, optional
        Library keys to try (default: the whole library).
    structure_threshold : float, default 0.03
        Probe score from which a residual counts as structured.
    max_rel_se, max_abs_corr : float
        Identifiability flags (see :func:`~swgcal.core.fit_terms`).
    max_starts : int, default 3
        Optimisations per candidate fit (best starting points).
    effective_bic : bool, default True
        Count n / τ_int samples in the BIC and the held-out likelihood of the rule and
        inflate the standard errors by the same τ_int (False: every sample counts, the
        plain BIC, and each fit's own τ_int).
    pair_candidates : int, default 4
        When no single candidate passes but some show evidence (held-out evidence or
        effective ΔBIC beyond its threshold), pairs of this many best candidates (by fit
        RSS) are tried jointly (0 or 1: no look-ahead).
    gain_noise_z : float, default 1
        The noise floor of a held-out gain in its standard errors, 0-10 (:func:`gain_floor`);
        1: a gain's noise floor is its s.e. as a residual's is its σ (set after 2 was
        measured on the shared recordings: docs/calibration.md, "Two floors of a gain").
    """

    min_rel_improvement: float = field(default=0.0, metadata=allowed(0, 1, hi_open=True))
    max_delta_bic: float = field(default=-10.0, metadata=allowed(None, 0))
    min_heldout_evidence: float = field(default=10.0, metadata=allowed(0, None))
    max_iter: int = field(default=12, metadata=allowed(0, None))
    candidates: Sequence[str] | None = None
    structure_threshold: float = field(default=0.03, metadata=allowed(0, 1))
    max_rel_se: float = field(default=0.5, metadata=allowed(0, None, lo_open=True))
    max_abs_corr: float = field(default=0.98, metadata=allowed(0, 1))
    max_starts: int = field(default=3, metadata=allowed(1, 50))
    effective_bic: bool = True
    pair_candidates: int = field(default=4, metadata=allowed(0, 50))
    gain_noise_z: float = field(default=1.0, metadata=allowed(0, 10, "standard errors"))

    def __post_init__(self) -> None:
        check_ranges(self)


@dataclass
class CandidateScore:
    """One candidate tried in one iteration.

    Attributes
    ----------
    val_rmse : float
        Validation RMSE with the candidate added [data units].
    rel_improvement : float
        1 − val_rmse / current validation RMSE.
    delta_bic : float
        Plain (i.i.d.) BIC change on the fit samples.
    delta_bic_eff : float
        BIC change with the effective number of samples n / τ_int (used for the rule).
    heldout_evidence : float
        2 ln Λ_val: twice the log-likelihood ratio of the validation samples, candidate
        against the current model, n_val / τ_int effective samples (used for the rule).
    status : str
        Why it was accepted or rejected.
    params : dict
        Derived parameters of the candidate (values only).
    implausible : bool
        Passed the evidence rule but a parameter lies outside its physical range
        (:attr:`~swgcal.terms.FitTerm.ranges`): the residual holds structure that
        this effect would absorb without being it.
    small : bool
        Rejected only for lack of evidence although its held-out gain is positive: an
        effect that may be there but is too small for these data.
    heldout_gain, gain_se_white, gain_se, gain_floor : float
        RMSE_val,current − val_rmse, its paired s.e. (:func:`paired_gain`) with every
        validation sample and with n_val / τ_int, the floor it must exceed [data units].
    gain_floor_why : str
        Both floors (:func:`gain_floor`) with their figures and which binds.
    """

    name: str
    kind: str
    val_rmse: float
    rel_improvement: float
    delta_bic: float
    delta_bic_eff: float
    accepted: bool
    params: dict[str, float]
    status: str = ""
    fit: FitResult | None = None
    implausible: bool = False
    heldout_evidence: float = float("nan")
    small: bool = False
    heldout_gain: float = float("nan")
    gain_se_white: float = float("nan")
    gain_se: float = float("nan")
    gain_floor: float = float("nan")
    gain_floor_why: str = ""

    def as_dict(self) -> dict[str, Any]:
        return {"name": self.name, "kind": self.kind, "val_rmse": self.val_rmse,
                "rel_improvement": self.rel_improvement, "delta_bic": self.delta_bic,
                "delta_bic_eff": self.delta_bic_eff,
                "heldout_evidence": self.heldout_evidence, "accepted": self.accepted,
                "status": self.status, "params": self.params,
                "implausible": self.implausible, "small": self.small,
                "heldout_gain": self.heldout_gain, "gain_se": self.gain_se,
                "gain_floor": self.gain_floor, "gain_floor_why": self.gain_floor_why}


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
    gain_floor: float = float("nan")
    gain_floor_why: str = ""

    def as_dict(self) -> dict[str, Any]:
        return {"index": self.index, "model": self.model, "val_rmse": self.val_rmse,
                "bic": self.bic, "diagnosis": self.diagnosis.as_dict(),
                "candidates": [c.as_dict() for c in self.candidates], "accepted": self.accepted,
                "gain_floor": self.gain_floor, "gain_floor_why": self.gain_floor_why}


@dataclass
class CalibrationResult:
    """Outcome of :func:`select_effects` (and of each kind's ``calibrate``).

    Attributes
    ----------
    added : list of str
        Names of the accepted effects, in order.
    base_model_final, final : FitResult
        Base model and final model refitted on fit + validation samples.
    rmse : dict
        ``{"fit"|"validation"|"test": {"before": x, "after": y}}`` [data units];
        fit/validation from the selection fits, test from the final refits.
    diag_before, diag_after : Diagnosis
        Residual diagnosis of the base model and of the final model (fit + validation).
    unexplained : bool
        The final residual is still structured, or a candidate outside its physical range
        still passes the evidence rule on it.
    implausible : list of str
        Candidates of the last iteration that passed the evidence rule but lie outside
        their physical range, with their gain and the violated range.
    heldout_whiteness : dict
        The whiteness test of the final model's residual on the test samples
        (:func:`swgcal.diagnose.whiteness`): ``rms``, ``noise_floor``, ``ratio``,
        ``limit``, ``fails``. A failing test makes the residual unexplained even where no
        probe explains it.
    """

    problem: Problem
    config: SelectionConfig
    iterations: list[Iteration]
    added: list[str]
    base_model_final: FitResult
    final: FitResult
    rmse: dict[str, dict[str, float]]
    diag_before: Diagnosis
    diag_after: Diagnosis
    unexplained: bool
    residual_signature: str
    elapsed_s: float = 0.0
    implausible: list[str] = field(default_factory=list)
    heldout_whiteness: dict[str, Any] = field(default_factory=dict)

    @property
    def rmse_before(self) -> float:
        return self.rmse["test"]["before"]

    @property
    def rmse_after(self) -> float:
        return self.rmse["test"]["after"]

    def too_small(self) -> list[CandidateScore]:
        """Single candidates of the last iteration rejected only for lack of evidence
        although their held-out gain is positive (:attr:`CandidateScore.small`), best
        first: effects that may be there but that these data cannot establish."""
        last = self.iterations[-1].candidates if self.iterations else []
        return [c for c in last if c.small and " + " not in c.name]

    def effect_terms(self) -> list[Term]:
        """Accepted effect terms of the final model, in order of acceptance."""
        by = {t.name: t for t in self.final.terms}
        return [by[n] for n in self.added]

    def predictions(self) -> tuple[np.ndarray, np.ndarray]:
        """Predictions of the base model and the final model on all samples."""
        sig = self.problem.signals
        return self.base_model_final.predict(sig), self.final.predict(sig)


def check_candidates(candidates: Sequence[str] | None, library: Mapping[str, Any], kind: str,
                     library_name: str = "library") -> list[str]:
    """The library keys to try, every one checked against the kind's library.

    Parameters
    ----------
    candidates : sequence of str or None
        ``selection.candidates``; None: every key of ``library``, in its order.
    library : mapping of str to type
        The kind's effects by key (:attr:`Problem.library`).
    kind : str
        The data kind whose effects the error names (``"friction"``, ...).
    library_name : str, default "library"
        What the error calls ``library``.

    Raises
    ------
    ValueError
        ``selection.candidates: unknown {kind} effects [...]; {library_name}: [...]``.
    """
    keys = list(candidates) if candidates is not None else list(library)
    unknown = [k for k in keys if k not in library]
    if unknown:
        raise ValueError(f"selection.candidates: unknown {kind} effects {unknown}; "
                         f"{library_name}: {sorted(library)}")
    return keys


def _rmse(r: np.ndarray) -> float:
    return float(np.sqrt(np.mean(r * r))) if r.size else float("nan")


def _order(terms: Sequence[Term]) -> tuple[Term, ...]:
    """Transform terms first (they change what the others see), others in order."""
    return tuple([t for t in terms if t.is_transform] + [t for t in terms if not t.is_transform])


def _score(problem: Problem, fit: FitResult) -> tuple[np.ndarray, float]:
    r = problem.y - fit.predict(problem.signals)
    return r, _rmse(r[problem.split.validation])


def _fit_candidate(problem: Problem, current: FitResult, new_terms: Sequence[Term],
                   starts_new: Sequence[Sequence[np.ndarray]], fit_kw: dict[str, Any],
                   r_cur: np.ndarray, kind: str) -> CandidateScore | None:
    """Add ``new_terms`` to the current model: their θ optimised, the rest held (or
    optimised too, from the current values: :attr:`Problem.screen_jointly`); scored
    against the current model's residual ``r_cur``."""
    sig, sp = problem.signals, problem.split
    cur_th = {t.name: th for t, th in zip(current.terms, current.thetas, strict=True)}
    new_st = {t.name: st for t, st in zip(new_terms, starts_new, strict=True)}
    terms = _order(list(current.terms) + list(new_terms))
    starts = [[cur_th[t.name]] if t.name in cur_th else new_st[t.name] for t in terms]
    fixed = [t.name in cur_th and not problem.screen_jointly for t in terms]
    try:
        f = fit_terms(terms, sig, problem.y, sp.fit, starts, fixed=fixed, uncertainty=False,
                      **fit_kw)
    except (ValueError, np.linalg.LinAlgError) as e:
        log.warning("candidate %s failed: %s", "+".join(t.name for t in new_terms), e)
        return None
    r, v = _score(problem, f)
    val = problem.split.validation
    val_cur = _rmse(r_cur[val])
    gain, se_white = paired_gain(r_cur[val], r[val])
    params: dict[str, float] = {}
    for t in new_terms:
        i = f.terms.index(t)
        d = t.derived(f.coefs[i], f.thetas[i])
        params.update(d if len(new_terms) == 1 else {f"{t.name}.{k}": x for k, x in d.items()})
    return CandidateScore(
        name=" + ".join(t.name for t in new_terms), kind=kind, val_rmse=v,
        rel_improvement=1.0 - v / val_cur if val_cur > 0 else 0.0,
        delta_bic=f.bic - current.bic, delta_bic_eff=float("nan"), accepted=False,
        params=params, fit=f, heldout_gain=gain, gain_se_white=se_white)


def _new_terms(c: CandidateScore, current: FitResult) -> list[Term]:
    names = {t.name for t in current.terms}
    return [t for t in c.fit.terms if t.name not in names]


def _weak(problem: Problem, cfg: SelectionConfig, c: CandidateScore, current: FitResult,
          tau: float | None) -> tuple[FitResult, list[str]]:
    """The candidate's fit with uncertainties (covariance inflated by ``tau``, default its
    own τ_int) and its new terms' primary parameters that the data do not pin down."""
    f = with_uncertainty(c.fit, problem.signals, problem.split.fit, cfg.max_rel_se,
                         cfg.max_abs_corr, tau_int=tau)
    weak = []
    for term in _new_terms(c, current):
        est = f.estimates_of(term.name)
        weak += [f"{term.name}.{k} (rel. s.e. "
                 f"{est[k].std / abs(est[k].value) if est[k].value else np.inf:.2g})"
                 for k in term.primary()
                 if k in est and not est[k].std <= cfg.max_rel_se * abs(est[k].value)]
    return f, weak


def _noise_model_member(problem: Problem, cfg: SelectionConfig, c: CandidateScore,
                        current: FitResult) -> bool:
    """Whether a candidate enters the noise model of :func:`_candidates`: it helps on the
    validation data, its parameters lie in their physical ranges and its primary ones
    are pinned down (with its own τ_int)."""
    if not c.rel_improvement > 0 or _out_of_range(c, current):
        return False
    try:
        return not _weak(problem, cfg, c, current, None)[1]
    except (ValueError, np.linalg.LinAlgError):  # pragma: no cover
        return False


def _out_of_range(c: CandidateScore, current: FitResult) -> bool:
    """Whether a candidate's fitted parameters leave their physical range."""
    f = c.fit
    for t in _new_terms(c, current):
        i = f.terms.index(t)
        if t.range_violations(t.derived(f.coefs[i], f.thetas[i])):
            return True
    return False


def _new_instance(problem: Problem, key: str, current: FitResult) -> Term | None:
    """The next instance of library effect ``key`` for the current model (``key#k`` for a
    repeat), None where the model holds as many as it may or the signals cannot carry it."""
    present = sum(1 for t in current.terms if t.kind == key)
    term = problem.library[key].for_signals(problem.signals,
                                            f"{key}#{present + 1}" if present else key)
    if present >= term.repeatable or not term.applicable(problem.signals):
        return None
    return term


def _candidate_terms(problem: Problem, key: str, current: FitResult,
                     second: bool = False) -> list[list[Term]]:
    """What is tried for library effect ``key``: an effect alone in the first round; a
    transform that acts on other kinds (:attr:`~swgcal.terms.FitTerm.acts_on`, a delay
    of the angle the ripples see) only in the ``second`` round, when no effect of the
    first passes - alone where the model holds a kind it acts on, else with a fresh
    instance of each (one candidate per kind; alone it would change nothing). It changes
    what every later term sees, so it comes after the effects that explain the residual
    by themselves."""
    term = _new_instance(problem, key, current)
    if term is None:
        return []
    acts_on = [k for k in getattr(term, "acts_on", ()) if k in problem.library]
    if not acts_on:
        return [] if second else [[term]]
    if not second:
        return []
    if any(t.kind in acts_on for t in current.terms):
        return [[term]]
    return [[term, other] for k in acts_on
            if (other := _new_instance(problem, k, current)) is not None]


def _candidates(problem: Problem, cfg: SelectionConfig, keys: Sequence[str],
                current: FitResult, r_cur: np.ndarray, val_cur: float,
                fit_kw: dict[str, Any], second: bool = False
                ) -> tuple[list[CandidateScore], float]:
    """Fit every candidate of the round (``second``: the transforms that act on other
    kinds, :func:`_candidate_terms`) added to the current model; ranked by validation
    RMSE.

    Returns the candidates and the noise model's τ_int: the smallest integrated
    autocorrelation time of the residuals of the current model, of every candidate that
    helps on the validation data, and of the richest model of the iteration (the current
    model plus all those candidates, nonlinear parameters as fitted singly - or refitted
    jointly from there under :attr:`Problem.screen_jointly` -, linear ones refitted
    jointly). Like Mallows' Cp, which takes σ² from the full model, the noise
    model then reflects what the library can explain: residual structure that library
    effects explain does not count against a candidate; structure nothing explains does.
    Only candidates that could be accepted enter the noise model (in range, primary
    parameters pinned down: :func:`_noise_model_member`): what only an implausible or
    unidentifiable candidate explains is structure no acceptable effect explains.
    """
    sig, sp = problem.signals, problem.split
    cands = []
    for key in keys:
        for new in _candidate_terms(problem, key, current, second):
            c = _fit_candidate(problem, current, new, [t.starts(sig, r_cur, sp.fit)
                                                       for t in new],
                               fit_kw, r_cur, " + ".join(t.kind for t in new))
            if c is not None:
                cands.append(c)
    cands.sort(key=lambda c: c.val_rmse)
    helpful = [c for c in cands if _noise_model_member(problem, cfg, c, current)]
    tau = min([current.tau_int] + [c.fit.tau_int for c in helpful])
    if helpful:
        terms = list(current.terms)
        thetas = {t.name: th for t, th in zip(current.terms, current.thetas, strict=True)}
        for c in helpful:
            for t in _new_terms(c, current):
                terms.append(t)
                thetas[t.name] = c.fit.thetas[c.fit.terms.index(t)]
        terms = _order(terms)
        try:
            full = fit_terms(terms, sig, problem.y, sp.fit, [[thetas[t.name]] for t in terms],
                             fixed=[not problem.screen_jointly] * len(terms),
                             uncertainty=False, **{**fit_kw, "max_starts": 1})
            tau = min(full.tau_int, tau)
        except (ValueError, np.linalg.LinAlgError) as e:  # pragma: no cover
            log.debug("full model failed: %s", e)
    _set_evidence(cands, current, tau, problem.split.validation.size, val_cur)
    return cands, tau


def _set_evidence(cands: Sequence[CandidateScore], current: FitResult, tau: float,
                  n_val: int, val_cur: float) -> None:
    """Effective ΔBIC on the fit samples, held-out evidence 2 ln Λ_val (module doc) and the
    held-out gain's s.e. (:func:`paired_gain`), all with n / τ_int effective samples."""
    tau = max(tau, 1.0)
    n_eff = current.n / tau
    for c in cands:
        c.gain_se = float(c.gain_se_white * np.sqrt(tau))
        dk = c.fit.k - current.k
        c.delta_bic_eff = float(n_eff * np.log(max(c.fit.rss, 1e-300) / current.rss)
                                + dk * np.log(n_eff))
        if n_val > 0 and val_cur > 0 and c.val_rmse > 0:
            c.heldout_evidence = float(2.0 * n_val / tau * np.log(val_cur / c.val_rmse))


def _pairs(problem: Problem, cfg: SelectionConfig, current: FitResult,
           cands: Sequence[CandidateScore], tau: float, r_cur: np.ndarray,
           fit_kw: dict[str, Any]) -> tuple[list[CandidateScore], float]:
    """Look-ahead when no single candidate passes: two effects that are confounded on
    the fit data may each fail alone (each absorbs part of the other and generalises
    badly) and pass together. Pairs of the ``pair_candidates`` candidates with the
    largest drop of the fit RSS are fitted jointly."""
    top = sorted(cands, key=lambda c: c.fit.rss)[:cfg.pair_candidates]
    out = []
    for i in range(len(top)):
        for j in range(i + 1, len(top)):
            ti, tj = _new_terms(top[i], current)[0], _new_terms(top[j], current)[0]
            if ti.kind == tj.kind:
                continue
            th = {}
            for f in (top[i].fit, top[j].fit):
                th.update({t.name: x for t, x in zip(f.terms, f.thetas, strict=True)})
            c = _fit_candidate(problem, current, [ti, tj], [[th[ti.name]], [th[tj.name]]],
                               {**fit_kw, "max_starts": 1}, r_cur, f"{ti.kind} + {tj.kind}")
            if c is not None:
                out.append(c)
    out.sort(key=lambda c: c.val_rmse)
    tau = min([tau] + [c.fit.tau_int for c in out
                       if _noise_model_member(problem, cfg, c, current)])
    _set_evidence(out, current, tau, problem.split.validation.size,
                  _rmse(r_cur[problem.split.validation]))
    return out, tau


def paired_gain(r_cur: np.ndarray, r_cand: np.ndarray, tau_int: float = 1.0
                ) -> tuple[float, float]:
    """A candidate's held-out gain over the current model and its standard error, paired.

    With d_i = r_cur,i² − r_cand,i² on the same samples, the mean square drops by mean(d),
    s.e. sd(d) / sqrt(n / τ_int); the RMSE by g = mean(d) / (RMSE_cur + RMSE_cand)
    exactly, its s.e. the same ratio (delta method). The noise both models share cancels.

    Parameters
    ----------
    r_cur, r_cand : ndarray, shape (n,)
        Residuals of the current model and of the candidate [data units].
    tau_int : float, default 1
        Integrated autocorrelation time [samples]: n / τ_int effective samples (as the
        evidence rule counts them); below 1 counts as 1.

    Returns
    -------
    gain, se : float
        g and its s.e. [data units]; NaN without samples (se: fewer than 2).

    Raises
    ------
    ValueError
        The residuals differ in shape.
    """
    a, b = np.asarray(r_cur, float), np.asarray(r_cand, float)
    if a.shape != b.shape:
        raise ValueError(f"paired residuals differ in shape: {a.shape} and {b.shape}")
    d, den = a * a - b * b, _rmse(a) + _rmse(b)
    if not den > 0:
        return (0.0, 0.0) if a.size else (float("nan"), float("nan"))
    se = np.std(d, ddof=1) * np.sqrt(max(tau_int, 1.0) / a.size) if a.size > 1 else np.nan
    return float(np.mean(d) / den), float(se / den)


def gain_floor(problem: Problem, gain_se: float = 0.0,
               z: float = SelectionConfig.gain_noise_z) -> tuple[float, str]:
    """The held-out gain an effect must exceed to be kept: the larger of two floors.

    The sensor's resolution (:attr:`Problem.resolution`, a quantisation step): a gain below
    it is finer than the sensor shows. The gain's noise floor, z times its paired standard
    error (:func:`paired_gain`): what noise alone gives. Not the residual's noise floor
    σ_n: a ripple as large as the noise gains 0.22 σ_n, which the data establish; nor the
    unpaired s.e. of one validation RMSE, which holds the noise both models share (twice
    it refused a planted ripple's gain of 0.00097 N m).

    Parameters
    ----------
    problem : Problem
        Its ``resolution`` and ``units``.
    gain_se : float, default 0
        The gain's standard error [target units]; 0 or NaN: no noise floor.
    z : float, default :attr:`SelectionConfig.gain_noise_z`

    Returns
    -------
    floor, why : float, str
        [target units]; both floors with their figures and which binds, for the report.
    """
    u, res = problem.units, float(problem.resolution)
    noise = float(z * gain_se) if gain_se > 0 else 0.0  # NaN > 0 is False
    binds = "the noise floor" if noise > res else "the resolution" if res else "neither"
    return max(res, noise), (
        (f"resolution {res:.3g} {u}" if res else "resolution not known") + "; "
        + (f"noise floor {noise:.3g} {u} ({z:g} × s.e. {gain_se:.3g})" if noise
           else "noise floor not known") + f": {binds} binds")


def _choose(problem: Problem, cfg: SelectionConfig, current: FitResult,
            cands: list[CandidateScore], tau: float) -> CandidateScore | None:
    """First candidate in the ranking that passes the acceptance rule (module doc) and
    whose held-out gain exceeds both its floors (:func:`gain_floor`)."""
    chosen = None
    for c in cands:
        se = c.gain_se if cfg.effective_bic else c.gain_se_white
        c.gain_floor, c.gain_floor_why = gain_floor(problem, se, cfg.gain_noise_z)
        if chosen is not None:
            c.status = "not needed (a better-ranked candidate was accepted)"
            continue
        dbic = c.delta_bic_eff if cfg.effective_bic else c.delta_bic
        hev = c.heldout_evidence if cfg.effective_bic else c.heldout_evidence * max(tau, 1.0)
        if not c.rel_improvement > 0:
            c.status = (f"rejected: no held-out gain (validation RMSE "
                        f"{100 * -c.rel_improvement:+.2g} %)")
            continue
        if not c.rel_improvement > cfg.min_rel_improvement:
            c.status = (f"rejected: validation gain {100 * c.rel_improvement:.2g} % <= floor "
                        f"{100 * cfg.min_rel_improvement:.2g} %")
            continue
        short = []
        if not hev > cfg.min_heldout_evidence:
            short.append(f"held-out evidence 2 ln Λ = {hev:.3g} <= {cfg.min_heldout_evidence:g}")
        if not dbic < cfg.max_delta_bic:
            short.append(f"{'effective ' if cfg.effective_bic else ''}ΔBIC {dbic:+.3g} >= "
                         f"{cfg.max_delta_bic:g}")
        if c.gain_floor > 0 and not c.heldout_gain > c.gain_floor:
            short.append(f"held-out gain {c.heldout_gain:.3g} {problem.units} <= "
                         f"{c.gain_floor:.3g} {problem.units} ({c.gain_floor_why})")
        if short:
            c.small = True
            c.status = (f"rejected: too small for these data (validation gain "
                        f"{100 * c.rel_improvement:.2g} %): " + "; ".join(short))
            continue
        # identifiability of the new terms' primary parameters
        f, weak = _weak(problem, cfg, c, current, tau if cfg.effective_bic else None)
        if weak:
            c.status = "rejected: not pinned down by the data: " + ", ".join(weak)
            continue
        implausible = []
        for term in _new_terms(c, current):
            est = f.estimates_of(term.name)
            implausible += [f"{term.name}.{v}" for v in
                            term.range_violations({k: e.value for k, e in est.items()})]
        if implausible:
            c.status = IMPLAUSIBLE_PREFIX + ", ".join(implausible)
            c.implausible = True
            continue
        c.accepted = True
        c.status = "accepted"
        chosen = c
    return chosen


def _iteration(problem: Problem, cfg: SelectionConfig, keys: Sequence[str], it: int,
               current: FitResult, r_cur: np.ndarray, val_cur: float,
               fit_kw: dict[str, Any]) -> tuple[Iteration, CandidateScore | None]:
    """One iteration: diagnose the current residual (fit samples); below ``max_iter``, rank
    the candidates and choose one (pairs when none passes but some show evidence).
    Returns the iteration's record and the accepted candidate."""
    diag = diagnose(problem.signals, problem.t, r_cur, problem.split.fit, problem.probes,
                    problem.units, cfg.structure_threshold)
    cands: list[CandidateScore] = []
    accepted = None
    floor = (float("nan"), "")
    if it < cfg.max_iter:
        cands, tau = _candidates(problem, cfg, keys, current, r_cur, val_cur, fit_kw)
        floor = (float(problem.resolution), f"the sensor's resolution ({problem.resolution:.3g} "
                 f"{problem.units}; 0: not known) and the gain's noise floor, "
                 f"{cfg.gain_noise_z:g} × its standard error (paired, n_val / τ_int samples)")
        accepted = _choose(problem, cfg, current, cands, tau)
        if accepted is None:  # the second round: the transforms acting on other kinds
            more, tau_c = _candidates(problem, cfg, keys, current, r_cur, val_cur, fit_kw,
                                      second=True)
            accepted = _choose(problem, cfg, current, more, tau_c) if more else None
        else:
            more = []
        evidence = any(c.heldout_evidence > cfg.min_heldout_evidence
                       or c.delta_bic_eff < cfg.max_delta_bic for c in cands)
        if accepted is None and cfg.pair_candidates >= 2 and evidence:  # look-ahead 2
            pairs, tau = _pairs(problem, cfg, current, cands, tau, r_cur, fit_kw)
            accepted = _choose(problem, cfg, current, pairs, tau)
            cands = cands + pairs
        cands = sorted(cands + more, key=lambda c: c.val_rmse) if more else cands
    record = Iteration(it, [t.name for t in current.terms], val_cur, current.bic, diag, cands,
                       accepted.name if accepted else None, floor[0], floor[1])
    best = cands[0] if cands else None
    log.info("%s iteration %d: val RMSE %.4g, best %s (%.4g), accepted %s", problem.name, it,
             val_cur, best and best.name, best.val_rmse if best else np.nan, record.accepted)
    return record, accepted


@dataclass
class _Selection:
    """Where the loop on the fit samples ended: the base model and the selected model
    (fitted on the fit samples), the selected model's residual on all samples and its
    validation RMSE, the iterations and the instance names added."""

    base_model: FitResult
    current: FitResult
    r_cur: np.ndarray
    val_cur: float
    iterations: list[Iteration]
    added: list[str]


def _select(problem: Problem, cfg: SelectionConfig, keys: Sequence[str],
            fit_kw: dict[str, Any]) -> _Selection:
    """The loop on the fit samples: from the base model, add the accepted candidate and
    refit all nonlinear parameters jointly, until no candidate is accepted."""
    sig, y, sp = problem.signals, problem.y, problem.split
    current = fit_terms(_order(problem.base_model), sig, y, sp.fit, uncertainty=False, **fit_kw)
    base_model_sel = current
    r_cur, val_cur = _score(problem, current)
    iterations: list[Iteration] = []
    added: list[str] = []
    for it in range(cfg.max_iter + 1):
        record, accepted = _iteration(problem, cfg, keys, it, current, r_cur, val_cur, fit_kw)
        iterations.append(record)
        if accepted is None:
            break
        # joint refit of all nonlinear parameters, from the candidate's values
        current_before = current
        current = fit_terms(accepted.fit.terms, sig, y, sp.fit,
                            [[th] for th in accepted.fit.thetas], uncertainty=False,
                            **{**fit_kw, "max_starts": 1})
        added.extend(t.name for t in _new_terms(accepted, current_before))
        r_cur, val_cur = _score(problem, current)
    return _Selection(base_model_sel, current, r_cur, val_cur, iterations, added)


def _final_result(problem: Problem, cfg: SelectionConfig, sel: _Selection,
                  fit_kw: dict[str, Any], t_start: float) -> CalibrationResult:
    """Final refits of the base model and the selected model on fit + validation samples,
    the RMSE before and after on the fit, validation and test samples, the diagnoses of
    the final residuals."""
    sig, y, sp = problem.signals, problem.y, problem.split
    idx_fv = sp.fit_validation
    base_final = fit_terms(_order(problem.base_model), sig, y, idx_fv, **fit_kw)
    final = fit_terms(sel.current.terms, sig, y, idx_fv, _final_starts(sel.current, base_final),
                      **fit_kw)
    r_b = y - base_final.predict(sig)
    r_a = y - final.predict(sig)
    r_bs = y - sel.base_model.predict(sig)
    rmse = {
        "fit": {"before": _rmse(r_bs[sp.fit]), "after": _rmse(sel.r_cur[sp.fit])},
        "validation": {"before": _rmse(r_bs[sp.validation]), "after": sel.val_cur},
        "test": {"before": _rmse(r_b[sp.test]), "after": _rmse(r_a[sp.test])},
    }
    d_before = diagnose(sig, problem.t, r_b, idx_fv, problem.probes, problem.units,
                        cfg.structure_threshold)
    d_after = d_before if not sel.added else diagnose(
        sig, problem.t, r_a, idx_fv, problem.probes, problem.units, cfg.structure_threshold)
    structured, signature, white = _heldout_verdict(problem, r_a, d_after)
    return CalibrationResult(
        problem=problem, config=cfg, iterations=sel.iterations, added=sel.added,
        base_model_final=base_final, final=final, rmse=rmse, diag_before=d_before,
        diag_after=d_after, unexplained=structured, residual_signature=signature,
        elapsed_s=time.perf_counter() - t_start, heldout_whiteness=white)


def _final_starts(cur: FitResult, base_final: FitResult) -> list[list[np.ndarray]]:
    """Starts of a final refit: every term from its values in ``cur``, a base term also
    from the base's own refit (``base_final``, from several starts): a bounded fit has
    several optima (the UR3 day's J3, J5: docs/calibration.md, "Several starts")."""
    base_th = {t.name: th for t, th in zip(base_final.terms, base_final.thetas, strict=True)}
    return [[th] if (b := base_th.get(t.name)) is None or not b.size or np.allclose(b, th)
            else [th, b] for t, th in zip(cur.terms, cur.thetas, strict=True)]


def _heldout_verdict(problem: Problem, r_after: np.ndarray, d_after: Diagnosis
                     ) -> tuple[bool, str, dict[str, Any]]:
    """The final verdict with the held-out whiteness test: (structured, signature, the
    test's figures). The residual of the test samples failing the test (RMS above
    :data:`~swgcal.diagnose.WHITENESS_RATIO` times its noise floor) is structured even
    where the diagnosis on the fit samples found none."""
    rms, nf, ratio = whiteness(problem.t, r_after, problem.split.test)
    fails = bool(ratio > WHITENESS_RATIO)
    info = {"rms": rms, "noise_floor": nf, "ratio": ratio, "limit": WHITENESS_RATIO,
            "fails": fails}
    if not fails or d_after.structured:
        return d_after.structured, d_after.signature, info
    return True, (f"{d_after.signature.rstrip('.')}; but the held-out (test) residual fails "
                  f"the whiteness test: RMS {rms:.3g} {problem.units}, {ratio:.2f}x its noise "
                  f"floor {nf:.3g} {problem.units} (> {WHITENESS_RATIO:g}): structure the "
                  "probes do not see"), info


def _flag_implausible(res: CalibrationResult) -> None:
    """Candidates of the last iteration outside their physical range: in
    ``res.implausible``, the residual unexplained (the library lacks an effect)."""
    last = res.iterations[-1].candidates if res.iterations else []
    res.implausible = [f"{c.name} (validation gain {100 * c.rel_improvement:.2g} %, held-out "
                       f"2 ln Λ {c.heldout_evidence:.3g}; {c.status.split(': ', 2)[-1]})"
                       for c in last if c.implausible]
    if res.implausible:
        res.unexplained = True
        res.residual_signature = (
            res.residual_signature.rstrip(".") + _IMPLAUSIBLE_NOTE + " still explains part "
            "of the residual with very strong evidence, so an effect the library does not "
            "hold is there: " + "; ".join(res.implausible) + ".")


def refit_final(result: CalibrationResult, cur: FitResult, meta: dict[str, Any], *,
                keep_note: bool = True) -> CalibrationResult:
    """``result`` with a changed model (after the loop: ripples grouped or pruned, unpinned
    effects dropped): ``cur`` refitted on fit + validation samples from its values (and a
    base term also from the base model's own optimum, :func:`_final_starts`).

    Parameters
    ----------
    result : CalibrationResult
        What :func:`select_effects` returned.
    cur : FitResult
        The changed model, fitted on the fit samples.
    meta : dict
        The problem's new ``meta``.
    keep_note : bool, default True
        Keep what :func:`select_effects` appended to the final diagnosis' signature (the
        candidates outside their physical range).

    Returns
    -------
    CalibrationResult
        A copy with the final model, the errors after, the final diagnosis, ``added``
        (the effects ``cur`` keeps) and ``unexplained`` updated.
    """
    p, cfg = result.problem, result.config
    sp, sig, y = p.split, p.signals, p.y
    final = fit_terms(cur.terms, sig, y, sp.fit_validation,
                      _final_starts(cur, result.base_model_final), max_rel_se=cfg.max_rel_se,
                      max_abs_corr=cfg.max_abs_corr, max_starts=cfg.max_starts)
    r_fit, r_a = y - cur.predict(sig), y - final.predict(sig)
    rmse = {k: dict(v) for k, v in result.rmse.items()}
    for k, r in (("fit", r_fit), ("validation", r_fit), ("test", r_a)):
        rmse[k]["after"] = _rmse(r[getattr(sp, k)])
    d_after = diagnose(sig, p.t, r_a, sp.fit_validation, p.probes, p.units,
                       cfg.structure_threshold)
    structured, signature, white = _heldout_verdict(p, r_a, d_after)
    names = {t.name for t in cur.terms}
    at = result.residual_signature.find(_IMPLAUSIBLE_NOTE)
    extra = result.residual_signature[at:] if keep_note and at >= 0 else ""
    return dataclasses.replace(
        result, problem=dataclasses.replace(p, meta=meta), final=final,
        added=[n for n in result.added if n in names], rmse=rmse, diag_after=d_after,
        unexplained=bool(structured or result.implausible),
        residual_signature=(signature.rstrip(".") + extra) if extra else signature,
        heldout_whiteness=white)


def select_effects(problem: Problem, config: SelectionConfig | None = None) -> CalibrationResult:
    """The selection loop on a problem: fit the base model, add the library effect the
    residual needs while held-out evidence supports it, stop with a verdict.

    Raises
    ------
    KeyError
        ``config.candidates`` names an effect that is not in the library.
    """
    cfg = config or SelectionConfig()
    t_start = time.perf_counter()
    keys = list(cfg.candidates) if cfg.candidates is not None else list(problem.library)
    unknown = [k for k in keys if k not in problem.library]
    if unknown:
        raise KeyError(f"candidates {unknown} not in the library {sorted(problem.library)}")
    fit_kw = dict(max_rel_se=cfg.max_rel_se, max_abs_corr=cfg.max_abs_corr,
                  max_starts=cfg.max_starts)
    sel = _select(problem, cfg, keys, fit_kw)
    res = _final_result(problem, cfg, sel, fit_kw, t_start)
    _flag_implausible(res)
    log.info("%s: test RMSE %.4g -> %.4g, added %s, unexplained %s", problem.name,
             res.rmse["test"]["before"], res.rmse["test"]["after"], res.added, res.unexplained)
    return res
