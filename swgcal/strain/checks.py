"""What a strain calibration may hand on, and with which caveats.

A calibration's accepted effects become a simulation option (``sensor_effects`` of
:mod:`swgsim.sensing.effects`, kinematic-error harmonics for
:func:`swgsim.gear.dynamics.gear_with_ke`). Three checks decide how:

* *withheld parameters*: a per-channel value that the data cannot pin down is kept out
  of the option (its channel gets the neutral value) and listed with the reason
  (:func:`withheld_parameters`);
* *caveat*: effects accepted in a run whose final residual is still structured may
  have absorbed part of what no library effect explains
  (:func:`swgcal.report.caveat`, shared with the friction side);
* *too small*: candidates rejected only for lack of evidence although their held-out
  gain is positive are named in the report's Result section (:func:`too_small_rows`).
"""

from __future__ import annotations

from collections.abc import Mapping
from typing import Any

from ..loop import CalibrationResult
from ..report import fmt_value

__all__ = ["withheld_parameters", "simulation_option", "too_small_rows", "result_extras"]


def withheld_parameters(result: CalibrationResult) -> list[dict[str, Any]]:
    """Per-channel parameters of accepted effects that the data cannot pin down.

    Two kinds: channels an effect does not estimate (its ``withheld(coef, theta, sig) ->
    {channel: (parameter, reason)}``, e.g. the gauge angle of a channel with almost no
    WG-angle information) and estimated channel values flagged as not pinned down in the
    final fit (:attr:`~swgcal.core.ParamEstimate.flag`) of an effect whose
    channels can be set neutral (``channel_param``). The summary's simulation option sets
    both to the neutral value (:func:`simulation_option`).

    Returns
    -------
    list of dict
        ``{"effect", "channel", "parameter", "value", "reason"}`` per withheld value.
    """
    final = result.final
    sig = result.problem.signals
    out = []
    for term in result.effect_terms():
        fn = getattr(term, "withheld", None)
        if fn is None:
            continue
        i = final.terms.index(term)
        est = final.estimates_of(term.name)
        skip = fn(final.coefs[i], final.thetas[i], sig)
        for c, (pname, reason) in skip.items():
            out.append({"effect": term.name, "channel": int(c), "parameter": pname,
                        "value": None, "reason": reason})
        for c in range(5):
            e = est.get(term.channel_param(c))
            if c in skip or e is None or not e.flag:
                continue
            out.append({"effect": term.name, "channel": c, "parameter": e.name,
                        "value": float(e.value), "reason": f"{e.flag}, ± {e.std:.2g} {e.unit}"})
    return out


def simulation_option(result: CalibrationResult, withheld: list[dict[str, Any]]
                      ) -> tuple[list[dict[str, Any]], list[dict[str, Any]]]:
    """Accepted effects as simulation options, withheld channels neutral.

    Returns
    -------
    sensor_effects : list of dict
        Entries of :func:`swgsim.sensing.effects.apply_sensor_effects`'s ``effects``.
    gear_ke_harmonics : list of dict
        ``{order, amp_rad, phase_rad}`` for :func:`swgsim.gear.dynamics.gear_with_ke`.
    """
    final = result.final
    sensor, ke = [], []
    for term in result.effect_terms():
        i = final.terms.index(term)
        if hasattr(term, "sensor_effect"):
            skip = [w["channel"] for w in withheld if w["effect"] == term.name]
            kw = {"neutral": skip} if skip else {}
            sensor.append(term.sensor_effect(final.coefs[i], final.thetas[i], **kw))
        if hasattr(term, "gear_harmonic"):
            ke.append(term.gear_harmonic(final.coefs[i], final.thetas[i]))
    return sensor, ke


def too_small_rows(result: CalibrationResult) -> list[dict[str, Any]]:
    """Candidates of the last iteration rejected only for lack of evidence although their
    held-out gain is positive (:meth:`CalibrationResult.too_small`).

    Returns
    -------
    list of dict
        ``{"name", "validation_gain", "heldout_evidence", "delta_bic_eff", "params",
        "status"}``, best first (validation gain as a fraction).
    """
    return [{"name": c.name, "validation_gain": float(c.rel_improvement),
             "heldout_evidence": float(c.heldout_evidence),
             "delta_bic_eff": float(c.delta_bic_eff), "params": dict(c.params),
             "status": c.status} for c in result.too_small()]


def result_extras(summary: Mapping[str, Any]) -> list[str]:
    """Markdown lines for the Result section: too-small candidates, withheld
    parameters, caveat."""
    lines: list[str] = []
    small = summary.get("too_small") or []
    sel = summary.get("selection", {})
    if small:
        lines += ["Too small for these data (rejected only for lack of evidence: held-out "
                  f"evidence 2 ln Λ <= {fmt_value(sel.get('min_heldout_evidence'), 3)} or "
                  f"effective ΔBIC >= {fmt_value(sel.get('max_delta_bic'), 3)}, although the "
                  "held-out gain is positive; they may be there, more or longer windows would "
                  "tell): " + "; ".join(f"**{r['name']}** (validation gain "
                                        f"{fmt_value(100 * r['validation_gain'], 2)} %, 2 ln Λ "
                                        f"{fmt_value(r['heldout_evidence'], 3)}, effective ΔBIC "
                                        f"{fmt_value(r['delta_bic_eff'], 3)})" for r in small)
                  + ".", ""]
    wh = summary.get("withheld") or []
    if wh:
        lines += ["Kept out of the simulation option (not pinned down by the data): "
                  + "; ".join(f"{w['effect']}.{w['parameter']} = {fmt_value(w['value'], 3)} "
                              f"({w['reason']})" for w in wh) + ".", ""]
    cv = (summary.get("simulation") or {}).get("caveat")
    if cv:
        lines += [f"**Caveat.** {cv}", ""]
    return lines
