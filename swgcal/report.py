"""Summary (JSON-ready dict) and markdown parts shared by both data kinds.

:func:`base_summary` gives the machine-readable account both data kinds share
(``summary.json``): errors before and after on the test data, the accepted effects with
parameters and uncertainties (and against their physical ranges), whether the final
residual is still structured and how, what candidates rejected as physically implausible
would have absorbed, how the held-out data were chosen, every iteration's candidate
ranking. The markdown helpers (:func:`result_section`, :func:`param_rows`,
:func:`effect_range_lines`, ...) are shared by the kinds' reports
(:mod:`swgcal.friction.report`, :mod:`swgcal.strain.report`).
"""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from typing import Any

import numpy as np

from .core import FitResult, Term
from .loop import CalibrationResult

__all__ = ["base_summary", "caveat", "option_yaml", "UNCERTAINTY_METHOD", "to_jsonable",
           "fmt_value", "param_rows",
           "result_section", "implausible_candidates", "implausible_lines",
           "effect_range_lines"]

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


def base_summary(result: CalibrationResult, source: str | None = None) -> dict[str, Any]:
    """Machine-readable summary of a calibration: the keys both data kinds share.

    Parameters
    ----------
    result : CalibrationResult
    source : str, optional
        Path of the measured data.

    Returns
    -------
    dict
        JSON-serialisable. Keys include ``rmse_before``, ``rmse_after`` (test data,
        data units), ``effects_added`` (list of ``{name, kind, params: {p: {value, std,
        unit, identifiable, flag}}, ...}``; each also carries ``ranges``, its
        characterising parameters against their declared physical ranges with sources),
        ``unexplained`` (bool), ``residual_signature`` (str), ``heldout`` (dict),
        ``iterations``, ``implausible_candidates`` (:func:`implausible_candidates`),
        ``ripples`` (``problem.meta["ripples"]`` when a kind records it, else None),
        ``final_model``, ``library``. Each kind's ``summarize`` adds its own keys
        (:func:`swgcal.friction.summarize`,
        :func:`swgcal.strain.summarize`).
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
        })
    base_term = result.base_model_final.terms[0]
    base_params = result.base_model_final.estimates_of(base_term.name)
    final_base = final.estimates_of(base_term.name)
    meta = dict(p.meta)
    ripples = meta.pop("ripples", None)
    out = {
        "kind": p.kind, "name": p.name, "source": source, "units": p.units,
        "data": meta,
        "rmse_before": result.rmse_before, "rmse_after": result.rmse_after,
        "rmse_ratio": result.rmse_after / result.rmse_before if result.rmse_before else None,
        "rmse": result.rmse,
        "noise_floor": result.diag_after.noise_floor,
        "base_model": {"name": base_term.name, "description": base_term.description,
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
        "final_model": {"terms": [t.name for t in final.terms], "n_params": final.k,
                        "bic_fit_validation": final.bic, "tau_int": final.tau_int,
                        "condition_number": final.cond},
        "uncertainty_method": UNCERTAINTY_METHOD,
        "library": [_library_entry(k, cls) for k, cls in p.library.items()],
        "elapsed_s": result.elapsed_s,
    }
    return to_jsonable(out)



def caveat(result: CalibrationResult) -> str | None:
    """Caveat for the simulation option of a run that ends unexplained, else None.

    Parameters
    ----------
    result : CalibrationResult

    Returns
    -------
    str or None
        Why to use the accepted effects with care (the final residual is still
        structured, so they may have absorbed part of it); None when the run is explained
        or accepted nothing.
    """
    if not (result.unexplained and result.added):
        return None
    return ("The final residual is still structured (" + result.residual_signature.rstrip(".")
            + "): the accepted effects (" + ", ".join(result.added) + ") were chosen in the "
            "presence of structure that no library effect explains and may have absorbed "
            "part of it. Use them as a simulation option with care: check them on data "
            "without that structure, or once the structure is modelled.")


def option_yaml(comments: Sequence[str], option: Mapping[str, Any]) -> str:
    """A simulation option as YAML text, with comment lines above it.

    Parameters
    ----------
    comments : sequence of str
        One comment per line, without the ``#``.
    option : mapping
        The option (JSON-ready values).

    Returns
    -------
    str
    """
    import yaml

    return "".join(f"# {c}\n" for c in comments) + yaml.safe_dump(dict(option),
                                                                   sort_keys=False)


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


def result_section(summary: Mapping[str, Any], base_model: str, extra: str) -> list[str]:
    """Markdown lines of a report's "Result" section (friction and strain reports).

    Parameters
    ----------
    summary : mapping
        Summary with ``units``, ``rmse`` (fit / validation / test, before / after),
        ``rmse_before``, ``rmse_after``, ``effects_added``, ``unexplained`` and
        ``residual_signature``.
    base model : str
        Name of the model before calibration, e.g. ``"paper law"``.
    extra : str
        Text right after the held-out RMSE and its unit, e.g. ``" (ratio 0.5)"``.

    Returns
    -------
    list of str
    """
    s, u = summary, summary["units"]
    lines = ["## Result", "", f"| | RMSE before ({base_model}) | RMSE after | after / before |",
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


