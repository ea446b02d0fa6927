"""Summary (JSON-ready dict) and markdown report of a calibration.

:func:`summarize` gives the machine-readable account (``summary.json``): errors before
and after on the test blocks, the accepted effects with parameters and uncertainties
(and against their physical ranges), whether the final residual is still structured and
how, what candidates rejected as physically implausible would have absorbed, how
ripple instances were added, grouped by harmonics or removed, how the held-out data were
chosen, every iteration's candidate ranking, and the accepted effects as a simulation
option (``friction_effects``). :func:`render_report` turns it into markdown; figures are
made elsewhere (``swgcli.calibrate_figures``) and passed in by file name.
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from typing import Any

import numpy as np

from .core import FitResult, Term
from .friction_ripples import RippleTerm
from .loop import CalibrationResult
from .ripple_groups import HARMONIC_REL_TOL

__all__ = ["summarize", "render_report", "UNCERTAINTY_METHOD", "to_jsonable", "fmt_value",
           "param_rows",
           "implausible_candidates", "implausible_lines", "effect_range_lines",
           "ripple_lines"]

UNCERTAINTY_METHOD = (
    "Jacobian of the full parameter vector at the optimum (linear coefficients exactly, "
    "nonlinear parameters by central differences): cov = s² (JᵀJ)⁻¹ · τ_int, s² the "
    "residual variance, τ_int the integrated autocorrelation time of the residual (Sokal's "
    "window, c = 5), an effective-sample-size correction for autocorrelated residuals; "
    "derived parameters (amplitude, phase, b3, θ_b) by the delta method. Approximate: it "
    "treats the regressors as white; a block bootstrap would be the stricter check. A "
    "parameter is flagged as not pinned down when its relative standard error exceeds "
    "max_rel_se; a correlation with another parameter beyond max_abs_corr in magnitude is "
    "noted (the pair trades off).")


def to_jsonable(x: Any) -> Any:
    """Recursively convert numpy scalars/arrays to Python; NaN/inf to None."""
    if isinstance(x, Mapping):
        return {str(k): to_jsonable(v) for k, v in x.items()}
    if isinstance(x, (list, tuple)):
        return [to_jsonable(v) for v in x]
    if isinstance(x, np.ndarray):
        return to_jsonable(x.tolist())
    if isinstance(x, (np.floating, float)):
        v = float(x)
        return v if math.isfinite(v) else None
    if isinstance(x, (np.integer,)):
        return int(x)
    if isinstance(x, np.bool_):
        return bool(x)
    return x


def _params(fit: FitResult, term_name: str) -> dict[str, dict[str, Any]]:
    return {k: e.as_dict() for k, e in fit.estimates_of(term_name).items()}


IMPLAUSIBLE_PREFIX = "rejected: outside its physical range: "


def _ranges_of(term: Term, fit: FitResult) -> dict[str, dict[str, Any]]:
    """Declared physical ranges of a term with the fitted values (``high``/``low`` None
    in JSON for an open side)."""
    est = fit.estimates_of(term.name)
    i = fit.terms.index(term)
    vals = term.derived(fit.coefs[i], fit.thetas[i])
    out = {}
    for name, (lo, hi, src) in dict(getattr(term, "ranges", {}) or {}).items():
        v = est[name].value if name in est else vals.get(name)
        if v is None:
            continue
        out[name] = {"value": float(v), "low": lo, "high": hi, "source": src,
                     "inside": bool(lo <= v <= hi)}
    return out


def _orders_of(term: Term, fit: FitResult) -> dict[str, Any] | None:
    """Harmonics of a ripple and, with the gear ratio, their wave-generator orders and
    whether each is an integer order within :data:`HARMONIC_REL_TOL`."""
    if not isinstance(term, RippleTerm):
        return None
    period = float(fit.thetas[fit.terms.index(term)][0])
    orders = term.orders(period)
    return {"harmonics": list(term.harmonics), "fundamental_period": period,
            "gear_ratio": term.gear_ratio, "orders": orders,
            "integer_order": None if orders is None else [_integer_order(k) for k in orders]}


def _integer_order(k: float) -> bool:
    h = round(k)
    return bool(h >= 1 and abs(k / h - 1.0) <= HARMONIC_REL_TOL)


def implausible_candidates(result: CalibrationResult) -> list[dict[str, Any]]:
    """Candidates that passed the evidence rule but were rejected for a parameter outside
    its physical range: structure in the residual that they would have absorbed.

    Parameters
    ----------
    result : CalibrationResult

    Returns
    -------
    list of dict
        Per candidate: ``iteration``, ``final_iteration`` (True for the residual the loop
        ended with), ``name``, ``kind``, ``validation_gain`` (relative drop of the
        validation RMSE it would have brought), ``val_rmse`` and ``val_rmse_current``
        [data units], ``heldout_evidence``, ``delta_bic_eff``, ``violations`` (each
        parameter against its range and the range's source) and ``params``.
    """
    its = result.iterations
    last = its[-1].index if its else None
    out = []
    for it in its:
        for c in it.candidates:
            if not getattr(c, "implausible", False):
                continue
            st = c.status or ""
            out.append({
                "iteration": it.index, "final_iteration": it.index == last,
                "name": c.name, "kind": c.kind, "validation_gain": c.rel_improvement,
                "val_rmse": c.val_rmse, "val_rmse_current": it.val_rmse,
                "heldout_evidence": getattr(c, "heldout_evidence", None),
                "delta_bic_eff": c.delta_bic_eff,
                "violations": st[len(IMPLAUSIBLE_PREFIX):] if st.startswith(
                    IMPLAUSIBLE_PREFIX) else st,
                "params": dict(c.params)})
    return out


def _library_entry(key: str, cls: type) -> dict[str, Any]:
    try:
        term = cls()
        params = [f"{q.name} [{q.unit}]" for q in (*term.linear, *term.nonlinear)]
    except (TypeError, ValueError):  # a term that needs constructor arguments
        term = cls
        lin = cls.linear if isinstance(cls.linear, tuple) else ()
        params = [f"{q.name} [{q.unit}]" for q in (*lin, *cls.nonlinear)]
    return {"name": key, "description": term.description, "signature": term.signature,
            "source": term.source, "parameters": params}


def summarize(result: CalibrationResult, source: str | None = None) -> dict[str, Any]:
    """Machine-readable summary of a calibration.

    Parameters
    ----------
    result : CalibrationResult
    source : str, optional
        Path of the measured data.

    Returns
    -------
    dict
        JSON-serialisable. Keys include ``rmse_before``, ``rmse_after`` (test blocks,
        data units), ``effects_added`` (list of ``{name, kind, params: {p: {value, std,
        unit, identifiable, flag}}, ...}``), ``unexplained`` (bool),
        ``residual_signature`` (str), ``heldout`` (dict), ``iterations``,
        ``friction_effects`` (simulation option) and ``simulation`` (v_s, t0, baseline).
        Each effect also carries ``ranges`` (its characterising parameters against their
        declared physical ranges, with sources) and, for a ripple, ``orders``
        (harmonics, fundamental period, wave-generator orders when the gear ratio is
        known); ``implausible_candidates`` (:func:`implausible_candidates`) lists what
        candidates rejected for a parameter outside its range would have absorbed, and
        ``ripples`` the harmonic grouping and held-out support of the ripples
        (:func:`~swgsim.calibration.ripple_groups.group_ripples`; None when it did not
        run); ``proposed`` the terms beyond the library that discovery proposes for a
        structured final residual (:meth:`~swgsim.calibration.discovery.Proposal.as_dict`
        entries, :mod:`swgsim.calibration.discovery_friction`; empty otherwise).
    """
    p = result.problem
    final = result.final
    accepted_at = {}
    for it in result.iterations:
        for c in it.candidates:
            if c.accepted:
                for name in c.name.split(" + "):
                    accepted_at[name] = (it.index, c)
    effects = []
    for term in result.effect_terms():
        it_idx, cand = accepted_at.get(term.name, (None, None))
        i = final.terms.index(term)
        effects.append({
            "name": term.name, "kind": term.kind,
            "params": _params(final, term.name),
            "raw_params": term.to_params(final.coefs[i], final.thetas[i]),
            "options": term.options(),
            "description": term.description, "signature": term.signature,
            "source": term.source, "accepted_in_iteration": it_idx,
            "accepted_as": cand.name if cand else None,
            "validation_gain": cand.rel_improvement if cand else None,
            "delta_bic": cand.delta_bic if cand else None,
            "delta_bic_eff": cand.delta_bic_eff if cand else None,
            "ranges": _ranges_of(term, final),
            "orders": _orders_of(term, final),
        })
    base_term = result.baseline_final.terms[0]
    base_params = result.baseline_final.estimates_of(base_term.name)
    final_base = final.estimates_of(base_term.name)
    meta = dict(p.meta)
    ripples = meta.pop("ripples", None)
    sim: dict[str, Any] = {}
    if p.kind == "friction":
        sim = {"v_s_rad_s": meta.get("v_s_rad_s"), "t0_s": meta.get("t0_s"),
               "baseline": {k: e.value for k, e in final_base.items()},
               "call": "swgsim.calibration.FrictionEffects(summary['friction_effects'], "
                       "v_s=summary['simulation']['v_s_rad_s'], baseline=summary['simulation']"
                       "['baseline'], t0=summary['simulation']['t0_s'])"}
    from .discovery import propose  # terms beyond the library (structured residual only)
    proposed = [x.as_dict() for x in propose(result)] if p.kind == "friction" else []
    out = {
        "kind": p.kind, "name": p.name, "source": source, "units": p.units,
        "data": meta,
        "rmse_before": result.rmse_before, "rmse_after": result.rmse_after,
        "rmse_ratio": result.rmse_after / result.rmse_before if result.rmse_before else None,
        "rmse": result.rmse,
        "noise_floor": result.diag_after.noise_floor,
        "baseline": {"name": base_term.name, "description": base_term.description,
                     "params": {k: e.as_dict() for k, e in base_params.items()},
                     "params_in_final_model": {k: e.as_dict() for k, e in final_base.items()}},
        "effects_added": effects,
        "unexplained": bool(result.unexplained),
        "residual_signature": result.residual_signature,
        "residual_signature_before": result.diag_before.signature,
        "diagnosis_before": result.diag_before.as_dict(),
        "diagnosis_after": result.diag_after.as_dict(),
        "heldout": p.split.description,
        "selection": {k: (list(v) if isinstance(v, tuple) else v)
                      for k, v in vars(result.config).items()},
        "iterations": [it.as_dict() for it in result.iterations],
        "implausible_candidates": implausible_candidates(result),
        "ripples": ripples,
        "proposed": proposed,
        "final_model": {"terms": [t.name for t in final.terms], "n_params": final.k,
                        "bic_fit_validation": final.bic, "tau_int": final.tau_int,
                        "condition_number": final.cond},
        "uncertainty_method": UNCERTAINTY_METHOD,
        "friction_effects": [
            {"name": e["name"], "kind": e["kind"], "params": e["raw_params"],
             **({"options": e["options"]} if e["options"] else {})} for e in effects]
        if p.kind == "friction" else [],
        "simulation": sim,
        "library": [_library_entry(k, cls) for k, cls in p.library.items()],
        "elapsed_s": result.elapsed_s,
    }
    return to_jsonable(out)


# ---------------------------------------------------------------------------------------
# markdown


def fmt_value(x: Any, digits: int = 4) -> str:
    """A number for a markdown table: ``digits`` significant digits, "–" for None/NaN.

    Parameters
    ----------
    x : float or None
    digits : int, default 4

    Returns
    -------
    str
    """
    if x is None:
        return "–"
    if isinstance(x, float):
        if not math.isfinite(x):
            return "–"
        return f"{x:.{digits}g}"
    return str(x)


def param_rows(params: Mapping[str, Mapping[str, Any]]) -> list[str]:
    """Markdown rows ``| name | value | std | unit | pinned down |`` of reported parameters.

    Parameters
    ----------
    params : mapping of str to mapping
        ``name -> {"value", "std", "unit", "identifiable", ...}`` (summary entries).

    Returns
    -------
    list of str
    """
    rows = []
    for k, e in params.items():
        ok = "yes" if e["identifiable"] else "no: " + e["flag"]
        if e.get("note"):
            ok += f" ({e['note']})"
        rows.append(f"| {k} | {fmt_value(e['value'])} | {fmt_value(e['std'], 2)} | {e['unit']} "
                    f"| {ok} |")
    return rows


def result_section(summary: Mapping[str, Any], baseline: str, extra: str) -> list[str]:
    """Markdown lines of a report's "Result" section (friction and strain reports).

    Parameters
    ----------
    summary : mapping
        Summary with ``units``, ``rmse`` (fit / validation / test, before / after),
        ``rmse_before``, ``rmse_after``, ``effects_added``, ``unexplained`` and
        ``residual_signature``.
    baseline : str
        Name of the model before calibration, e.g. ``"paper law"``.
    extra : str
        Text right after the held-out RMSE and its unit, e.g. ``" (ratio 0.5)"``.

    Returns
    -------
    list of str
    """
    s, u = summary, summary["units"]
    lines = ["## Result", "", f"| | RMSE before ({baseline}) | RMSE after | after / before |",
             "|---|---|---|---|"]
    for k in ("fit", "validation", "test"):
        b, a = s["rmse"][k]["before"], s["rmse"][k]["after"]
        lines.append(f"| {k} | {fmt_value(b)} {u} | {fmt_value(a)} {u} | "
                     f"{fmt_value(a / b if b else None, 3)} |")
    lines += ["", f"Held-out (test) RMSE {fmt_value(s['rmse_before'])} "
                  f"→ {fmt_value(s['rmse_after'])} "
              f"{u}{extra}. Effects added: "
              + (", ".join(f"**{e['name']}**" for e in s["effects_added"]) or "none") + ".", ""]
    if s["unexplained"]:
        lines += ["**The final residual is still structured and no library effect explains "
                  "it.** " + s["residual_signature"], ""]
    else:
        lines += ["The final residual shows no structure along the probed variables: "
                  + s["residual_signature"], ""]
    lines += implausible_lines(s)
    return lines


def implausible_lines(summary: Mapping[str, Any]) -> list[str]:
    """Markdown lines on the candidates rejected as implausible (summary key
    ``implausible_candidates``): those of the last iteration as structure of the final
    residual that they would have absorbed, earlier ones in one sentence.

    Parameters
    ----------
    summary : mapping

    Returns
    -------
    list of str
        Empty when no candidate was rejected for its physical range.
    """
    imp = list(summary.get("implausible_candidates") or [])
    if not imp:
        return []
    u = summary.get("units", "")
    last = [c for c in imp if c.get("final_iteration")]
    lines = []
    if last:
        lines += [("The final residual holds structure" if summary.get("unexplained") else
                   "The last residual still holds some structure")
                  + " that these library effects would absorb, but only with a parameter "
                  "outside its physical range, so they were rejected as implausible (the "
                  "structure is something else, not explained by the library):", "",
                  "| candidate | would absorb: validation gain | val. RMSE with it | "
                  "held-out evidence | parameter against its range (source) |",
                  "|---|---|---|---|---|"]
        for c in last:
            lines.append(f"| {c['name']} | {fmt_value(100 * (c['validation_gain'] or 0), 3)} % | "
                         f"{fmt_value(c['val_rmse'])} {u} "
                         f"(from {fmt_value(c['val_rmse_current'])}) | "
                         f"{fmt_value(c.get('heldout_evidence'), 4)} | {c['violations']} |")
        lines.append("")
    early = [c for c in imp if not c.get("final_iteration")]
    if early:
        lines += ["Rejected as implausible in earlier iterations: " + "; ".join(
            f"{c['name']} (iteration {c['iteration']}, validation gain "
            f"{fmt_value(100 * (c['validation_gain'] or 0), 3)} %: {c['violations']})"
            for c in early) + ".", ""]
    return lines


def _range_text(r: Mapping[str, Any], unit: str = "") -> str:
    lo = "-inf" if r["low"] is None or r["low"] == -math.inf else fmt_value(r["low"], 3)
    hi = "inf" if r["high"] is None or r["high"] == math.inf else fmt_value(r["high"], 3)
    return f"[{lo}, {hi}]{unit}"


def effect_range_lines(effect: Mapping[str, Any]) -> list[str]:
    """Markdown lines of an accepted effect: its characterising parameters against their
    physical ranges, and for a ripple its harmonics and wave-generator orders.

    Parameters
    ----------
    effect : mapping
        An entry of the summary's ``effects_added``.

    Returns
    -------
    list of str
    """
    lines = []
    rng = effect.get("ranges") or {}
    if rng:
        parts = []
        for k, r in rng.items():
            unit = (effect["params"].get(k) or {}).get("unit", "")
            unit = f" {unit}" if unit and unit != "-" else ""
            parts.append(f"{k} = {fmt_value(r['value'])}{unit} "
                         f"{'inside' if r['inside'] else 'OUTSIDE'} "
                         f"{_range_text(r, unit)} ({r['source']})")
        lines += ["Physical ranges: " + "; ".join(parts) + ".", ""]
    o = effect.get("orders")
    if o:
        h = o["harmonics"]
        txt = (f"Harmonics {', '.join(str(x) for x in h)} of the fundamental period "
               f"{fmt_value(o['fundamental_period'])} rad" if h != [1] else
               f"Period {fmt_value(o['fundamental_period'])} rad")
        if o.get("orders"):
            txt += (f"; gear ratio N = {fmt_value(o['gear_ratio'])}: wave-generator order"
                    f"{'s' if len(h) > 1 else ''} " + ", ".join(
                        f"{k:.3f}" + ("" if ok else " (not an integer order)")
                        for k, ok in zip(o["orders"], o["integer_order"], strict=True)))
        else:
            txt += " (gear ratio not given: no wave-generator order)"
        lines += [txt + ".", ""]
    return lines


def ripple_lines(summary: Mapping[str, Any]) -> list[str]:
    """Markdown section on the ripples (summary key ``ripples``, written by
    :func:`~swgsim.calibration.ripple_groups.group_ripples`): the validation RMSE as
    ripple instances were added, harmonic groups, ripples removed for lack of held-out
    support, the held-out evidence of each ripple kept.

    Parameters
    ----------
    summary : mapping

    Returns
    -------
    list of str
        Empty when the summary has no ripple record or nothing to show.
    """
    rp = summary.get("ripples")
    if not rp or not (rp.get("history") or rp.get("groups") or rp.get("removed")):
        return []
    u = summary.get("units", "")
    n = rp.get("gear_ratio")
    lines = ["## Ripples", "",
             (f"Gear ratio N = {fmt_value(n)}: a period P over the output angle is the "
              "wave-generator order k = 2π / (P N)." if n else
              "Gear ratio not given (option gear_ratio): periods over the output angle "
              "only, no wave-generator orders."), ""]
    hist = rp.get("history") or []
    if hist:
        lines += ["Validation RMSE as ripple instances were added (an instance enters only "
                  "with held-out evidence, see Selection; the last row is the best ripple "
                  "candidate the loop turned down):", "",
                  "| iteration | ripple | period [rad] | order | val. RMSE before → after | "
                  "gain | held-out evidence | added |", "|---|---|---|---|---|---|---|---|"]
        for h in hist:
            lines.append(
                f"| {h['iteration']} | {h['name']} | "
                f"{', '.join(fmt_value(x) for x in h['periods']) or '–'} | "
                f"{', '.join(fmt_value(x, 4) for x in h['orders'] or []) or '–'} | "
                f"{fmt_value(h['val_rmse_before'])} → "
                f"{fmt_value(h['val_rmse_after'])} {u} | "
                f"{fmt_value(100 * (h['validation_gain'] or 0), 3)} % | "
                f"{fmt_value(h['heldout_evidence'], 4)} | "
                + ("yes" if h["accepted"] else f"no: {h['status']}") + " |")
        lines.append("")
    for g in rp.get("groups") or []:
        orders = (", ".join(f"{k:.3f}" for k in g["orders"]) if g.get("orders") else None)
        lines += [f"Harmonic group {', '.join(g['members'])}: periods "
                  + ", ".join(fmt_value(p) for p in g["periods_separate"])
                  + f" rad = harmonics {g['harmonics']} of {fmt_value(g['fundamental_period'])} rad"
                  + (f" (wave-generator orders {orders})" if orders else "")
                  + f"; validation RMSE separate {fmt_value(g['val_rmse_separate'])}, grouped "
                  f"{fmt_value(g['val_rmse_grouped'])} {u}, evidence for separate periods "
                  f"{fmt_value(g['evidence_separate_vs_grouped'], 3)}: "
                  + (f"grouped as one effect **{g['name']}**." if g.get("grouped")
                     else f"kept separate ({g.get('why')})."), ""]
    for r in rp.get("removed") or []:
        lines += [f"Removed **{r['name']}**: {r['why']} (validation RMSE "
                  f"{fmt_value(r['val_rmse_with'])} with, {fmt_value(r['val_rmse_without'])} {u} "
                  "without).", ""]
    sup = rp.get("support") or []
    if sup:
        lines += ["Held-out evidence of each ripple in the final model (2 ln Λ of the "
                  "validation samples, the model without it against the model with it; "
                  f"required > {fmt_value(rp.get('min_heldout_evidence'))}): " + "; ".join(
                      f"{x['name']} {fmt_value(x['heldout_evidence'], 4)} (validation gain "
                      f"{fmt_value(100 * (x['validation_gain'] or 0), 3)} %)" for x in sup)
                  + ".", ""]
    return lines


def render_report(result: CalibrationResult, summary: Mapping[str, Any],
                  figures: Mapping[str, str] | None = None) -> str:
    """Markdown report of a calibration.

    Parameters
    ----------
    result : CalibrationResult
    summary : mapping
        From :func:`summarize`.
    figures : mapping of str to str, optional
        Figure key (``"velocity"``, ``"position"``, ``"hysteresis"``, ``"time"``,
        ``"overlay"``) to a path relative to the report.

    Returns
    -------
    str
    """
    figures = dict(figures or {})
    s = summary
    u = s["units"]
    d = s["data"]
    lines = [f"# Calibration report: {s['name']}", ""]
    lines += [f"Measured data: `{s['source']}` (kind: {s['kind']}). "
              f"{d.get('n_samples')} samples over {fmt_value(d.get('duration_s'))} s, median "
              f"sample interval {fmt_value(d.get('dt_median_s'))} s; acceleration "
              f"{d.get('ddq_source')}; smooth-sign velocity v_s = {fmt_value(d.get('v_s_rad_s'))} "
              "rad/s.", ""]
    if d.get("data_notes"):
        lines += ["Data checks on loading: " + "; ".join(d["data_notes"]) + ".", ""]
    lines += result_section(s, "paper law", f" (ratio {fmt_value(s['rmse_ratio'], 3)})")
    h = s["heldout"]
    lines += ["## Held-out data", "",
              f"{h.get('method')}: {h.get('n_blocks')} blocks of {fmt_value(h.get('block_s'))} s; "
              f"validation blocks {h.get('validation_blocks')}, test blocks "
              f"{h.get('test_blocks')}"
              + (" (the last block is a test block, so drift terms must extrapolate)"
                 if h.get("n_blocks") and h["n_blocks"] - 1 in (h.get("test_blocks") or [])
                 else "")
              + f"; guard of {fmt_value(h.get('guard_s'))} s dropped at every boundary "
              f"between roles; samples {h.get('n_samples')}. {h.get('note', '')}.", ""]
    lines += ["## Baseline: paper law (eq. 5-6 on the joint)", "",
              "τ = b0 tanh(q̇/v_s) + b1 q̇ + b2 q̇³ + b3 sin(q + θ_b), fitted on fit + "
              "validation blocks.", "",
              "| parameter | value | s.e. | unit | identifiable |", "|---|---|---|---|---|"]
    lines += param_rows(s["baseline"]["params"]) + [""]
    lines += ["## Selection", "",
              "Each iteration adds every library candidate to the current model and refits "
              "on the fit blocks; candidates are ranked by validation RMSE. Accepted: the "
              "first in the ranking with validation gain > "
              f"{100 * s['selection']['min_rel_improvement']:.0f} %, "
              f"{'effective ' if s['selection'].get('effective_bic') else ''}ΔBIC < "
              f"{s['selection']['max_delta_bic']:g} and primary parameters pinned down "
              f"(rel. s.e. < {s['selection']['max_rel_se']:g}). When no single candidate "
              "passes, pairs of the best candidates are tried jointly. Effective ΔBIC: "
              "n/τ_int samples (τ_int of the best residual of the iteration).", ""]
    its = s["iterations"]
    for n_it, it in enumerate(its):
        lines += [f"### Iteration {it['index']}: model {' + '.join(it['model'])}, "
                  f"validation RMSE {fmt_value(it['val_rmse'])} {u}", "",
                  f"Residual (fit blocks): {it['diagnosis']['signature']}", ""]
        if it["accepted"]:
            nxt = (its[n_it + 1]["diagnosis"] if n_it + 1 < len(its) else None)
            trace = []
            for name in it["accepted"].split(" + "):
                kind = name.split("#")[0]
                cls = result.problem.library.get(kind)
                for pr in getattr(cls, "probes", ()):
                    b = it["diagnosis"]["probes"].get(pr, {}).get("score")
                    a = nxt["probes"].get(pr, {}).get("score") if nxt else None
                    if b is not None:
                        trace.append(f"{name} ↔ probe {pr}: {fmt_value(b, 2)} → {fmt_value(a, 2)}")
            if trace:
                lines += ["Trace (the accepted effect's signature probes, score before → "
                          "after): " + "; ".join(trace) + ".", ""]
        if not it["candidates"]:
            lines += ["(no candidates tried: iteration limit)", ""]
            continue
        lines += ["| rank | candidate | val. RMSE | gain | ΔBIC | eff. ΔBIC | status |",
                  "|---|---|---|---|---|---|---|"]
        for r, c in enumerate(it["candidates"], 1):
            lines.append(f"| {r} | {c['name']} | {fmt_value(c['val_rmse'])} | "
                         f"{fmt_value(100 * c['rel_improvement'], 3)} "
                         f"% | {fmt_value(c['delta_bic'], 5)} | "
                         f"{fmt_value(c['delta_bic_eff'], 4)} | {c['status']} |")
        lines.append("")
    lines += ["## Accepted effects", ""]
    if not s["effects_added"]:
        lines += ["None.", ""]
    for e in s["effects_added"]:
        lines += [f"### {e['name']}", "",
                  f"{e['description']}. Signature: {e['signature']}. Source: {e['source']}. "
                  f"Accepted in iteration {e['accepted_in_iteration']}"
                  + (f" (as {e['accepted_as']})" if e["accepted_as"] != e["name"] else "")
                  + f": validation gain {fmt_value(100 * (e['validation_gain'] or 0), 3)} %, ΔBIC "
                  f"{fmt_value(e['delta_bic'], 5)}, effective ΔBIC "
                  f"{fmt_value(e['delta_bic_eff'], 4)}.",
                  "", "| parameter | value | s.e. | unit | identifiable |",
                  "|---|---|---|---|---|"]
        lines += param_rows(e["params"]) + [""]
        lines += effect_range_lines(e)
    lines += ["Paper-law parameters in the final model:", "",
              "| parameter | value | s.e. | unit | identifiable |", "|---|---|---|---|---|"]
    lines += param_rows(s["baseline"]["params_in_final_model"]) + [""]
    fm = s["final_model"]
    lines += [f"Final model: {fm['n_params']} parameters, condition number of the scaled "
              f"JᵀJ {fmt_value(fm['condition_number'], 3)}, residual τ_int "
              f"{fmt_value(fm['tau_int'], 3)} samples.", ""]
    lines += ripple_lines(s)
    from .discovery import proposals_section  # apart from the accepted effects
    lines += proposals_section(s.get("proposed", []))
    lines += ["## Residual diagnosis", "",
              "Probe scores: out-of-sample fraction of the residual mean square explained "
              "by a nonparametric model along one variable (two halves of time blocks, "
              f"structured above {fmt_value(s['diagnosis_after']['threshold'])}).", "",
              "| probe | baseline residual | final residual |", "|---|---|---|"]
    pb, pa = s["diagnosis_before"]["probes"], s["diagnosis_after"]["probes"]
    for k in pb:
        lines.append(f"| {k} | {fmt_value(pb[k]['score'], 3)} | {fmt_value(pa[k]['score'], 3)} |")
    lines += ["", f"Baseline residual: {s['residual_signature_before']}", "",
              f"Final residual: {s['residual_signature']}", "",
              f"Noise floor (difference-based, Gasser et al. 1986): "
              f"{fmt_value(s['noise_floor'])} {u}; test RMSE after is "
              f"{fmt_value(s['rmse_after'] / s['noise_floor'] if s['noise_floor'] else None, 3)}× "
              "that (the estimator removes smooth structure and underestimates coloured "
              "noise).", ""]
    captions = {
        "velocity": "Residual against velocity (baseline and final), coloured by the sign "
                    "of the acceleration.",
        "position": "Residual against joint angle per direction of motion, and its "
                    "spectrum over q.",
        "hysteresis": "Residual near reversals: against velocity split by the sign of "
                      "q̇·q̈, and against acceleration.",
        "time": "Residual against time with the block roles, and its spectrum in time.",
        "overlay": "Measured torque and the predictions of the paper law and the final "
                   "model on held-out (test) data.",
    }
    if figures:
        lines += ["## Figures", ""]
        for k, path in figures.items():
            lines += [f"![{k}]({path})", "", f"*{captions.get(k, k)}*", ""]
    lines += ["## Uncertainty", "", s["uncertainty_method"], ""]
    if s["friction_effects"]:
        sim = s["simulation"]
        lines += ["## As a simulation option", "",
                  "The accepted effects, for `swgsim.calibration.FrictionEffects` (or a "
                  "`friction_effects` config list):", "", "```yaml", "friction_effects:"]
        for e in s["friction_effects"]:
            ps = ", ".join(f"{k}: {fmt_value(v, 6)}" for k, v in e["params"].items())
            opt = (", options: {" + ", ".join(f"{k}: {v}" for k, v in e["options"].items())
                   + "}") if e.get("options") else ""
            lines.append(f"  - {{kind: {e['kind']}, name: '{e['name']}', params: {{{ps}}}{opt}}}")
        lines += [f"friction_v_s: {fmt_value(sim.get('v_s_rad_s'), 6)}",
                  f"friction_t0_s: {fmt_value(sim.get('t0_s'), 6)}", "```", ""]
    lines += [f"Run time {fmt_value(s['elapsed_s'], 3)} s.", ""]
    return "\n".join(lines)
