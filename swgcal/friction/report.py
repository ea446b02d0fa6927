"""Summary (``summary.json``), markdown report and simulation option of a friction
calibration.

:func:`summarize` adds to the shared keys (:func:`swgcal.report.base_summary`)
the ripples' wave-generator orders, the harmonic grouping, the proposals beyond the
library and the accepted effects as a simulation option (``friction_effects``);
:func:`render_report` turns it into markdown (figures: :mod:`.figures`, passed in by
file name); :func:`simulation_files` gives ``friction_effects.yaml``.
"""

from __future__ import annotations

from collections.abc import Mapping
from typing import Any

from swgsim.gear.friction.ripples import RippleTerm

from ..core import FitResult, Term
from ..discovery import proposals_section
from ..loop import CalibrationResult
from ..report import (
    base_summary,
    caveat,
    effect_range_lines,
    fmt_value,
    option_yaml,
    param_rows,
    result_section,
    to_jsonable,
)
from .discovery import propose
from .ripple_groups import HARMONIC_REL_TOL

__all__ = ["summarize", "render_report", "ripple_lines", "simulation_files"]


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



def summarize(result: CalibrationResult, source: str | None = None) -> dict[str, Any]:
    """Machine-readable summary of a friction calibration (``summary.json``).

    Parameters
    ----------
    result : CalibrationResult
        Of a friction problem.
    source : str, optional
        Path of the measured data.

    Returns
    -------
    dict
        JSON-serialisable: the keys of :func:`swgcal.report.base_summary`
        (``rmse_before``, ``rmse_after`` on the test blocks [N m], ``effects_added``,
        ``unexplained``, ``heldout``, ``iterations``, ...), and for the friction side:
        each ripple in ``effects_added`` carries ``orders`` (harmonics, fundamental
        period, wave-generator orders when the gear ratio is known); ``ripples`` the
        harmonic grouping and held-out support of the ripples
        (:func:`~swgcal.friction.ripple_groups.group_ripples`; None when it
        did not run); ``proposed`` the terms beyond the library that discovery proposes
        for a structured final residual (:mod:`swgcal.friction.discovery`;
        empty otherwise); ``friction_effects`` the accepted effects as a simulation
        option and ``simulation`` (v_s, t0, base model) for
        :class:`swgsim.gear.friction.FrictionEffects`.
    """
    s = base_summary(result, source)
    final = result.final
    by_name = {t.name: t for t in result.effect_terms()}
    for e in s["effects_added"]:
        e["orders"] = to_jsonable(_orders_of(by_name[e["name"]], final))
    base_name = result.base_model_final.terms[0].name
    final_base = final.estimates_of(base_name)
    meta = result.problem.meta
    s["proposed"] = [x.as_dict() for x in propose(result)]
    s["friction_effects"] = [
        {"name": e["name"], "kind": e["kind"], "params": e["raw_params"],
         **({"options": e["options"]} if e["options"] else {})} for e in s["effects_added"]]
    s["simulation"] = {
        "v_s_rad_s": meta.get("v_s_rad_s"), "t0_s": meta.get("t0_s"),
        "base_model": {k: e.value for k, e in final_base.items()},
        "caveat": caveat(result),
        "call": "swgsim.gear.friction.FrictionEffects(summary['friction_effects'], "
                "v_s=summary['simulation']['v_s_rad_s'], base_model=summary['simulation']"
                "['base_model'], t0=summary['simulation']['t0_s'])"}
    return to_jsonable(s)


def simulation_files(summary: Mapping[str, Any]) -> dict[str, str]:
    """The accepted effects as a simulation option: ``friction_effects.yaml`` for
    ``conf/friction_effects/`` (:func:`swgsim.gear.friction.friction_effects_from_config`).

    Parameters
    ----------
    summary : mapping
        From :func:`summarize`.

    Returns
    -------
    dict of str to str
        File name -> text.
    """
    sim = summary.get("simulation") or {}
    fx = {"v_s": sim.get("v_s_rad_s"), "t0_s": sim.get("t0_s"),
          "base_model": sim.get("base_model"), "effects": summary["friction_effects"]}
    head = [f"accepted friction effects of {summary['name']} (swgsim-calibrate); a config "
            "option for conf/friction_effects/"]
    if sim.get("caveat"):
        head.append(f"caveat: {sim['caveat']}")
    return {"friction_effects.yaml": option_yaml(head, fx)}


def ripple_lines(summary: Mapping[str, Any]) -> list[str]:
    """Markdown section on the ripples (summary key ``ripples``, written by
    :func:`~swgcal.friction.ripple_groups.group_ripples`): the validation RMSE as
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


def _data_lines(s: Mapping[str, Any]) -> list[str]:
    """Title and what the measured data are."""
    d = s["data"]
    lines = [f"# Calibration report: {s['name']}", ""]
    lines += [f"Measured data: `{s['source']}` (kind: {s['kind']}). "
              f"{d.get('n_samples')} samples over {fmt_value(d.get('duration_s'))} s, median "
              f"sample interval {fmt_value(d.get('dt_median_s'))} s; acceleration "
              f"{d.get('ddq_source')}; smooth-sign velocity v_s = {fmt_value(d.get('v_s_rad_s'))} "
              "rad/s.", ""]
    if d.get("data_notes"):
        lines += ["Data checks on loading: " + "; ".join(d["data_notes"]) + ".", ""]
    return lines


def _heldout_lines(s: Mapping[str, Any]) -> list[str]:
    """The held-out time blocks."""
    lines: list[str] = []
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
    return lines


def _base_model_lines(s: Mapping[str, Any]) -> list[str]:
    """The paper-law base model and its parameters."""
    lines: list[str] = []
    lines += ["## Base model: paper law (eq. 5-6 on the joint)", "",
              "τ = b0 tanh(q̇/v_s) + b1 q̇ + b2 q̇³ + b3 sin(q + θ_b), fitted on fit + "
              "validation blocks.", "",
              "| parameter | value | s.e. | unit | identifiable |", "|---|---|---|---|---|"]
    lines += param_rows(s["base_model"]["params"]) + [""]
    return lines


def _selection_lines(s: Mapping[str, Any]) -> list[str]:
    """The acceptance rule."""
    lines: list[str] = []
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
    return lines


def _iteration_lines(result: CalibrationResult, its: list, n_it: int, u: str) -> list[str]:
    """One iteration: the residual, the probe trace of the accepted effect, the
    ranked candidates."""
    it = its[n_it]
    lines: list[str] = []
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
        return lines + ["(no candidates tried: iteration limit)", ""]
    lines += ["| rank | candidate | val. RMSE | gain | ΔBIC | eff. ΔBIC | status |",
              "|---|---|---|---|---|---|---|"]
    for r, c in enumerate(it["candidates"], 1):
        lines.append(f"| {r} | {c['name']} | {fmt_value(c['val_rmse'])} | "
                     f"{fmt_value(100 * c['rel_improvement'], 3)} "
                     f"% | {fmt_value(c['delta_bic'], 5)} | "
                     f"{fmt_value(c['delta_bic_eff'], 4)} | {c['status']} |")
    lines.append("")
    return lines


def _accepted_lines(s: Mapping[str, Any]) -> list[str]:
    """The accepted effects and the final model."""
    lines: list[str] = []
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
    lines += param_rows(s["base_model"]["params_in_final_model"]) + [""]
    fm = s["final_model"]
    lines += [f"Final model: {fm['n_params']} parameters, condition number of the scaled "
              f"JᵀJ {fmt_value(fm['condition_number'], 3)}, residual τ_int "
              f"{fmt_value(fm['tau_int'], 3)} samples.", ""]
    return lines


def _diagnosis_lines(s: Mapping[str, Any]) -> list[str]:
    """Probe scores before/after, signatures, noise floor."""
    u = s["units"]
    lines: list[str] = []
    lines += ["## Residual diagnosis", "",
              "Probe scores: out-of-sample fraction of the residual mean square explained "
              "by a nonparametric model along one variable (two halves of time blocks, "
              f"structured above {fmt_value(s['diagnosis_after']['threshold'])}).", "",
              "| probe | base model residual | final residual |", "|---|---|---|"]
    pb, pa = s["diagnosis_before"]["probes"], s["diagnosis_after"]["probes"]
    for k in pb:
        lines.append(f"| {k} | {fmt_value(pb[k]['score'], 3)} | {fmt_value(pa[k]['score'], 3)} |")
    lines += ["", f"Base model residual: {s['residual_signature_before']}", "",
              f"Final residual: {s['residual_signature']}", "",
              f"Noise floor (difference-based, Gasser et al. 1986): "
              f"{fmt_value(s['noise_floor'])} {u}; test RMSE after is "
              f"{fmt_value(s['rmse_after'] / s['noise_floor'] if s['noise_floor'] else None, 3)}× "
              "that (the estimator removes smooth structure and underestimates coloured "
              "noise).", ""]
    return lines


def _figure_lines(figures: Mapping[str, str]) -> list[str]:
    """The figures with captions."""
    lines: list[str] = []
    captions = {
        "velocity": "Residual against velocity (base model and final), coloured by the sign "
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
    return lines


def _simulation_lines(s: Mapping[str, Any]) -> list[str]:
    """The accepted effects as a simulation option."""
    lines: list[str] = []
    if s["friction_effects"]:
        sim = s["simulation"]
        lines += ["## As a simulation option", "",
                  "The accepted effects, for `swgsim.gear.friction.FrictionEffects` (or a "
                  "`friction_effects` config list):", "", "```yaml", "friction_effects:"]
        for e in s["friction_effects"]:
            ps = ", ".join(f"{k}: {fmt_value(v, 6)}" for k, v in e["params"].items())
            opt = (", options: {" + ", ".join(f"{k}: {v}" for k, v in e["options"].items())
                   + "}") if e.get("options") else ""
            lines.append(f"  - {{kind: {e['kind']}, name: '{e['name']}', params: {{{ps}}}{opt}}}")
        lines += [f"friction_v_s: {fmt_value(sim.get('v_s_rad_s'), 6)}",
                  f"friction_t0_s: {fmt_value(sim.get('t0_s'), 6)}", "```", ""]
        if sim.get("caveat"):
            lines += [f"**Caveat.** {sim['caveat']}", ""]
    return lines


def render_report(result: CalibrationResult, summary: Mapping[str, Any],
                  figures: Mapping[str, str] | None = None) -> str:
    """Markdown report of a friction calibration.

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
    s = summary
    lines = _data_lines(s)
    lines += result_section(s, "paper law", f" (ratio {fmt_value(s['rmse_ratio'], 3)})")
    lines += _heldout_lines(s) + _base_model_lines(s) + _selection_lines(s)
    for n_it in range(len(s["iterations"])):
        lines += _iteration_lines(result, s["iterations"], n_it, s["units"])
    lines += _accepted_lines(s)
    lines += ripple_lines(s)
    lines += proposals_section(s.get("proposed", []))
    lines += _diagnosis_lines(s) + _figure_lines(dict(figures or {}))
    lines += ["## Uncertainty", "", s["uncertainty_method"], ""]
    lines += _simulation_lines(s)
    lines += [f"Run time {fmt_value(s['elapsed_s'], 3)} s.", ""]
    return "\n".join(lines)
