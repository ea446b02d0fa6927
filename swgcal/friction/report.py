"""Summary (``summary.json``), markdown report and simulation option of a friction
calibration.

:func:`summarize` adds to the shared keys (:func:`swgcal.report.base_summary`)
the ripples' wave-generator orders, the harmonic grouping, the proposals beyond the
library and the accepted effects as a simulation option (``friction_effects``);
:data:`REPORT` is what the report (figures: :mod:`.figures`) and ``friction_effects.yaml``
add to the shared ones (:mod:`swgcal.report`).
"""

from __future__ import annotations

from collections.abc import Mapping
from typing import Any

from swgsim.base.markdown import md_table
from swgsim.gear.friction.ripples import RippleTerm, period_in_gear_terms

from ..core import FitResult, Term, physical_check
from ..discovery import proposals_section
from ..loop import CalibrationResult
from ..report import (
    ReportInput,
    ReportParts,
    SimulationOption,
    accepted_lines,
    base_summary,
    caveat,
    diagnosis_lines,
    fmt_value,
    iteration_lines,
    param_table,
    score_if_physical,
    to_jsonable,
    uncertainty_lines,
)
from .discovery import propose
from .ripple_groups import HARMONIC_REL_TOL

__all__ = ["NOT_SIMULATED", "REPORT", "summarize", "ripple_lines"]

#: Accepted effects left out of the simulation option ``friction_effects``: the
#: simulation's friction effects see t, q, q̇, q̈ only (the report says so).
NOT_SIMULATED = ("temperature_friction", "measured_variable")


def _orders_of(term: Term, fit: FitResult) -> dict[str, Any] | None:
    """Harmonics of a ripple and, with the gear ratio, their wave-generator orders and
    whether each is an integer order within :data:`HARMONIC_REL_TOL`."""
    if not isinstance(term, RippleTerm):
        return None
    period = float(fit.thetas[fit.terms.index(term)][0])
    orders = term.orders(period)
    est = fit.estimates_of(term.name).get("period")
    std = est.std if est is not None else float("nan")
    return {"harmonics": list(term.harmonics), "fundamental_period": period,
            "gear_terms": period_in_gear_terms(period, std, term.gear_ratio, HARMONIC_REL_TOL),
            "gear_ratio": term.gear_ratio, "orders": orders,
            "integer_order": None if orders is None else [
                bool(round(k) >= 1 and abs(k / round(k) - 1.0) <= HARMONIC_REL_TOL)
                for k in orders]}


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
    score_if_physical(s, {"before": physical_check(result.base_model_final),
                          "after": physical_check(result.final)}, "the paper law alone")
    final = result.final
    by_name = {t.name: t for t in result.effect_terms()}
    for e in s["effects_added"]:
        e["orders"] = to_jsonable(_orders_of(by_name[e["name"]], final))
    meta = result.problem.meta
    s["proposed"] = [x.as_dict() for x in propose(result)]
    s["friction_effects"] = [
        {"name": e["name"], "kind": e["kind"], "params": e["raw_params"],
         **({"options": e["options"]} if e["options"] else {})} for e in s["effects_added"]
        if e["kind"] not in NOT_SIMULATED]
    s["simulation"] = {
        "v_s_rad_s": meta.get("v_s_rad_s"), "t0_s": meta.get("t0_s"),
        "base_model": {k: e["value"] for k, e in s["base_model"]["params_in_final_model"].items()},
        "caveat": caveat(result),
        "call": "swgsim.gear.friction.FrictionEffects(summary['friction_effects'], "
                "v_s=summary['simulation']['v_s_rad_s'], base_model=summary['simulation']"
                "['base_model'], t0=summary['simulation']['t0_s'])"}
    return to_jsonable(s)


def _option(summary: Mapping[str, Any]) -> SimulationOption:
    """``friction_effects.yaml`` (:func:`swgsim.gear.friction.friction_effects_from_config`)."""
    sim = summary.get("simulation") or {}
    fx = {"v_s": sim.get("v_s_rad_s"), "t0_s": sim.get("t0_s"),
          "base_model": sim.get("base_model"), "effects": summary["friction_effects"]}
    return SimulationOption(
        "friction_effects.yaml", [f"accepted friction effects of {summary['name']} "
                                  "(swgsim-calibrate); a config option for "
                                  "conf/friction_effects/"], fx, sim.get("caveat"))


def ripple_lines(summary: Mapping[str, Any]) -> list[str]:
    """Markdown section on the ripples (summary key ``ripples``, written by
    :func:`~swgcal.friction.ripple_groups.group_ripples`): the validation RMSE as
    ripple instances were added, harmonic groups, ripples removed for lack of held-out
    support, the held-out evidence of each ripple kept.

    Returns
    -------
    list of str
        Empty when the summary has no ripple record or nothing to show.
    """
    rp = summary.get("ripples")
    if not rp or not (rp.get("history") or rp.get("groups") or rp.get("removed")
                      or rp.get("merged")):
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
                  md_table(["iteration", "ripple", "period [rad]", "order",
                            "val. RMSE before → after", "gain", "held-out evidence", "added"],
                           [[f"{h['iteration']}", f"{h['name']}",
                             ", ".join(fmt_value(x) for x in h["periods"]) or "–",
                             ", ".join(fmt_value(x, 4) for x in h["orders"] or []) or "–",
                             f"{fmt_value(h['val_rmse_before'])} → "
                             f"{fmt_value(h['val_rmse_after'])} {u}",
                             f"{fmt_value(100 * (h['validation_gain'] or 0), 3)} %",
                             fmt_value(h["heldout_evidence"], 4),
                             "yes" if h["accepted"] else f"no: {h['status']}"] for h in hist]),
                  ""]
    for m in rp.get("merged") or []:
        lines += [f"Merged **{m['members'][1]}** into **{m['name']}**: periods "
                  + ", ".join(fmt_value(x, 6) for x in m["periods"]) + " rad, "
                  f"|1/P1 − 1/P2| × span = {fmt_value(m['resolution'], 3)} < 1 (the recording "
                  f"cannot tell them apart); refitted period {fmt_value(m['period'], 6)} rad, "
                  f"validation RMSE {fmt_value(m['val_rmse_separate'])} separate, "
                  f"{fmt_value(m['val_rmse_merged'])} {u} merged.", ""]
    table = _period_table(summary)
    if table:
        lines += ["Periods of the final model's ripples (nonlinear least squares; standard "
                  "errors corrected for the residual's autocorrelation):", "", *table, ""]
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


def _period_table(summary: Mapping[str, Any]) -> list[str]:
    """Markdown table of the final ripples' periods with standard errors and orders."""
    rows = []
    for e in summary.get("effects_added") or []:
        g = (e.get("orders") or {}).get("gear_terms")
        if not g:
            continue
        wg = (f"{fmt_value(g['wg_order'], 6)} ± {fmt_value(g['wg_order_std'], 2)}"
              if "wg_order" in g else "– (gear ratio not given)")
        rows.append([e["name"], f"{fmt_value(g['period'], 7)} ± {fmt_value(g['period_std'], 2)}",
                     f"{fmt_value(100 * g['rel_std'], 2)} %",
                     f"{fmt_value(g['output_order'], 6)} ± {fmt_value(g['output_order_std'], 2)}",
                     wg, g.get("reading", "–")])
    return [md_table(["ripple", "period [rad]", "rel. s.e.", "cycles per output turn",
                      "wave-generator (= motor) order", "reading"], rows)] if rows else []


def _data_lines(s: Mapping[str, Any]) -> list[str]:
    """What the measured data are."""
    d = s["data"]
    lines = [f"Measured data: `{s['source']}` (kind: {s['kind']}). "
             f"{d.get('n_samples')} samples over {fmt_value(d.get('duration_s'))} s, median "
             f"sample interval {fmt_value(d.get('dt_median_s'))} s; acceleration "
             f"{d.get('ddq_source')}; smooth-sign velocity v_s = {fmt_value(d.get('v_s_rad_s'))} "
             "rad/s.", ""]
    if d.get("data_notes"):
        lines += ["Data checks on loading: " + "; ".join(d["data_notes"]) + ".", ""]
    return lines


def _heldout_lines(s: Mapping[str, Any]) -> list[str]:
    """The held-out time blocks."""
    h = s["heldout"]
    return ["## Held-out data", "",
            f"{h.get('method')}: {h.get('n_blocks')} blocks of {fmt_value(h.get('block_s'))} s; "
            f"validation blocks {h.get('validation_blocks')}, test blocks {h.get('test_blocks')}"
            + (" (the last block is a test block, so drift terms must extrapolate)"
               if h.get("n_blocks") and h["n_blocks"] - 1 in (h.get("test_blocks") or [])
               else "")
            + f"; guard of {fmt_value(h.get('guard_s'))} s dropped at every boundary "
            f"between roles; samples {h.get('n_samples')}. {h.get('note', '')}.", ""]


def _base_model_lines(s: Mapping[str, Any]) -> list[str]:
    """The paper-law base model and its parameters."""
    return ["## Base model: paper law (eq. 5-6 on the joint)", "",
            "τ = b0 tanh(q̇/v_s) + b1 q̇ + b2 q̇³ + b3 sin(q + θ_b), fitted on fit + "
            "validation blocks.", "", *param_table(s["base_model"]["params"]),
            s.get("not_scored") or "The paper law alone is physical (b0, b1 >= 0, no "
                                   "parameter on a bound of its fit): scored.", "",
            *([s["final_unphysical"], ""] if s.get("final_unphysical") else [])]


def _selection_lines(s: ReportInput) -> list[str]:
    """The acceptance rule, then every iteration with its residual and ranked candidates."""
    library = s.result.problem.library
    return ["## Selection", "",
            "Each iteration adds every library candidate to the current model and refits "
            "on the fit blocks; candidates are ranked by validation RMSE. Accepted: the "
            "first in the ranking with validation gain > "
            f"{100 * s['selection']['min_rel_improvement']:.0f} %, "
            f"{'effective ' if s['selection'].get('effective_bic') else ''}ΔBIC < "
            f"{s['selection']['max_delta_bic']:g} and primary parameters pinned down "
            f"(rel. s.e. < {s['selection']['max_rel_se']:g}). When no single candidate "
            "passes, pairs of the best candidates are tried jointly. Effective ΔBIC: "
            "n/τ_int samples (τ_int of the best residual of the iteration).", "",
            *iteration_lines(s, detail=lambda it, nxt: _residual_lines(library, it, nxt))]


def _residual_lines(library: Mapping[str, type], it: Mapping[str, Any],
                    nxt: Mapping[str, Any] | None) -> list[str]:
    """An iteration's residual and the probe scores of the effect it accepted, before/after."""
    lines = [f"Residual (fit blocks): {it['diagnosis']['signature']}", ""]
    if not it["accepted"]:
        return lines
    trace = []
    for name in it["accepted"].split(" + "):
        for pr in getattr(library.get(name.split("#")[0]), "probes", ()):
            b = it["diagnosis"]["probes"].get(pr, {}).get("score")
            a = nxt["diagnosis"]["probes"].get(pr, {}).get("score") if nxt else None
            if b is not None:
                trace.append(f"{name} ↔ probe {pr}: {fmt_value(b, 2)} → {fmt_value(a, 2)}")
    if trace:
        lines += ["Trace (the accepted effect's signature probes, score before → "
                  "after): " + "; ".join(trace) + ".", ""]
    return lines


def _accepted_lines(s: Mapping[str, Any]) -> list[str]:
    """The accepted effects and the final model."""
    fm = s["final_model"]
    return [*accepted_lines(s, selection=True), "Paper-law parameters in the final model:", "",
            *param_table(s["base_model"]["params_in_final_model"]),
            f"Final model: {fm['n_params']} parameters, condition number of the scaled "
            f"JᵀJ {fmt_value(fm['condition_number'], 3)}, residual τ_int "
            f"{fmt_value(fm['tau_int'], 3)} samples.", ""]


def _diagnosis_lines(s: Mapping[str, Any]) -> list[str]:
    """Probe scores before/after, signatures, noise floor."""
    return [*diagnosis_lines(s, "two halves of time blocks, "),
            f"Noise floor (difference-based, Gasser et al. 1986): "
            f"{fmt_value(s['noise_floor'])} {s['units']}; test RMSE after is "
            f"{fmt_value(s['rmse_after'] / s['noise_floor'] if s['noise_floor'] else None, 3)}× "
            "that (the estimator removes smooth structure and underestimates coloured "
            "noise).", ""]


_CAPTIONS = {
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


def _simulation_lines(s: Mapping[str, Any]) -> list[str]:
    """The accepted effects as a simulation option."""
    if not s["friction_effects"]:
        return []
    sim = s["simulation"]
    lines = ["## As a simulation option", "",
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
    left = [e["name"] for e in s["effects_added"] if e["kind"] in NOT_SIMULATED]
    if left:
        lines += [f"Left out: {', '.join(left)} (the simulation's friction effects see t, q, "
                  "q̇, q̈, not the joint's temperature or another measured variable).", ""]
    return lines


#: What a friction report adds to the shared skeleton (:func:`swgcal.report.render_report`;
#: figure keys of :func:`~swgcal.friction.figures.make_figures`), and its simulation option.
REPORT = ReportParts(
    title="Calibration report", data=_data_lines, base_model="paper law",
    result_note=lambda s: f" (ratio {fmt_value(s['rmse_ratio'], 3)})",
    sections=(_heldout_lines, _base_model_lines, _selection_lines, _accepted_lines,
              ripple_lines, proposals_section, _diagnosis_lines),
    captions=_CAPTIONS, closing=(uncertainty_lines, _simulation_lines), option=_option)
