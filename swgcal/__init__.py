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

Layout: the kind-independent parts here, each data kind a subpackage of the same shape
(build problem -> calibrate -> summarise -> render -> write); the module map and what
belongs to the simulator: docs/ARCHITECTURE.md, "Calibration loop".
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
