"""After the selection loop: near-equal periods merged, ripples as harmonics of one
fundamental, held-out support, each period with its standard error in the gear's terms.

The loop adds ripple instances one at a time (``position_ripple``, ``position_ripple#2``,
...), each with its own free period, refined by nonlinear least squares in the period
(the phase and amplitude are linear, :mod:`swgcal.core`) from the residual periodogram's
peaks. Three things can then go wrong that no single step of the loop sees:

* two instances of one kind at periods closer than the recording resolves (Rayleigh:
  ``|1/P1 − 1/P2| · S < 1`` over the angle span S the recording covers) fit an
  amplitude modulation, not two ripples: :func:`near_equal_pairs` finds them and they
  are merged into one instance, its period refitted, before anything else;

* harmonics of one fundamental (orders 2 and 4 of the wave generator) enter as unrelated
  instances: :func:`harmonic_groups` finds instances whose periods are integer fractions
  of one fundamental (with the gear ratio N: integer wave-generator orders k = 2π /
  (period · N)), and :func:`group_ripples` replaces them by one
  :class:`~swgsim.gear.friction.ripples.RippleTerm` with that fundamental and the
  harmonic numbers, unless the held-out data support the separate periods;
* an instance that paid when it was added may be redundant in the final model (a later
  effect explains the same structure): every ripple of the final model must keep
  held-out evidence of its own, ``2 ln Λ_val = (n_val / τ_int) ln(RMSE_without² /
  RMSE_with²)`` above the loop's ``min_heldout_evidence`` (the same
  predictive-likelihood scale as the acceptance rule, see
  :mod:`swgcal.loop`); the least supported one is removed and the check
  repeated (backward elimination on held-out data).

Both steps fit on the fit samples and judge on the validation samples, like the loop;
the test samples stay untouched until the final model is refitted on fit + validation
samples. What was grouped, removed, and the validation RMSE as ripple instances were
added go to ``problem.meta["ripples"]`` (summary key ``ripples``).
"""

from __future__ import annotations

import dataclasses
import logging
import math
from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np

from swgsim.gear.friction.ripples import RippleTerm, wave_generator_order

from ..core import FitResult, Term, fit_terms, with_uncertainty
from ..loop import CalibrationResult, refit_final

log = logging.getLogger(__name__)

__all__ = ["HARMONIC_REL_TOL", "RippleGroupProposal", "harmonic_groups", "group_ripples",
           "ripple_history", "heldout_evidence", "near_equal_pairs"]

HARMONIC_REL_TOL = 0.01
"""Relative tolerance of a harmonic relation (period ratio or wave-generator order): the
accuracy of a period estimate over a few tens of cycles, and of a gear ratio given as N
where N + 1 applies (1 % at N = 100). Widened to 3 standard errors of the period."""
MAX_PERIOD_TOL = 0.02
"""A period whose 3 standard errors exceed this fraction of it joins no harmonic group."""
MAX_HARMONIC = 8
"""Highest harmonic number of a group found without the gear ratio."""
MAX_MISSING = 2
"""Without the gear ratio, the fundamental may be absent: up to this multiple of the
longest member period is tried (orders 2 and 3 have the fundamental twice the order-2
period; higher multiples match unrelated periods too easily: 3:4 is within 1 % of many
ratios)."""

DEFAULT_MIN_EVIDENCE = 10.0
"""Held-out evidence 2 ln Λ_val a ripple must keep when the selection config has no
``min_heldout_evidence`` (Kass & Raftery 1995: "very strong" above 10)."""


@dataclass(frozen=True)
class RippleGroupProposal:
    """Instances whose periods are harmonics of one fundamental.

    Attributes
    ----------
    members : tuple of int
        Indices into the period list given to :func:`harmonic_groups`.
    harmonics : tuple of int
        Harmonic number of each member (same order as ``members``).
    fundamental : float
        Fundamental period [rad] (average of period × harmonic over the members).
    """

    members: tuple[int, ...]
    harmonics: tuple[int, ...]
    fundamental: float


def _near(ratio: float, h: int, tol: float) -> bool:
    return h >= 1 and abs(ratio / h - 1.0) <= tol


def harmonic_groups(periods: Sequence[float], rel_se: Sequence[float] | None = None,
                    gear_ratio: float | None = None, rel_tol: float = HARMONIC_REL_TOL
                    ) -> list[RippleGroupProposal]:
    """Group periods that are integer fractions of one fundamental.

    With the gear ratio N, a period P belongs to a group when its wave-generator order
    k = 2π / (P N) is within tolerance of an integer h >= 1 (fundamental 2π / N, the
    wave-generator turn). Without N, each period not yet grouped, longest first, or up
    to :data:`MAX_MISSING` times it, is tried as the fundamental P0; the members are the
    periods P with P0 / P within tolerance of an integer <= :data:`MAX_HARMONIC`; the
    longest period that groups with another anchors the group, the choice grouping most
    periods winning (the smallest multiple on a tie); then the rest is searched again. A
    group needs two members with distinct harmonics; of two members at the same
    harmonic the one nearer to it is kept.

    Parameters
    ----------
    periods : sequence of float
        Periods over the output angle [rad], > 0.
    rel_se : sequence of float, optional
        Relative standard errors of the periods; the tolerance of a member is the
        larger of ``rel_tol`` and 3 of them, and a period whose 3 standard errors exceed
        :data:`MAX_PERIOD_TOL` joins no group (any ratio would fit it).
    gear_ratio : float, optional
        Reduction ratio N.
    rel_tol : float, default :data:`HARMONIC_REL_TOL`

    Raises
    ------
    ValueError
        A non-positive period, or ``rel_se`` of another length.
    """
    p = np.asarray(periods, float)
    if np.any(~(p > 0)):
        raise ValueError(f"periods must be > 0 [rad], got {list(periods)}")
    se = np.zeros(p.size) if rel_se is None else np.nan_to_num(np.asarray(rel_se, float),
                                                                nan=np.inf)
    if se.size != p.size:
        raise ValueError(f"rel_se has {se.size} entries for {p.size} periods")
    tol = np.maximum(rel_tol, 3.0 * se)
    # a harmonic relation is claimed only between periods the data pin down
    eligible = 3.0 * se <= MAX_PERIOD_TOL
    if gear_ratio is not None:
        return _groups_by_order(p, eligible, tol, float(gear_ratio))
    return _groups_by_ratio(p, eligible, tol)


def _dedupe(cands: list[tuple[int, int, float]]) -> list[tuple[int, int, float]]:
    """Of candidate members (index, harmonic, relative error) at the same harmonic, the
    one nearest to it; by harmonic."""
    best: dict[int, tuple[int, int, float]] = {}
    for i, h, err in cands:
        if h not in best or err < best[h][2]:
            best[h] = (i, h, err)
    return sorted(best.values(), key=lambda x: x[1])


def _proposal(p: np.ndarray, sel: list[tuple[int, int, float]]) -> RippleGroupProposal:
    """The group of the members ``sel``; fundamental: the mean of period × harmonic."""
    f0 = float(np.mean([p[i] * h for i, h, _ in sel]))
    return RippleGroupProposal(tuple(i for i, _, _ in sel), tuple(h for _, h, _ in sel), f0)


def _groups_by_order(p: np.ndarray, eligible: np.ndarray, tol: np.ndarray,
                     gear_ratio: float) -> list[RippleGroupProposal]:
    """With the gear ratio: the eligible periods whose wave-generator order is near an
    integer, one group when there are two or more."""
    cands = []
    for i in np.flatnonzero(eligible).tolist():
        k = wave_generator_order(float(p[i]), gear_ratio)
        h = int(round(k))
        if _near(k, h, tol[i]):
            cands.append((i, h, abs(k / h - 1.0)))
    sel = _dedupe(cands)
    return [_proposal(p, sel)] if len(sel) >= 2 else []


def _groups_by_ratio(p: np.ndarray, eligible: np.ndarray, tol: np.ndarray
                     ) -> list[RippleGroupProposal]:
    """Without the gear ratio: the longest period that groups another one (or a small
    multiple of it) anchors a group, the choice grouping most periods winning; then the
    rest is searched again."""
    out: list[RippleGroupProposal] = []
    left = sorted(np.flatnonzero(eligible).tolist(), key=lambda i: -p[i])
    while len(left) >= 2:
        best: list[tuple[int, int, float]] = []
        for a in left:
            for m in range(1, MAX_MISSING + 1):
                p0 = p[a] * m
                cands = []
                for i in left:
                    ratio = p0 / p[i]
                    h = int(round(ratio))
                    t_ia = math.hypot(tol[i], tol[a]) if i != a else tol[i]
                    if h <= MAX_HARMONIC and _near(ratio, h, t_ia):
                        cands.append((i, h, abs(ratio / h - 1.0)))
                sel = _dedupe(cands)
                if len(sel) >= 2 and len(sel) > len(best) and a in [i for i, _, _ in sel]:
                    best = sel
            if best:
                break  # the longest period that groups another one anchors the group
        if len(best) < 2:
            break
        out.append(_proposal(p, best))
        left = [i for i in left if i not in {j for j, _, _ in best}]
    return out


def near_equal_pairs(periods: Sequence[float], span: float) -> list[tuple[int, int]]:
    """Pairs of periods a recording cannot tell apart (Rayleigh's criterion over q).

    Two sinusoids over an angle span S are resolved when their spatial frequencies differ
    by at least 1 / S (Rayleigh; e.g. Kay, Modern Spectral Estimation, 1988, sec. 4.4):
    closer, their sum is one sinusoid whose amplitude is modulated across the span.

    Parameters
    ----------
    periods : sequence of float
        Periods [rad], > 0.
    span : float
        Angle span the recording covers [rad], > 0.

    Returns
    -------
    list of (int, int)
        Index pairs (i < j) with ``|1/P_i − 1/P_j| · span < 1``, closest first.

    Raises
    ------
    ValueError
        A non-positive period or span.
    """
    p = np.asarray(periods, float)
    if np.any(p <= 0) or not span > 0:
        raise ValueError(f"periods and span must be > 0, got {list(p)}, {span}")
    f = 1.0 / p
    out = [(abs(f[i] - f[j]) * span, i, j) for i in range(p.size)
           for j in range(i + 1, p.size) if abs(f[i] - f[j]) * span < 1.0]
    return [(i, j) for _, i, j in sorted(out)]


def heldout_evidence(val_with: float, val_without: float, n_val: int, tau: float) -> float:
    """Held-out evidence of a term, 2 ln Λ_val = (n_val / τ_int) ln(RMSE_without² /
    RMSE_with²) (the scale of the loop's acceptance rule, :mod:`swgcal.loop`).

    Parameters
    ----------
    val_with, val_without : float
        Validation RMSE with and without the term [data units], > 0.
    n_val : int
        Validation samples.
    tau : float
        Integrated autocorrelation time of the residual [samples] (>= 1 used).

    Returns
    -------
    float
        Positive when the term helps on the held-out data.
    """
    if not (val_with > 0 and val_without > 0):
        return float("nan")
    return float(2.0 * n_val / max(float(tau), 1.0) * math.log(val_without / val_with))


def _is_ripple(problem_library: dict, kind: str) -> bool:
    """Whether a candidate kind (``"a"`` or a pair ``"a + b"``) holds a ripple."""
    for k in kind.split(" + "):
        cls = problem_library.get(k)
        if isinstance(cls, type) and issubclass(cls, RippleTerm):
            return True
    return False


def ripple_history(result: CalibrationResult) -> list[dict[str, Any]]:
    """Validation RMSE as ripple instances were added, and the ripple candidate the loop
    turned down last.

    Returns
    -------
    list of dict
        Per accepted ripple: ``iteration``, ``name``, ``val_rmse_before``,
        ``val_rmse_after``, ``validation_gain``, ``heldout_evidence``, ``periods`` [rad]
        and ``orders`` (None without a gear ratio; a pair candidate has a period per
        ripple), ``accepted`` True; then, from the last
        iteration, the best-ranked ripple candidate not accepted with its ``status``
        (``accepted`` False, ``val_rmse_after``: its validation RMSE).
    """
    lib = dict(result.problem.library)
    n_ratio = getattr(result.problem.signals, "gear_ratio", None)
    its = result.iterations
    out = []

    def entry(it, c, after, accepted):
        # a pair candidate reports "name.period" per member
        pers = [float(v) for k, v in dict(c.params).items()
                if k == "period" or k.endswith(".period")]
        return {"iteration": it.index, "name": c.name, "val_rmse_before": it.val_rmse,
                "val_rmse_after": after, "validation_gain": c.rel_improvement,
                "heldout_evidence": getattr(c, "heldout_evidence", None),
                "periods": pers,
                "orders": ([wave_generator_order(x, n_ratio) for x in pers] if n_ratio
                           else None),
                "accepted": accepted, "status": c.status}

    for j, it in enumerate(its):
        for c in it.candidates:
            if c.accepted and _is_ripple(lib, c.kind):
                after = its[j + 1].val_rmse if j + 1 < len(its) else None
                out.append(entry(it, c, after, True))
    if its:
        last = its[-1]
        rej = [c for c in last.candidates if _is_ripple(lib, c.kind) and not c.accepted]
        if rej and last.accepted is None:
            out.append(entry(last, rej[0], rej[0].val_rmse, False))
    return out


def _val_rmse(result: CalibrationResult, fit: FitResult) -> float:
    p = result.problem
    r = (p.y - fit.predict(p.signals))[p.split.validation]
    return float(np.sqrt(np.mean(r * r))) if r.size else float("nan")


def _refit(result: CalibrationResult, terms: Sequence[Term], thetas: dict[str, np.ndarray],
           free: set[str], fit_kw: dict[str, Any]) -> FitResult:
    """Fit on the fit samples: nonlinear parameters of ``free`` terms optimised from
    ``thetas``, the others held; all linear coefficients refitted."""
    p = result.problem
    return fit_terms(terms, p.signals, p.y, p.split.fit, [[thetas[t.name]] for t in terms],
                     fixed=[t.name not in free for t in terms], uncertainty=False,
                     **{**fit_kw, "max_starts": 1})


def group_ripples(result: CalibrationResult, *, rel_tol: float = HARMONIC_REL_TOL,
                  min_evidence: float | None = None) -> CalibrationResult:
    """Group harmonic ripples into one effect and drop ripples without held-out support.

    Parameters
    ----------
    result : CalibrationResult
        From :func:`~swgcal.loop.calibrate` (friction problems; a result
        without ripple effects comes back with only the history recorded).
    rel_tol : float, default :data:`HARMONIC_REL_TOL`
        Tolerance of a harmonic relation (:func:`harmonic_groups`).
    min_evidence : float, optional
        Held-out evidence 2 ln Λ_val a ripple must keep, and by which separate periods
        must beat their group to stay separate; default the selection config's
        ``min_heldout_evidence`` (:data:`DEFAULT_MIN_EVIDENCE` if it has none).

    Returns
    -------
    CalibrationResult
        A copy; where something changed, the final model refitted on fit + validation
        samples, the test errors, the final diagnosis and ``added`` updated.
        ``problem.meta["ripples"]`` holds ``gear_ratio``, ``history``
        (:func:`ripple_history`), ``groups`` (name, members, harmonics, fundamental
        period and order, held-out evidence of separate against grouped), ``removed``
        and ``support`` (held-out evidence and validation gain of each ripple kept).
    """
    p, cfg = result.problem, result.config
    if min_evidence is None:
        min_evidence = float(getattr(cfg, "min_heldout_evidence", DEFAULT_MIN_EVIDENCE))
    info: dict[str, Any] = {"gear_ratio": getattr(p.signals, "gear_ratio", None),
                            "history": ripple_history(result),
                            "merged": [], "groups": [], "removed": [], "support": [],
                            "min_heldout_evidence": min_evidence}
    ripples = [t for t in result.final.terms if isinstance(t, RippleTerm)
               and t.name in result.added]
    if not ripples:
        return dataclasses.replace(result, problem=dataclasses.replace(
            p, meta={**p.meta, "ripples": info}))
    st = _Pruning.start(result, min_evidence, info)
    _merge_near_equal(st, ripples)
    _group_harmonics(st, ripples, rel_tol)
    _drop_unsupported(st, ripples)
    meta = {**p.meta, "ripples": info}
    if not st.changed:
        return dataclasses.replace(result, problem=dataclasses.replace(p, meta=meta))
    return refit_final(result, st.cur, meta)


@dataclass
class _Pruning:
    """The model while ripples are grouped and pruned: the current fit (on the fit
    samples), its nonlinear parameters by term name and validation RMSE."""

    result: CalibrationResult
    cur: FitResult
    val_cur: float
    min_evidence: float
    info: dict[str, Any]
    fit_kw: dict[str, Any]
    thetas: dict[str, np.ndarray] = dataclasses.field(default_factory=dict)
    changed: bool = False

    @classmethod
    def start(cls, result: CalibrationResult, min_evidence: float,
              info: dict[str, Any]) -> _Pruning:
        """The selection model, refitted on the fit samples from the final values."""
        cfg = result.config
        fit_kw = dict(max_rel_se=cfg.max_rel_se, max_abs_corr=cfg.max_abs_corr)
        terms = list(result.final.terms)
        thetas = {t.name: np.asarray(th, float) for t, th in zip(terms, result.final.thetas,
                                                                  strict=True)}
        cur = _refit(result, terms, thetas, {t.name for t in terms}, fit_kw)
        st = cls(result, cur, _val_rmse(result, cur), min_evidence, info, fit_kw)
        st.accept(cur, st.val_cur, changed=False)
        return st

    @property
    def n_val(self) -> int:
        return int(self.result.problem.split.validation.size)

    @property
    def gear_ratio(self) -> float | None:
        return self.info["gear_ratio"]

    def accept(self, fit: FitResult, val_rmse: float, changed: bool = True) -> None:
        """Make ``fit`` the current model."""
        self.cur, self.val_cur = fit, val_rmse
        self.changed = self.changed or changed
        self.thetas = {t.name: np.asarray(th, float) for t, th in
                       zip(fit.terms, fit.thetas, strict=True)}


def _merge_near_equal(st: _Pruning, ripples: Sequence[Term]) -> None:
    """Step 0: two single ripples of one kind at periods the recording cannot tell apart
    (:func:`near_equal_pairs` over the angle span) become one, started at their
    amplitude-weighted period and refitted; repeated while such a pair is left."""
    span = float(st.result.problem.signals.scales.q_span)
    names = {r.name for r in ripples}
    while True:
        for kind in sorted({t.kind for t in ripples}):
            members = [t for t in st.cur.terms if t.kind == kind and t.name in names
                       and isinstance(t, RippleTerm) and t.single]
            pairs = near_equal_pairs([float(st.thetas[t.name][0]) for t in members], span) \
                if len(members) > 1 else []
            if pairs:
                break
        else:
            return
        a, b = members[pairs[0][0]], members[pairs[0][1]]
        if not _merge(st, a, b, span):
            return


def _merge(st: _Pruning, a: Term, b: Term, span: float) -> bool:
    """Merge ripple ``b`` into ``a`` (module docstring, step 0); False where the refit fails."""
    cur = st.cur
    amp = {t.name: float(np.hypot(*cur.coefs[cur.terms.index(t)][:2])) for t in (a, b)}
    per = {t.name: float(st.thetas[t.name][0]) for t in (a, b)}
    w = np.array([amp[a.name] ** 2, amp[b.name] ** 2]) + 1e-300
    start = float(np.average([per[a.name], per[b.name]], weights=w))
    terms = [t for t in cur.terms if t is not b]
    try:
        fm = _refit(st.result, terms, {**st.thetas, a.name: np.array([start])}, {a.name},
                    st.fit_kw)
    except (ValueError, np.linalg.LinAlgError) as e:  # pragma: no cover
        log.warning("merging %s into %s failed: %s", b.name, a.name, e)
        return False
    val_m = _val_rmse(st.result, fm)
    st.info["merged"].append({
        "name": a.name, "members": [a.name, b.name], "periods": [per[a.name], per[b.name]],
        "amplitudes": [amp[a.name], amp[b.name]],
        "resolution": abs(1.0 / per[a.name] - 1.0 / per[b.name]) * span,
        "period": float(fm.thetas[fm.terms.index(a)][0]),
        "val_rmse_separate": st.val_cur, "val_rmse_merged": val_m})
    st.accept(fm, val_m)
    return True


def _period_errors(st: _Pruning, ripples: Sequence[Term]) -> dict[tuple[str, str], Any]:
    """Standard errors of the current model's parameters, by (term, parameter), when two
    single ripples of one kind could be harmonics of each other (else empty)."""
    kinds = [t.kind for t in ripples if t.single]
    if not any(kinds.count(k) > 1 for k in kinds):
        return {}
    p, cfg = st.result.problem, st.result.config
    try:
        cu = with_uncertainty(st.cur, p.signals, p.split.fit, cfg.max_rel_se, cfg.max_abs_corr)
    except (ValueError, np.linalg.LinAlgError) as e:  # pragma: no cover
        log.debug("ripple uncertainties failed: %s", e)
        return {}
    return {(e.term, e.name): e for e in cu.estimates}


def _group_harmonics(st: _Pruning, ripples: Sequence[Term], rel_tol: float) -> None:
    """Step 1: ripples of one kind whose periods are harmonics of one fundamental become
    one effect, unless the held-out data support separate periods."""
    est = _period_errors(st, ripples)
    for kind in sorted({t.kind for t in ripples}):
        members = [t for t in st.cur.terms if t.kind == kind and isinstance(t, RippleTerm)
                   and t.single and t.name in st.result.added]
        if len(members) < 2:
            continue
        periods = [float(st.thetas[t.name][0]) for t in members]
        rse = []
        for t, per in zip(members, periods, strict=True):
            e = est.get((t.name, "period"))
            rse.append(e.std / per if e is not None and np.isfinite(e.std) else 0.0)
        for g in harmonic_groups(periods, rse, st.gear_ratio, rel_tol):
            _try_group(st, kind, [members[i] for i in g.members], g)


def _try_group(st: _Pruning, kind: str, mem: list[Term], g: RippleGroupProposal) -> None:
    """Fit one harmonic group as one effect; keep it unless separate periods win."""
    n_ratio = st.gear_ratio
    cur, thetas = st.cur, st.thetas
    first = min(mem, key=lambda t: cur.terms.index(t))
    fund = g.fundamental  # with N: the wave-generator turn, refined by the fit
    merged = type(mem[0])(first.name, harmonics=sorted(g.harmonics), gear_ratio=n_ratio)
    new_terms = [merged if t is first else t for t in cur.terms if t not in mem
                 or t is first]
    th2 = {**thetas, first.name: np.array([fund])}
    try:
        fg = _refit(st.result, new_terms, th2, {first.name}, st.fit_kw)
    except (ValueError, np.linalg.LinAlgError) as e:
        log.warning("grouping %s failed: %s", [t.name for t in mem], e)
        return
    val_g = _val_rmse(st.result, fg)
    tau = min(cur.tau_int, fg.tau_int)
    ev_sep = heldout_evidence(st.val_cur, val_g, st.n_val, tau)  # separate vs grouped
    i_m = fg.terms.index(merged)
    viol = merged.range_violations(merged.derived(fg.coefs[i_m], fg.thetas[i_m]))
    p0 = float(fg.thetas[i_m][0])
    rec = {"name": merged.name, "kind": kind, "members": [t.name for t in mem],
           "harmonics": list(merged.harmonics), "fundamental_period": p0,
           "fundamental_order": (wave_generator_order(p0, n_ratio) if n_ratio
                                 else None),
           "orders": merged.orders(p0),
           "periods_separate": [float(thetas[t.name][0]) for t in mem],
           "val_rmse_separate": st.val_cur, "val_rmse_grouped": val_g,
           "evidence_separate_vs_grouped": ev_sep, "range_violations": viol}
    if ev_sep > st.min_evidence or viol:
        rec["grouped"] = False
        rec["why"] = ("the held-out data support separate periods" if not viol
                      else "grouped fundamental outside its range: " + "; ".join(viol))
    else:
        rec["grouped"] = True
        st.accept(fg, val_g)
    st.info["groups"].append(rec)


def _drop_unsupported(st: _Pruning, ripples: Sequence[Term]) -> None:
    """Step 2: every ripple keeps held-out evidence of its own (backward elimination:
    the least supported one goes while it is below ``min_evidence``)."""
    names = {r.name for r in ripples}
    while True:
        rips = [t for t in st.cur.terms if isinstance(t, RippleTerm) and t.name in names]
        if not rips:
            return
        support = [x for x in (_support(st, r) for r in rips) if x is not None]
        if not support:
            return
        ev, r, f0, v0 = min(support, key=lambda x: x[0])
        if ev > st.min_evidence:
            st.info["support"] = [{"name": x[1].name, "heldout_evidence": x[0],
                                   "validation_gain": 1.0 - st.val_cur / x[3] if x[3]
                                   else None, "val_rmse_without": x[3]} for x in support]
            return
        st.info["removed"].append({"name": r.name, "heldout_evidence": ev,
                                   "val_rmse_with": st.val_cur, "val_rmse_without": v0,
                                   "why": f"held-out evidence 2 ln Λ = {ev:.3g} <= "
                                          f"{st.min_evidence:g} in the final model"})
        st.accept(f0, v0)


def _support(st: _Pruning, r: Term) -> tuple[float, Term, FitResult, float] | None:
    """Held-out evidence of ripple ``r`` in the current model: (2 ln Λ, r, the fit
    without it, its validation RMSE); None when the refit fails."""
    without = [t for t in st.cur.terms if t is not r]
    try:
        f0 = _refit(st.result, without, st.thetas, set(), st.fit_kw)
    except (ValueError, np.linalg.LinAlgError) as e:  # pragma: no cover
        log.debug("support of %s failed: %s", r.name, e)
        return None
    v0 = _val_rmse(st.result, f0)
    ev = heldout_evidence(st.val_cur, v0, st.n_val, min(st.cur.tau_int, f0.tau_int))
    return ev, r, f0, v0
