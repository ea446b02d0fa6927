"""Summary (JSON-ready dict) and markdown report of a calibration.

:func:`summarize` gives the machine-readable account (``summary.json``): errors before
and after on the test blocks, the accepted effects with parameters and uncertainties,
whether the final residual is still structured and how, how the held-out data were
chosen, every iteration's candidate ranking, and the accepted effects as a simulation
option (``friction_effects``). :func:`render_report` turns it into markdown; figures are
made elsewhere (``swgcli.calibrate_figures``) and passed in by file name.
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from typing import Any

import numpy as np

from .core import FitResult
from .loop import CalibrationResult

__all__ = ["summarize", "render_report", "UNCERTAINTY_METHOD", "to_jsonable"]

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
        })
    base_term = result.baseline_final.terms[0]
    base_params = result.baseline_final.estimates_of(base_term.name)
    final_base = final.estimates_of(base_term.name)
    meta = dict(p.meta)
    sim: dict[str, Any] = {}
    if p.kind == "friction":
        sim = {"v_s_rad_s": meta.get("v_s_rad_s"), "t0_s": meta.get("t0_s"),
               "baseline": {k: e.value for k, e in final_base.items()},
               "call": "swgsim.calibration.FrictionEffects(summary['friction_effects'], "
                       "v_s=summary['simulation']['v_s_rad_s'], baseline=summary['simulation']"
                       "['baseline'], t0=summary['simulation']['t0_s'])"}
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


def _fmt(x: Any, digits: int = 4) -> str:
    if x is None:
        return "–"
    if isinstance(x, float):
        if not math.isfinite(x):
            return "–"
        return f"{x:.{digits}g}"
    return str(x)


def _param_rows(params: Mapping[str, Mapping[str, Any]]) -> list[str]:
    rows = []
    for k, e in params.items():
        ok = "yes" if e["identifiable"] else "no: " + e["flag"]
        if e.get("note"):
            ok += f" ({e['note']})"
        rows.append(f"| {k} | {_fmt(e['value'])} | {_fmt(e['std'], 2)} | {e['unit']} | {ok} |")
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
        lines.append(f"| {k} | {_fmt(b)} {u} | {_fmt(a)} {u} | "
                     f"{_fmt(a / b if b else None, 3)} |")
    lines += ["", f"Held-out (test) RMSE {_fmt(s['rmse_before'])} → {_fmt(s['rmse_after'])} "
              f"{u}{extra}. Effects added: "
              + (", ".join(f"**{e['name']}**" for e in s["effects_added"]) or "none") + ".", ""]
    if s["unexplained"]:
        lines += ["**The final residual is still structured and no library effect explains "
                  "it.** " + s["residual_signature"], ""]
    else:
        lines += ["The final residual shows no structure along the probed variables: "
                  + s["residual_signature"], ""]
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
              f"{d.get('n_samples')} samples over {_fmt(d.get('duration_s'))} s, median "
              f"sample interval {_fmt(d.get('dt_median_s'))} s; acceleration "
              f"{d.get('ddq_source')}; smooth-sign velocity v_s = {_fmt(d.get('v_s_rad_s'))} "
              "rad/s.", ""]
    if d.get("data_notes"):
        lines += ["Data checks on loading: " + "; ".join(d["data_notes"]) + ".", ""]
    lines += result_section(s, "paper law", f" (ratio {_fmt(s['rmse_ratio'], 3)})")
    h = s["heldout"]
    lines += ["## Held-out data", "",
              f"{h.get('method')}: {h.get('n_blocks')} blocks of {_fmt(h.get('block_s'))} s; "
              f"validation blocks {h.get('validation_blocks')}, test blocks "
              f"{h.get('test_blocks')}"
              + (" (the last block is a test block, so drift terms must extrapolate)"
                 if h.get("n_blocks") and h["n_blocks"] - 1 in (h.get("test_blocks") or [])
                 else "")
              + f"; guard of {_fmt(h.get('guard_s'))} s dropped at every boundary "
              f"between roles; samples {h.get('n_samples')}. {h.get('note', '')}.", ""]
    lines += ["## Baseline: paper law (eq. 5-6 on the joint)", "",
              "τ = b0 tanh(q̇/v_s) + b1 q̇ + b2 q̇³ + b3 sin(q + θ_b), fitted on fit + "
              "validation blocks.", "",
              "| parameter | value | s.e. | unit | identifiable |", "|---|---|---|---|---|"]
    lines += _param_rows(s["baseline"]["params"]) + [""]
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
                  f"validation RMSE {_fmt(it['val_rmse'])} {u}", "",
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
                        trace.append(f"{name} ↔ probe {pr}: {_fmt(b, 2)} → {_fmt(a, 2)}")
            if trace:
                lines += ["Trace (the accepted effect's signature probes, score before → "
                          "after): " + "; ".join(trace) + ".", ""]
        if not it["candidates"]:
            lines += ["(no candidates tried: iteration limit)", ""]
            continue
        lines += ["| rank | candidate | val. RMSE | gain | ΔBIC | eff. ΔBIC | status |",
                  "|---|---|---|---|---|---|---|"]
        for r, c in enumerate(it["candidates"], 1):
            lines.append(f"| {r} | {c['name']} | {_fmt(c['val_rmse'])} | "
                         f"{_fmt(100 * c['rel_improvement'], 3)} % | {_fmt(c['delta_bic'], 5)} | "
                         f"{_fmt(c['delta_bic_eff'], 4)} | {c['status']} |")
        lines.append("")
    lines += ["## Accepted effects", ""]
    if not s["effects_added"]:
        lines += ["None.", ""]
    for e in s["effects_added"]:
        lines += [f"### {e['name']}", "",
                  f"{e['description']}. Signature: {e['signature']}. Source: {e['source']}. "
                  f"Accepted in iteration {e['accepted_in_iteration']}"
                  + (f" (as {e['accepted_as']})" if e["accepted_as"] != e["name"] else "")
                  + f": validation gain {_fmt(100 * (e['validation_gain'] or 0), 3)} %, ΔBIC "
                  f"{_fmt(e['delta_bic'], 5)}, effective ΔBIC {_fmt(e['delta_bic_eff'], 4)}.",
                  "", "| parameter | value | s.e. | unit | identifiable |",
                  "|---|---|---|---|---|"]
        lines += _param_rows(e["params"]) + [""]
    lines += ["Paper-law parameters in the final model:", "",
              "| parameter | value | s.e. | unit | identifiable |", "|---|---|---|---|---|"]
    lines += _param_rows(s["baseline"]["params_in_final_model"]) + [""]
    fm = s["final_model"]
    lines += [f"Final model: {fm['n_params']} parameters, condition number of the scaled "
              f"JᵀJ {_fmt(fm['condition_number'], 3)}, residual τ_int "
              f"{_fmt(fm['tau_int'], 3)} samples.", ""]
    lines += ["## Residual diagnosis", "",
              "Probe scores: out-of-sample fraction of the residual mean square explained "
              "by a nonparametric model along one variable (two halves of time blocks, "
              f"structured above {_fmt(s['diagnosis_after']['threshold'])}).", "",
              "| probe | baseline residual | final residual |", "|---|---|---|"]
    pb, pa = s["diagnosis_before"]["probes"], s["diagnosis_after"]["probes"]
    for k in pb:
        lines.append(f"| {k} | {_fmt(pb[k]['score'], 3)} | {_fmt(pa[k]['score'], 3)} |")
    lines += ["", f"Baseline residual: {s['residual_signature_before']}", "",
              f"Final residual: {s['residual_signature']}", "",
              f"Noise floor (difference-based, Gasser et al. 1986): "
              f"{_fmt(s['noise_floor'])} {u}; test RMSE after is "
              f"{_fmt(s['rmse_after'] / s['noise_floor'] if s['noise_floor'] else None, 3)}× "
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
            ps = ", ".join(f"{k}: {_fmt(v, 6)}" for k, v in e["params"].items())
            opt = (", options: {" + ", ".join(f"{k}: {v}" for k, v in e["options"].items())
                   + "}") if e.get("options") else ""
            lines.append(f"  - {{kind: {e['kind']}, name: '{e['name']}', params: {{{ps}}}{opt}}}")
        lines += [f"friction_v_s: {_fmt(sim.get('v_s_rad_s'), 6)}",
                  f"friction_t0_s: {_fmt(sim.get('t0_s'), 6)}", "```", ""]
    lines += [f"Run time {_fmt(s['elapsed_s'], 3)} s.", ""]
    return "\n".join(lines)
