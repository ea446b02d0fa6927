"""Summary (JSON-ready dict), the one markdown renderer and the parts every data kind shares.

:func:`base_summary` gives the machine-readable account every data kind shares
(``summary.json``): errors before and after on the test data, the accepted effects with
parameters and uncertainties (and against their physical ranges), whether the final
residual is still structured and how, what candidates rejected as physically implausible
would have absorbed, how the held-out data were chosen, every iteration's candidate
ranking. :func:`render_report` writes every kind's ``report.md`` from one skeleton and
:func:`simulation_files` its simulation option; a kind declares only what is its own in a
:class:`ReportParts` (``REPORT`` of :mod:`swgcal.friction.report`,
:mod:`swgcal.strain.report`, :mod:`swgcal.thermal.report`), drawing on the sections kinds
share (:func:`iteration_lines`, :func:`accepted_lines`, :func:`diagnosis_lines`, ...).
"""

from __future__ import annotations

import math
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any, NamedTuple

import numpy as np

from swgsim.base.markdown import md_table
from swgsim.files.ownership import save_figure

from .core import FitResult, Term
from .diagnose import WHITENESS_RATIO, acf_and_periodogram
from .loop import IMPLAUSIBLE_PREFIX, CalibrationResult

__all__ = ["base_summary", "caveat", "score_if_physical", "UNCERTAINTY_METHOD", "to_jsonable",
           "fmt_value",
           "param_table", "implausible_candidates", "implausible_lines", "effect_range_lines",
           "ReportInput", "Section", "SimulationOption", "ReportParts", "render_report",
           "simulation_files", "iteration_lines", "accepted_lines", "diagnosis_lines",
           "uncertainty_lines", "heldout_whiteness_figure"]

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
    """Machine-readable summary of a calibration: the keys every data kind shares.

    Parameters
    ----------
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
        (:func:`swgcal.friction.summarize`, :func:`swgcal.strain.summarize`, ...).
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
                     "params": _params(result.base_model_final, base_term.name),
                     "params_in_final_model": _params(final, base_term.name)},
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


# ---------------------------------------------------------------------------------------
# markdown


def score_if_physical(s: dict[str, Any], physical: Mapping[str, list[str]],
                      base: str) -> None:
    """Score a summary only where its base model's fit is physical (issue 86), in place.

    Parameters
    ----------
    s : dict
        A summary (:func:`base_summary`); gets ``physical``, ``scored`` (the base alone
        physical), ``not_scored`` (the one line why not, or None; then ``rmse_before``,
        ``rmse_after`` and ``rmse_ratio`` become None: no headline) and
        ``final_unphysical`` (the one line on the final model's fit, or None: reported,
        not a reason to withhold the score, since its effects may trade off against the
        base's terms).
    physical : mapping
        ``before`` and ``after``: :func:`swgcal.core.physical_check` of the base model
        alone and of the final model.
    base : str
        The base model in words (``"the paper law alone"``).
    """
    before, after = list(physical["before"]), list(physical["after"])
    s["physical"] = {"before": before, "after": after}
    s["scored"] = not before
    s["not_scored"] = None if s["scored"] else (
        f"Not scored as a calibration: the fit of {base} is unphysical ("
        + "; ".join(before) + ").")
    s["final_unphysical"] = None if not after else (
        "The final model's fit is unphysical (" + "; ".join(after) + ").")
    if not s["scored"]:
        s["rmse_before"] = s["rmse_after"] = s["rmse_ratio"] = None


def fmt_value(x: Any, digits: int = 4) -> str:
    """A number for a markdown table: ``digits`` significant digits, "–" for None/NaN."""
    if x is None or (isinstance(x, float) and not math.isfinite(x)):
        return "–"
    return f"{x:.{digits}g}" if isinstance(x, float) else str(x)


def param_table(params: Mapping[str, Mapping[str, Any]],
                head: Sequence[str | None] = ("parameter", "value", "s.e.", "unit",
                                              "identifiable")) -> list[str]:
    """Markdown table ``| name | value | std | unit | pinned down |`` of reported parameters,
    and a blank line.

    Parameters
    ----------
    params : mapping of str to mapping
        ``name -> {"value", "std", "unit", "identifiable", ...}`` (summary entries).
    head : sequence of str or None, optional
        The columns' names (None: a blank one, :func:`swgsim.base.markdown.md_table`).
    """
    rows = []
    for k, e in params.items():
        ok = "yes" if e["identifiable"] else "no: " + e["flag"]
        if e.get("note"):
            ok += f" ({e['note']})"
        rows.append([k, fmt_value(e["value"]), fmt_value(e["std"], 2), f"{e['unit']}", ok])
    return [md_table(head, rows), ""]


def implausible_lines(summary: Mapping[str, Any]) -> list[str]:
    """Markdown lines on the candidates rejected as implausible (summary key
    ``implausible_candidates``): those of the last iteration as structure of the final
    residual that they would have absorbed, earlier ones in one sentence.

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
                  md_table(["candidate", "would absorb: validation gain", "val. RMSE with it",
                            "held-out evidence", "parameter against its range (source)"],
                           [[f"{c['name']}", f"{fmt_value(100 * (c['validation_gain'] or 0), 3)} %",
                             f"{fmt_value(c['val_rmse'])} {u} "
                             f"(from {fmt_value(c['val_rmse_current'])})",
                             fmt_value(c.get("heldout_evidence"), 4), f"{c['violations']}"]
                            for c in last]), ""]
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


# ---------------------------------------------------------------------------------------
# the one renderer: a kind's parts in the shared skeleton


class ReportInput(dict):
    """The summary a report renders (a copy), the calibration ``result`` beside it."""

    def __init__(self, summary: Mapping[str, Any], result: CalibrationResult) -> None:
        super().__init__(summary)
        self.result = result


#: A report section: markdown lines of the summary, ending with a blank line (or none).
Section = Callable[[ReportInput], list[str]]


class SimulationOption(NamedTuple):
    """A kind's simulation option (:func:`simulation_files`): file name, comment lines
    above it (without ``#``), the option (JSON-ready) and its caveat (or None)."""

    file: str
    comments: list[str]
    option: dict[str, Any]
    caveat: str | None


@dataclass(frozen=True)
class ReportParts:
    """What a data kind contributes to the one renderer (:func:`render_report`): the
    ``title`` (before ``": <data name>"``), the ``data`` section under it, the name of the
    ``base_model`` in the Result table (``result_note(summary)`` right after the held-out
    RMSE), the ``sections`` after it, the figure ``captions`` (None: figures without a
    heading or captions), the ``closing`` sections, whether the report ends with the
    ``run_time``, and its simulation ``option`` (:func:`simulation_files`)."""

    title: str
    data: Section
    base_model: str
    sections: tuple[Section, ...]
    option: Callable[[Mapping[str, Any]], SimulationOption]
    result_note: Callable[[Mapping[str, Any]], str] | None = None
    captions: Mapping[str, str] | None = None
    closing: tuple[Section, ...] = ()
    run_time: bool = True


#: The held-out whiteness test's figure: its key among a report's figures, and its caption.
WHITENESS_FIGURE = "heldout_whiteness"
WHITENESS_CAPTION = ("The held-out residual's whiteness test: its autocorrelation against "
                     "the white-noise band ±1.96/√n (Box, Jenkins & Reinsel, sec. 2.1.6), its "
                     "averaged periodogram against white noise at its noise floor.")


def heldout_whiteness_figure(result: CalibrationResult, out_dir: str | Path, dpi: int = 110
                             ) -> dict[str, str]:
    """The held-out whiteness test as a figure (:func:`swgcal.diagnose.acf_and_periodogram`)
    in ``out_dir/figures/`` (atomically) where that test alone makes the final residual
    structured (:attr:`~swgcal.loop.CalibrationResult.heldout_whiteness`).

    Parameters
    ----------
    result : CalibrationResult
    out_dir : str or Path
        The report's folder.
    dpi : int, default 110

    Returns
    -------
    dict of str to str
        ``{WHITENESS_FIGURE: "figures/heldout_whiteness.png"}``, or empty (not drawn).

    Raises
    ------
    ValueError
        No run of 8 consecutive test samples.
    """
    white, p = result.heldout_whiteness or {}, result.problem
    if not white.get("fails") or result.diag_after.structured:
        return {}
    from matplotlib.figure import Figure  # heavy: imported where a figure is drawn

    idx, u = np.asarray(p.split.test), p.units
    acf, freq, power = acf_and_periodogram(p.t, p.y - result.final.predict(p.signals), idx)
    fig = Figure(figsize=(9.0, 6.4), layout="constrained")
    ax1, ax2 = fig.subplots(2, 1)
    band = 1.96 / np.sqrt(idx.size)
    ax1.axhspan(-band, band, color="0.85", label=f"white noise: ±1.96/√n\n(n = {idx.size})")
    ax1.vlines(np.arange(1, acf.size), 0.0, acf[1:], color="tab:red", label="held-out residual")
    ax1.set(xlabel=f"lag [samples of {np.median(np.diff(p.t[idx])):.3g} s]",
            ylabel="autocorrelation [-]", xlim=(0, acf.size))
    ax1.set_title("normalised autocorrelation (lag 0 = 1 not drawn)", fontsize=9)
    edges = np.geomspace(freq[0], freq[-1] * 1.000001, 81)  # log bins, for readability
    b = np.searchsorted(edges, freq, side="right") - 1
    n = np.bincount(b, minlength=80)
    ax2.loglog(np.sqrt(edges[:-1] * edges[1:])[n > 0], (np.bincount(b, power, 80) / np.maximum(
        n, 1))[n > 0], color="tab:red", label="held-out residual\n(log-binned mean)")
    for level, style, text in ((white["noise_floor"], "k--", "white noise at the\nnoise floor"),
                               (white["rms"], "b:", "its mean square\n(RMS)")):
        ax2.axhline(level ** 2, color=style[0], ls=style[1:], label=f"{text} {level:.3g} {u}")
    ax2.set(xlabel="frequency [Hz]", ylabel=f"power [({u})² per frequency bin]")
    ax2.set_title("averaged periodogram against the noise floor", fontsize=9)
    for ax in (ax1, ax2):
        ax.legend(fontsize=8, loc="upper left", bbox_to_anchor=(1.01, 1.0), borderaxespad=0)
    fig.suptitle(f"{p.name}: the held-out (test) residual fails the whiteness test\nRMS / "
                 f"noise floor = {white['rms']:.3g} / {white['noise_floor']:.3g} {u} = "
                 f"{white['ratio']:.2f} > {WHITENESS_RATIO:g} (the test's limit)", fontsize=10)
    (Path(out_dir) / "figures").mkdir(parents=True, exist_ok=True)
    save_figure(fig, Path(out_dir) / (path := f"figures/{WHITENESS_FIGURE}.png"), dpi)
    return {WHITENESS_FIGURE: path}


def render_report(parts: ReportParts, result: CalibrationResult, summary: Mapping[str, Any],
                  figures: Mapping[str, str] | None = None) -> str:
    """Markdown report of a calibration (``report.md``), any data kind: the title, the
    kind's data section, the Result section (RMSE before and after on fit, validation and
    test data, the effects added, whether the final residual is still structured, with
    :data:`WHITENESS_FIGURE`, the candidates rejected as implausible), the kind's sections,
    the figures, its closing sections and the run time (:class:`ReportParts`).

    Parameters
    ----------
    parts : ReportParts
        The kind's (``REPORT`` of its report module).
    summary : mapping
        From the kind's ``summarize``.
    figures : mapping of str to str, optional
        Figure key (the kind's ``make_figures``) -> path relative to the report.
    """
    s, u = ReportInput(summary, result), summary["units"]
    rmse = [(k, s["rmse"][k]["before"], s["rmse"][k]["after"])
            for k in ("fit", "validation", "test")]
    lines = [f"# {parts.title}: {s['name']}", "", *parts.data(s), "## Result", "",
             md_table([None, f"RMSE before ({parts.base_model})", "RMSE after", "after / before"],
                      [[k, f"{fmt_value(b)} {u}", f"{fmt_value(a)} {u}",
                        fmt_value(a / b if b else None, 3)] for k, b, a in rmse]),
             "", f"Held-out (test) RMSE {fmt_value(s['rmse_before'])} → "
             f"{fmt_value(s['rmse_after'])} {u}"
             + (parts.result_note(s) if parts.result_note else "") + ". Effects added: "
             + (", ".join(f"**{e['name']}**" for e in s["effects_added"]) or "none") + ".", "",
             ("**The final residual is still structured and no library effect explains it.** "
              if s["unexplained"] else
              "The final residual shows no structure along the probed variables: ")
             + s["residual_signature"], ""]
    figures = dict(figures or {})
    white = figures.pop(WHITENESS_FIGURE, None)
    if white is not None:
        lines += [f"![held-out residual: autocorrelation and periodogram against the noise "
                  f"floor]({white})", "", f"*{WHITENESS_CAPTION}*", ""]
    lines += implausible_lines(s)
    for section in parts.sections:
        lines += section(s)
    if figures and parts.captions is not None:
        lines += ["## Figures", ""]
    for k, path in figures.items():
        lines += [f"![{k}]({path})", ""]
        if parts.captions is not None:
            lines += [f"*{parts.captions.get(k, k)}*", ""]
    for section in parts.closing:
        lines += section(s)
    if parts.run_time:
        lines += [f"Run time {fmt_value(s['elapsed_s'], 3)} s.", ""]
    return "\n".join(lines)


def simulation_files(parts: ReportParts, summary: Mapping[str, Any]) -> dict[str, str]:
    """The kind's simulation option as YAML, its comments and caveat above it.

    Parameters
    ----------
    summary : mapping
        From the kind's ``summarize``.

    Returns
    -------
    dict of str to str
        File name (e.g. ``friction_effects.yaml``) -> text.
    """
    import yaml

    o = parts.option(summary)
    head = [*o.comments, *([f"caveat: {o.caveat}"] if o.caveat else [])]
    return {o.file: "".join(f"# {c}\n" for c in head)
            + yaml.safe_dump(dict(o.option), sort_keys=False)}


def iteration_lines(summary: Mapping[str, Any], *, evidence: bool = False,
                    detail: Callable[[Any, Any], list[str]] | None = None) -> list[str]:
    """Markdown lines of every iteration: its model, validation RMSE and ranked candidates.

    Parameters
    ----------
    evidence : bool, default False
        With a column of each candidate's held-out evidence 2 ln Λ.
    detail : callable, optional
        ``detail(iteration, next iteration or None)`` -> lines before the candidates.
    """
    its, u = summary["iterations"], summary["units"]
    lines: list[str] = []
    for n, it in enumerate(its):
        lines += [f"### Iteration {it['index']}: model {' + '.join(it['model'])}, validation "
                  f"RMSE {fmt_value(it['val_rmse'])} {u}", ""]
        if detail is not None:
            lines += detail(it, its[n + 1] if n + 1 < len(its) else None)
        if not it["candidates"]:
            lines += ["(no candidates tried: iteration limit)", ""]
            continue
        cols = ["rank", "candidate", "val. RMSE", "gain", *(["2 ln Λ (held out)"] * evidence),
                "ΔBIC", "eff. ΔBIC", f"held-out gain [{u}]", "its floors", "status"]
        lines += [md_table(cols, [
            [r, f"{c['name']}", fmt_value(c["val_rmse"]),
             f"{fmt_value(100 * c['rel_improvement'], 3)} %",
             *[fmt_value(c.get("heldout_evidence"), 4)] * evidence,
             fmt_value(c["delta_bic"], 5), fmt_value(c["delta_bic_eff"], 4),
             f"{fmt_value(c.get('heldout_gain'), 3)} ± {fmt_value(c.get('gain_se'), 2)}",
             c.get("gain_floor_why") or "–", f"{c['status']}"]
            for r, c in enumerate(it["candidates"], 1)]), ""]
        if it.get("gain_floor_why"):
            lines += [f"An effect is kept only with a held-out gain (validation RMSE) above "
                      f"{it['gain_floor_why']}.", ""]
    return lines


def accepted_lines(summary: Mapping[str, Any], *, selection: bool = False) -> list[str]:
    """Markdown section "Accepted effects": each effect's description and parameters.

    Parameters
    ----------
    selection : bool, default False
        Also how each was accepted and its parameters against their physical ranges.
    """
    lines = ["## Accepted effects", ""]
    if not summary["effects_added"]:
        lines += ["None.", ""]
    for e in summary["effects_added"]:
        text = f"{e['description']}. Signature: {e['signature']}. Source: {e['source']}."
        if selection:
            text += (f" Accepted in iteration {e['accepted_in_iteration']}"
                     + (f" (as {e['accepted_as']})" if e["accepted_as"] != e["name"] else "")
                     + f": validation gain {fmt_value(100 * (e['validation_gain'] or 0), 3)} "
                     f"%, ΔBIC {fmt_value(e['delta_bic'], 5)}, effective ΔBIC "
                     f"{fmt_value(e['delta_bic_eff'], 4)}.")
        lines += [f"### {e['name']}", "", text, "", *param_table(e["params"])]
        if selection:
            lines += effect_range_lines(e)
    return lines


def diagnosis_lines(summary: Mapping[str, Any], how: str = "") -> list[str]:
    """Markdown section "Residual diagnosis": probe scores before and after, signatures.

    Parameters
    ----------
    how : str, default ""
        How the probes are scored, before "structured above" (e.g. ``"two halves of time
        blocks, "``).
    """
    s = summary
    pb, pa = s["diagnosis_before"]["probes"], s["diagnosis_after"]["probes"]
    return ["## Residual diagnosis", "",
            "Probe scores: out-of-sample fraction of the residual mean square explained by a "
            f"nonparametric model along one variable ({how}structured above "
            f"{fmt_value(s['diagnosis_after']['threshold'])}).", "",
            md_table(["probe", "base model residual", "final residual"],
                     [[k, fmt_value(pb[k]["score"], 3), fmt_value(pa[k]["score"], 3)]
                      for k in pb]),
            "", f"Base model residual: {s['residual_signature_before']}", "",
            f"Final residual: {s['residual_signature']}", ""]


def uncertainty_lines(summary: Mapping[str, Any]) -> list[str]:
    """Markdown section "Uncertainty" (the summary's ``uncertainty_method``)."""
    return ["## Uncertainty", "", summary["uncertainty_method"], ""]
