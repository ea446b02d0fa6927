"""Calibration against measured data: fit the model, diagnose the residual, add the
library effect that explains it, refit, and report the error before and after on
held-out data (docs/ARCHITECTURE.md, "Calibration loop").

One API for both data kinds (friction CSVs, schema-v1 strain data sets); each step
returns the same types whatever the kind::

    from swgcal import build_problem, calibrate, write_outputs
    problem = build_problem("franka_joint2_slow.csv")   # or a data-set directory
    result = calibrate(problem)                         # CalibrationResult
    summary = write_outputs(result, "reports/franka")   # report.md, summary.json, ...

or step by step: :func:`summarize` (JSON-ready dict), :func:`render_report` (markdown),
:func:`make_figures`.

Layout: the kind-independent parts here, the kinds in subpackages of the same shape
(build problem -> calibrate -> summarise -> render -> write):

* :mod:`.api` (kind detection and dispatch, writing the files), :mod:`.loop` (problem,
  selection loop, result), :mod:`.core` (separable least squares, uncertainties),
  :mod:`.split` (held-out splits), :mod:`.diagnose` (residual probes, noise floor),
  :mod:`.discovery` (terms beyond the library: the engine), :mod:`.report` (summary keys
  and markdown parts both kinds share), :mod:`.terms` (:class:`~swgcal.terms.FitTerm`:
  what a fit adds to a term's form), :mod:`.periodogram`;
* :mod:`.friction` (data kind 1) and :mod:`.strain` (data kind 2).

The model terms (:mod:`swgsim.gear.terms`), the friction effect forms (:mod:`swgsim.gear.friction`)
and the measurement effects (:mod:`swgsim.sensing.effects`) belong to the simulator; the
calibration fits them and holds what only a fit needs (bounds, starts, probes, physical
ranges).
"""

from .api import (
    KINDS,
    MeasuredDataError,
    build_problem,
    calibrate,
    detect_kind,
    kind_module,
    make_figures,
    options_from_config,
    render_report,
    summarize,
    write_outputs,
)
from .core import FitResult, Param, ParamEstimate, Term, fit_terms
from .diagnose import Diagnosis, diagnose, noise_floor
from .loop import CalibrationResult, Problem, SelectionConfig, select_effects
from .split import HeldOutSplit, group_split, time_block_split

__all__ = [
    "KINDS",
    "CalibrationResult",
    "Diagnosis",
    "FitResult",
    "HeldOutSplit",
    "MeasuredDataError",
    "Param",
    "ParamEstimate",
    "Problem",
    "SelectionConfig",
    "Term",
    "build_problem",
    "calibrate",
    "detect_kind",
    "diagnose",
    "fit_terms",
    "group_split",
    "kind_module",
    "make_figures",
    "noise_floor",
    "options_from_config",
    "render_report",
    "select_effects",
    "summarize",
    "time_block_split",
    "write_outputs",
]
