"""Calibration against measured joint friction (data kind 1: a friction CSV).

The kind's steps, with the same names and shapes as :mod:`swgcal.strain`:
:func:`build_problem` (recording -> :class:`~swgcal.loop.Problem`),
:func:`calibrate` (-> :class:`~swgcal.loop.CalibrationResult`),
:func:`summarize` (-> ``summary.json``), :func:`make_figures` (-> ``figures/*.png``),
and :data:`REPORT`, what its report (-> ``report.md``) and simulation option
(-> ``friction_effects.yaml``) add to the shared renderer (:mod:`swgcal.report`). The
kind-independent entry points are in :mod:`swgcal`.

Modules: docs/ARCHITECTURE.md, "Calibration loop".
"""

from .data import FrictionRecording, load_friction_csv, write_friction_csv
from .figures import make_figures
from .options import FrictionOptions
from .problem import OPTIONS, build_problem, calibrate, friction_problem
from .report import REPORT, summarize

__all__ = [
    "OPTIONS",
    "REPORT",
    "FrictionOptions",
    "FrictionRecording",
    "build_problem",
    "calibrate",
    "friction_problem",
    "load_friction_csv",
    "make_figures",
    "summarize",
    "write_friction_csv",
]
