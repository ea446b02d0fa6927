"""Summary, report, figure and simulation option of a thermal calibration (data kind 3).

The shared parts (:func:`swgcal.report.base_summary`, :func:`swgcal.report.render_report`)
carry the errors before and after, the effects and their parameters; here (:data:`REPORT`)
what a joint's warm-up adds: the fitted first-order constants as a
:class:`swgsim.gear.thermal.JointThermal` option, and the figure of the measured
temperature against both models.
"""

from __future__ import annotations

from collections.abc import Mapping
from pathlib import Path
from typing import Any

import numpy as np

from swgsim.base.markdown import md_table
from swgsim.files.ownership import save_figure

from ..loop import CalibrationResult
from ..report import (
    ReportParts,
    SimulationOption,
    base_summary,
    caveat,
    fmt_value,
    score_if_physical,
)

__all__ = ["ATTRIBUTION", "REPORT", "make_figures", "measured", "plot_joint", "summarize"]

#: The attribution the UR3 CobotOps day asks for (CC BY 4.0), wherever the file or a figure
#: made from it appears: in every report and figure of this kind, whose format is that day's.
ATTRIBUTION = ("Joint log format, and the UR3 day where it is the data: M. Tyrovolas, K. Aliev, "
               "D. Antonelli and C. Stylios, \"UR3 CobotOps\", UCI Machine Learning "
               "Repository, 2024, doi:10.24432/C5J891, CC BY 4.0.")


def summarize(result: CalibrationResult, source: str | None = None) -> dict[str, Any]:
    """Machine-readable summary of a thermal calibration (``summary.json``).

    Parameters
    ----------
    result : CalibrationResult
        Of a thermal problem (:func:`swgcal.thermal.build_problem`).
    source : str, optional
        Path of the joint log.

    Returns
    -------
    dict
        The keys of :func:`swgcal.report.base_summary` (RMSE before and after on the test
        part [K], ``effects_added`` with their parameters, ``unexplained``, ...) and
        ``joint_thermal``: the final model's first-order constants (``r_th_k_per_w``,
        ``tau_min``, ``ambient_c``) as fields of :class:`swgsim.gear.thermal.JointThermal`,
        with a caveat where the run is unexplained or unphysical; ``physical`` (why the
        base alone and the final model are not physical, :func:`swgcal.core.physical_check`),
        ``scored``, ``not_scored`` and ``final_unphysical``
        (:func:`swgcal.report.score_if_physical`) and ``crossval``
        (:func:`.problem.cross_validate`).
    """
    s = base_summary(result, source)
    s["crossval"] = s["data"].pop("crossval", None)
    score_if_physical(s, s["data"].pop("physical", {"before": [], "after": []}),
                      "the first-order model alone")
    base = result.final.estimates_of(result.final.terms[0].name)
    why = caveat(result) or s["not_scored"] or s["final_unphysical"] or (
        "The final residual is still structured (" + result.residual_signature.rstrip(".")
        + "): the first-order constants were fitted beside what no library effect explains."
        if result.unexplained else None)
    s["joint_thermal"] = {"r_th_k_per_w": base["r_th_k_per_w"].value,
                          "tau_min": base["tau_min"].value,
                          "ambient_c": base["ambient_c"].value, "caveat": why}
    s["attribution"] = ATTRIBUTION
    return s


def _option(summary: Mapping[str, Any]) -> SimulationOption:
    """The fitted first-order constants as a ``JointThermal`` option
    (``joint_thermal.yaml``)."""
    jt = dict(summary["joint_thermal"])
    why = jt.pop("caveat", None)
    return SimulationOption(
        "joint_thermal.yaml", [f"first-order constants of {summary['name']} (swgsim-calibrate, "
                               "thermal); fields of swgsim.gear.thermal.JointThermal",
                               "the loss proxy's constants scale r_th_k_per_w: see "
                               "summary.json data"], jt, why)


def _data_lines(s: Mapping[str, Any]) -> list[str]:
    """The attribution, the joint's log and the loss proxy, what is held out."""
    d = s["data"]
    return [s["attribution"], "",
            f"Joint {d['joint']}, {d['n_samples']} readings from {d['start']} over "
            f"{fmt_value(d['duration_h'], 3)} h, gaps {d['gaps_h']} h, "
            f"{d['missing_readings']} rows without a reading. Loss proxy (1 − η) k_τ |I| |ω| "
            f"with k_τ = {d['torque_per_amp_nm']} N m/A, η = {d['gear_efficiency']}. Room: "
            + (f"measured, {fmt_value(d['room_c'], 4)} °C." if d.get("room_c") is not None else
               f"fitted, at most the coolest joint's first reading "
               f"{fmt_value(d.get('room_max_c'), 4)} °C."), "",
            f"Held out: {s['heldout']}", ""]


_HEAD = ("parameter", "value", "std", "unit", None)


def _params_table(params: Mapping[str, Mapping[str, Any]]) -> list[str]:
    """Parameters with their standard errors, bounds and flags."""
    return [md_table(["parameter", "value", "s.e.", "unit", "bound", "pinned down"], [
        [k, fmt_value(e["value"]), fmt_value(e["std"], 2), f"{e['unit']}",
         e.get("bound") or "-", "yes" if e["identifiable"] else "no: " + e["flag"]]
        for k, e in params.items()]), ""]


def _fit_lines(s: Mapping[str, Any]) -> list[str]:
    """Whether the fits are physical, the base model's constants alone and in the final
    fit, and each kept effect's."""
    ph = s["physical"]
    lines = ["## Physical fits", "", s["not_scored"] or "The first-order model alone is "
             "physical: scored.", "", *([s["final_unphysical"], ""]
                                        if s.get("final_unphysical") else [])]
    lines += [f"- {w}: " + ("; ".join(ph[k]) or "physical") for w, k in
              (("First-order model alone", "before"), ("Final model", "after"))] + [""]
    lines += ["## Base model alone", "", *_params_table(s["base_model"]["params"]),
              "## Base model (final fit)", "",
              *_params_table(s["base_model"]["params_in_final_model"])]
    for e in s["effects_added"]:
        lines += [f"## Effect {e['name']}: {e['description']}", "", *_params_table(e["params"])]
    return lines


def _crossval_lines(s: Mapping[str, Any]) -> list[str]:
    """Held-out RMSE both ways across the gap, before and after each kept effect (its gain,
    both floors)."""
    cv = s.get("crossval")
    if not cv:
        return []
    b = cv["blocks"]
    rows = [[r["model"], *[f"{fmt_value(c['rmse'])} K" + (
        f" (gain {fmt_value(c['gain'], 3)} ± {fmt_value(c.get('gain_se'), 2)}; {c.get('why')})"
        if c["gain"] is not None else "") + (" unphysical" if c["unphysical"] else "")
        for c in (r["forward"], r["backward"])],
        {True: "yes", False: "no"}.get(r.get("clears"), "-")] for r in cv["rows"]]
    return ["## Cross-validation both ways across the gap", "",
            f"A: h {fmt_value(b['A'][0], 3)}-{fmt_value(b['A'][1], 3)}, B: h "
            f"{fmt_value(b['B'][0], 3)}-{fmt_value(b['B'][1], 3)}. Forward: fitted on A, "
            "scored on B; backward: fitted on B, scored on A (its first reading sets the "
            "start). An effect is worth keeping where its gain exceeds, both ways, the "
            f"sensor's resolution {fmt_value(cv['resolution_k'], 3)} K (the smallest step "
            "between readings) and the gain's noise floor, "
            f"{fmt_value(cv.get('z'), 3)} × the standard error of the paired gain on the "
            "scored block (n / τ_int effective samples).",
            "", md_table(["model", "forward RMSE on B", "backward RMSE on A",
                          "gain above both floors both ways"], rows), ""]


def _candidates_lines(s: Mapping[str, Any]) -> list[str]:
    """The candidates of the last iteration."""
    return ["## Candidates of the last iteration", "",
            md_table(["candidate", "validation RMSE", "held-out gain [K]", "its floors",
                      "status"],
                     [[f"{c['name']}", f"{fmt_value(c['val_rmse'])} K",
                       f"{fmt_value(c.get('heldout_gain'), 3)} ± {fmt_value(c.get('gain_se'), 2)}",
                       c.get("gain_floor_why") or "–", f"{c['status']}"]
                      for c in (s["iterations"][-1]["candidates"] if s["iterations"] else [])]),
            ""]


#: What a thermal report adds to the shared skeleton (:func:`swgcal.report.render_report`;
#: figure keys of :func:`make_figures`), and its simulation option.
REPORT = ReportParts(
    title="Thermal calibration", data=_data_lines, base_model="first-order model",
    sections=(_fit_lines, _crossval_lines, _candidates_lines), option=_option,
    run_time=False,
    result_note=lambda s: "" if s["scored"] else " (not scored: unphysical fit, below)")


def make_figures(result: CalibrationResult, out_dir: str | Path) -> dict[str, str]:
    """The measured temperature against the base and the final model, the held-out part
    shaded (``figures/temperature.png``).

    Returns
    -------
    dict of str to str
        ``{"temperature": "figures/temperature.png"}``.
    """
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    p = result.problem
    before, after = result.predictions()
    fig, ax = plt.subplots(figsize=(7, 3.2))
    plot_joint(ax, p.t / 3600.0, measured(p), before, after, p.split.fit.max())
    ax.set_title(p.name, fontsize=9)
    fig.text(0.01, 0.01, ATTRIBUTION, fontsize=5)
    out = Path(out_dir) / "figures"
    out.mkdir(parents=True, exist_ok=True)
    save_figure(fig, out / "temperature.png", 110)
    return {"temperature": "figures/temperature.png"}


def measured(problem: Any) -> np.ndarray:
    """The problem's target [°C], NaN where the log has no reading (in no split)."""
    sp = problem.split
    out = np.full(problem.y.shape, np.nan)
    idx = np.concatenate([sp.fit, sp.validation, sp.test])
    out[idx] = problem.y[idx]
    return out


def plot_joint(ax: Any, hours: np.ndarray, y: np.ndarray, before: np.ndarray,
               after: np.ndarray, last_fit: int) -> None:
    """One joint's panel: measured ``y`` [°C] (NaN: no reading) and both models against
    ``hours``, all shape (n,); the held-out part (after row ``last_fit``) shaded."""
    ax.plot(hours, y, ".", ms=1, color="0.3", label="measured")
    ax.plot(hours, before, lw=1, label="first-order (before)")
    ax.plot(hours, after, lw=1, ls="--", label="with kept effects (after)")
    ax.axvspan(hours[last_fit + 1] if last_fit + 1 < hours.size else hours[-1], hours[-1],
               color="0.9", zorder=0, label="held out")
    ax.set_xlabel("h since the first reading")
    ax.set_ylabel("°C")
    ax.legend(fontsize=6, loc="lower right")
