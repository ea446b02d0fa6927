"""Summary, markdown report and simulation option of a strain calibration.

:func:`summarize` (``summary.json``), :func:`order2_table`, and :data:`REPORT`: what the
report (``report.md``; figures: :mod:`.figures`) and ``sensor_effects.yaml`` add to the
shared ones (:mod:`swgcal.report`).
"""

from __future__ import annotations

import json
from collections.abc import Mapping
from typing import Any

import numpy as np

from swgsim.base.markdown import md_table

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
    to_jsonable,
    uncertainty_lines,
)
from .align import flipped_ke, input_angle_evidence
from .checks import (
    result_extras,
    simulation_option,
    too_small_rows,
    withheld_parameters,
)
from .discovery import propose
from .problem import one_blas_thread
from .signals import SENSORS, StrainSignals

__all__ = [
    "IDENTIFIABILITY",
    "REPORT",
    "summarize",
    "order2_components",
    "order2_table",
]

IDENTIFIABILITY = (
    "Declared degeneracies (no encoder angle in schema v1): the WG angle of each window is "
    "a nuisance fitted by alignment, so a delay common to all channels is a shift of that "
    "angle and cannot be identified (time_delay is a simulation option only, not a "
    "candidate); only relative gauge angles are observable (misplacements are relative to "
    "the alignment-weighted mean; the angle of a channel with < 1 % of the alignment "
    "weight is not estimated); a gain common to all channels is the base model's "
    "gauge_gain (channel gains are relative to their mean). A window's input angle is "
    "known modulo 180° only unless odd orders of the torque ripple rise above the noise "
    "(alignment table); the phase of an odd kinematic-error harmonic is then known "
    "modulo π only.")


def _alignment_se(result: CalibrationResult) -> np.ndarray:
    """Standard error of each window's WG angle from the alignment curvature [deg]:
    se(ψ0) = σ / sqrt(Σ_c |∂s_c/∂ψ ⊥ s_c|²), σ the final residual RMS."""
    sig: StrainSignals = result.problem.signals
    sl = slice(sig.n_lead, sig.n_lead + sig.n_t)
    p = sig.basis["s_wg"][:, :, sl] + sig.basis["s_t"][:, :, sl]
    d = sig.basis["dpsi"][:, :, sl]
    p = p - p.mean(-1, keepdims=True)
    d = d - d.mean(-1, keepdims=True)
    proj = (d * p).sum(-1, keepdims=True) / np.maximum((p * p).sum(-1, keepdims=True), 1e-30)
    info = ((d - proj * p) ** 2).sum(-1).sum(-1)  # (n_w,)
    return np.rad2deg(result.final.sigma / np.sqrt(np.maximum(info, 1e-30)))


def summarize(result: CalibrationResult, source: str | None = None) -> dict[str, Any]:
    """Machine-readable summary of a strain calibration (``summary.json``).

    The keys of :func:`swgcal.report.base_summary` (``rmse_before``,
    ``rmse_after`` on the test windows [mV/V], ``unexplained``, ``residual_signature``,
    ``iterations``, ...) with, for the strain side:

    * ``effects_added``: ``[{name, kind, params: {p: {value, stderr, unit, identifiable,
      flag}}, ...}]``;
    * ``heldout``: text; ``heldout_split``: the split as a dict;
    * ``sensor_effects``: accepted measurement effects as the option of
      :func:`swgsim.sensing.effects.apply_sensor_effects`, per-channel values that the data
      cannot pin down set neutral (listed in ``withheld``);
    * ``simulation``: the option with a ``caveat`` (None, or why to use it with care:
      effects accepted in a run that ends unexplained) and ``withheld``;
    * ``too_small``: candidates rejected only for lack of evidence although their
      held-out gain is positive (:mod:`.checks`); ``implausible``: candidates of
      the last iteration with very strong evidence but outside their physical range
      (they make the run ``unexplained``);
    * ``gear_ke_harmonics``: accepted kinematic-error harmonics for :func:`gear_with_ke`;
    * ``chain``: fitted base model (w0, gauge gain) as chain overrides;
    * ``alignment``: per window the time shifts, WG angle at its start (mod 180°) and its
      s.e., input angle at its start (nominal chain, and re-aligned with the accepted
      kinematic-error harmonics) modulo the period the data decide (``phi_in0_period_deg``:
      360°, or 180° where the odd orders of the torque ripple are below the noise,
      :mod:`.align`), with its s.e. and the evidence against a flip by 180°;
    * ``identifiability``: declared degeneracies and flagged parameters.
    """
    with one_blas_thread():  # alignment evidence, discovery: small products
        return _summarize(result, source)


def _summarize(result: CalibrationResult, source: str | None) -> dict[str, Any]:
    s = base_summary(result, source)
    p = result.problem
    split_desc = s.pop("heldout")
    s["heldout"] = split_desc.get("text", "")
    s["heldout_split"] = split_desc
    for e in s["effects_added"]:
        for q in e["params"].values():
            q["stderr"] = q.get("std")
    s["base_model"]["params"] = {k: {**v, "stderr": v.get("std")}
                               for k, v in s["base_model"]["params"].items()}
    final = result.final
    withheld = withheld_parameters(result)
    sensor, ke = simulation_option(result, withheld)
    s["sensor_effects"] = to_jsonable(sensor)
    s["gear_ke_harmonics"] = to_jsonable(ke)
    s["withheld"] = to_jsonable(withheld)
    s["too_small"] = to_jsonable(too_small_rows(result))
    s["implausible"] = list(result.implausible)
    base_term = next(t for t in final.terms if t.kind == "chain")
    base = {e.name: e.value for e in final.estimates_of(base_term.name).values()}
    gain = base.get("gauge_gain", float("nan"))
    s["chain"] = {"w0_m": base.get("w0_mm", float("nan")) * 1e-3, "gauge_gain": gain,
                  "note": ("w0_m -> ChainParams.w0_m; gauge_gain multiplies the gauge factor "
                           "(sensors.gauge_factor) of the whole layout")}
    s["simulation"] = {
        "sensor_effects": s["sensor_effects"], "gear_ke_harmonics": s["gear_ke_harmonics"],
        "call": ("swgsim.sensing.effects.apply_sensor_effects(signals, time_s, n_in_rpm, "
                 "summary['sensor_effects'], t_start_s=..., n_lead=...)"),
        "caveat": caveat(result), "withheld": s["withheld"]}
    se = _alignment_se(result)
    ke_final = tuple((h["order"], float(th[0]), float(th[1])) for h, th in (
        (term.gear_harmonic(final.coefs[i], final.thetas[i]), final.thetas[i])
        for i, term in enumerate(final.terms) if hasattr(term, "gear_harmonic")))
    sig: StrainSignals = p.signals
    if ke_final and sig.ripple is not None:
        upd = sig.ripple(ke_final)
        phi_fin = np.rad2deg(np.mod(upd["phi_in"][:, sig.n_lead], 2 * np.pi))
    else:
        phi_fin = [a["phi_in0_deg"] for a in p.meta["alignment"]]
    phi0 = [a["phi_in0_deg"] for a in p.meta["alignment"]]
    ia0 = ia_f = None
    if sig.ripple is not None:
        sigma2 = max(final.sigma ** 2 * max(final.tau_int, 1.0), 1e-30)
        ia0 = input_angle_evidence(sig.ripple.objectives(()), sig.fs, sig.n_in_rpm, sigma2)
        odd = any(k % 2 for k, _, _ in ke_final)
        ia_f = (input_angle_evidence(
            sig.ripple.objectives(ke_final), sig.fs, sig.n_in_rpm, sigma2,
            flipped=sig.ripple.objectives(flipped_ke(ke_final)) if odd else None)
            if ke_final else ia0)
        phi0, phi_fin = ia0.reported(phi0), ia_f.reported(phi_fin)
    al = [dict(a, psi0_se_deg=float(x), phi_in0_deg=float(f0), phi_in0_final_deg=float(f))
          for a, x, f0, f in zip(p.meta["alignment"], se, phi0, phi_fin, strict=True)]
    if ia0 is not None:
        for w, a in enumerate(al):
            a.update(phi_in0_period_deg=float(ia0.period_deg[w]),
                     phi_in0_se_deg=float(ia0.se_deg[w]),
                     phi_in0_flip_evidence=float(ia0.flip_evidence[w]),
                     phi_in0_final_period_deg=float(ia_f.period_deg[w]),
                     phi_in0_final_flip_evidence=float(ia_f.flip_evidence[w]))
        s["input_angle_global_flip_evidence"] = ia_f.global_evidence
        for h in s["gear_ke_harmonics"]:
            h["phase_known_modulo_rad"] = (np.pi if h["order"] % 2 and not
                                           ia_f.global_evidence > 10.0 else 2 * np.pi)
    s["alignment"] = to_jsonable(al)
    s["data"].pop("alignment", None)
    flagged = [f"{e.term}.{e.name}: {e.flag}" for e in final.estimates if e.flag]
    s["identifiability"] = {"declared": IDENTIFIABILITY, "flagged": flagged,
                            "condition_number": final.cond}
    diag = result.diag_after
    s["rmse_over_noise_floor"] = (result.rmse_after / diag.noise_floor
                                  if diag.noise_floor and diag.noise_floor > 0 else None)
    s["order2"] = to_jsonable(order2_table(result))
    s["proposed"] = [q.as_dict() for q in propose(result)]
    return to_jsonable(s)


def order2_components(sig: StrainSignals, x: np.ndarray) -> np.ndarray:
    """Amplitude and phase of the order-2 (ψ) component per window and channel.

    Parameters
    ----------
    x : ndarray, shape (n_windows * 5 * n_t,)
        Signals on the problem's rows [mV/V].

    Returns
    -------
    ndarray, shape (n_windows, 5, 2)
        Least squares of x on [1, cos 2ψ, sin 2ψ] per window and channel: amplitude
        [mV/V], phase [deg].
    """
    n_w, n_t = sig.n_windows, sig.n_t
    xs = x.reshape(n_w, 5, n_t)
    psi = sig.psi_rad.reshape(n_w, 5, n_t)[:, 0]
    out = np.empty((n_w, 5, 2))
    for w in range(n_w):
        a = np.column_stack([np.ones(n_t), np.cos(2 * psi[w]), np.sin(2 * psi[w])])
        c, *_ = np.linalg.lstsq(a, xs[w].T, rcond=None)  # (3, 5)
        out[w, :, 0] = np.hypot(c[1], c[2])
        out[w, :, 1] = np.rad2deg(np.arctan2(c[2], c[1]))
    return out


def order2_table(result: CalibrationResult) -> list[dict[str, Any]]:
    """Order-2 (ψ) amplitude and phase per operating point and channel: measured, base model
    and final model, mean over the windows of the operating point."""
    sig: StrainSignals = result.problem.signals
    pb, pa = result.predictions()
    m, b, a = (order2_components(sig, x) for x in (result.problem.y, pb, pa))
    op_w = sig.op.reshape(sig.n_windows, -1)[:, 0]
    rows = []
    for i, o in enumerate(sig.ops):
        sel = op_w == i
        for c, s in enumerate(SENSORS):
            def mean_ap(z, sel=sel, c=c):
                amp = float(z[sel, c, 0].mean())
                ph = float(np.rad2deg(np.angle(np.mean(np.exp(1j * np.deg2rad(z[sel, c, 1]))))))
                return amp, ph
            rows.append({"n_in_rpm": o[0], "t_out_nm": o[1], "channel": s,
                         "measured": mean_ap(m), "base_model": mean_ap(b), "final": mean_ap(a)})
    return rows


def _data_section(s: Mapping[str, Any]) -> list[str]:
    """The measured data."""
    d = s["data"]
    return [f"Measured data: `{s['source']}` (kind: strain, schema v1). {d['n_windows']} "
            f"windows of {fmt_value(d['window_s'] * 1e3, 3)} "
            f"ms at {fmt_value(d['sample_rate_hz'])} Hz; "
            "operating points (n_in [rpm], T_out [N m]) "
            + ", ".join(f"({o[0]:g}, {o[1]:g}) × {n}" for o, n in
                        zip(d["operating_points"], d["windows_per_op"], strict=True)) + ".", ""]


def _result_note(s: Mapping[str, Any]) -> str:
    """The noise floor after the held-out RMSE."""
    return (f"; difference-based noise floor {fmt_value(s['noise_floor'])} {s['units']} "
            f"(ratio {fmt_value(s['rmse_over_noise_floor'], 3)})")


def _heldout_section(s: Mapping[str, Any]) -> list[str]:
    """The held-out windows."""
    return ["## Held-out data", "", s["heldout"], ""]


def _base_model_section(s: ReportInput) -> list[str]:
    """The nominal chain's fitted scales, alone and in the final model."""
    return ["## Base model: nominal simulation chain", "",
            s.result.problem.base_model[0].description + ". Fitted on fit + validation "
            "windows:", "", *param_table(s["base_model"]["params"]),
            "In the final model (with the accepted effects):", "",
            *param_table(s["base_model"]["params_in_final_model"])]


def _alignment_section(s: Mapping[str, Any]) -> list[str]:
    """WG and input angle of every window."""
    d = s["data"]
    return ["WG angle of each window (alignment, nominal chain, per window on its own data; "
            "s.e. from the curvature with the final residual σ). The input angle φ_in is "
            "known modulo 360° only where the odd orders of the torque ripple rise above "
            "the noise (evidence 2 ln Λ against the peak 180° away > 10); elsewhere it is "
            "given modulo 180° (ambiguous: the order-2 ripple repeats every half "
            "revolution).", "",
            md_table(["sample", "role", "operating point", "ψ(0) mod 180° [deg]", "s.e. [deg]",
                      "φ_in(0) [deg] (final model)", "known modulo", "2 ln Λ (flip)"],
                     [[f"{a['sample']}", f"{a['role']}",
                       "{:g} rpm, {:g} N m".format(*d["operating_points"][a["op"]]),
                       fmt_value(a["psi0_deg"], 4), fmt_value(a["psi0_se_deg"], 2),
                       fmt_value(a["phi_in0_final_deg"], 4),
                       f"{fmt_value(a.get('phi_in0_final_period_deg'), 3)}°",
                       fmt_value(a.get("phi_in0_final_flip_evidence"), 3)]
                      for a in s["alignment"]]),
            ""]


def _selection_section(s: Mapping[str, Any]) -> list[str]:
    """The acceptance rule and every iteration's ranked candidates."""
    return ["## Selection", "",
            "Each iteration adds every library candidate to the current model and refits on "
            "the fit windows; candidates are ranked by validation RMSE. Accepted: the first "
            "with very strong evidence on the 2 ln B scale of Kass & Raftery (1995): "
            "held-out evidence 2 ln Λ (validation log-likelihood ratio, n/τ_int effective "
            f"samples) > {s['selection']['min_heldout_evidence']:g} and effective ΔBIC on "
            f"the fit windows < {s['selection']['max_delta_bic']:g}"
            + (f", validation gain > {100 * s['selection']['min_rel_improvement']:.2g} %"
               if s['selection']['min_rel_improvement'] > 0 else "")
            + f", its primary parameter pinned down (rel. s.e. < "
            f"{s['selection']['max_rel_se']:g}) and every parameter inside its physical "
            "range (the effect's declared source).", "", *iteration_lines(s, evidence=True)]


def _accepted_section(s: Mapping[str, Any]) -> list[str]:
    """The accepted effects with their parameters, and identifiability."""
    return [*accepted_lines(s), "## Identifiability", "", s["identifiability"]["declared"], "",
            f"Condition number of the scaled JᵀJ of the final model: "
            f"{fmt_value(s['identifiability']['condition_number'], 3)}. Flagged "
            "parameters: " + ("; ".join(s["identifiability"]["flagged"]) or "none") + ".", ""]


def _diagnosis_section(s: Mapping[str, Any]) -> list[str]:
    """Probe scores before and after, residual signatures, the order-2 table."""
    return [*diagnosis_lines(s),
            "Order-2 component of ψ (amplitude [mV/V] / phase [deg]) per operating point and "
            "channel, mean over its windows: how amplitude and phase change with speed and "
            "load.", "",
            md_table(["n_in [rpm]", "T_out [N m]", "channel", "measured", "base model", "final"],
                     [[f"{r['n_in_rpm']:g}", f"{r['t_out_nm']:g}", f"{r['channel']}",
                       *(f"{r[k][0]:.4f} / {r[k][1]:+.1f}"
                         for k in ("measured", "base_model", "final"))]
                      for r in s["order2"]]),
            ""]


_CAPTIONS = {
    "order_spectrum": "Residual amplitude spectrum per channel against the order of the "
                      "input rotation (base model grey, final colour), mean over windows.",
    "offsets": "Mean residual per window and channel along the recording sequence "
               "(offsets, drift), base model and final; held-out windows marked.",
    "channel_differences": "Channel differences s1−s3 and s2−s4 of a test window: measured, "
                           "base model and final model, and their residuals.",
    "speed_load": "Order-2 (ψ) amplitude and phase per window against speed and load: "
                  "measured, base model, final.",
    "overlay": "Measured signals of a test window with the base model and final predictions.",
}


def _simulation_section(s: Mapping[str, Any]) -> list[str]:
    """The accepted effects as a simulation option (sensor effects, KE harmonics)."""
    lines = ["## As a simulation option", ""]
    if s["simulation"].get("caveat"):
        lines += [f"**Caveat.** {s['simulation']['caveat']}", ""]
    if s["withheld"]:
        lines += ["Set neutral here (not pinned down by the data): " + "; ".join(
            f"{w['effect']}.{w['parameter']} ({w['reason']})" for w in s["withheld"]) + ".", ""]
    return lines + ["Measurement effects for `swgsim.sensing.effects.apply_sensor_effects` "
                    "(`sensor_effects` option):", "", "```json",
                    json.dumps(s["sensor_effects"], indent=1), "```", "",
                    "Kinematic-error harmonics for `swgsim.gear.dynamics.gear_with_ke`: "
                    + json.dumps(s["gear_ke_harmonics"]) + "; chain: w0 = "
                    f"{fmt_value(s['chain']['w0_m'])} "
                    f"m, gauge gain {fmt_value(s['chain']['gauge_gain'])}.", ""]


def _option(summary: Mapping[str, Any]) -> SimulationOption:
    """``sensor_effects.yaml``, the data-set option ``sensor_effects``
    (:func:`swgsim.sensing.effects.parse_sensor_effects`), KE harmonics as a comment."""
    sim = summary.get("simulation") or {}
    head = [f"accepted sensor effects of {summary['name']} (swgsim-calibrate); the data-set "
            "option sensor_effects"]
    if sim.get("gear_ke_harmonics"):
        head.append("kinematic-error harmonics (swgsim.gear.dynamics.gear_with_ke): "
                    + json.dumps(sim["gear_ke_harmonics"]))
    return SimulationOption("sensor_effects.yaml", head,
                            {"sensor_effects": list(sim.get("sensor_effects") or [])},
                            sim.get("caveat"))


#: What a strain report adds to the shared skeleton (:func:`swgcal.report.render_report`;
#: figure keys of :func:`~swgcal.strain.figures.make_figures`), and its simulation option.
REPORT = ReportParts(
    title="Strain calibration report", data=_data_section, base_model="nominal chain",
    result_note=_result_note,
    sections=(result_extras, _heldout_section, _base_model_section, _alignment_section,
              _selection_section, _accepted_section, _diagnosis_section, proposals_section),
    captions=_CAPTIONS, closing=(_simulation_section, uncertainty_lines), option=_option)
