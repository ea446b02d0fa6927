"""Calibration of the simulation chain against measured strain windows (data kind 2: a
schema-v1 data-set directory).

The kind's steps, with the same names and shapes as :mod:`swgcal.friction`:
:func:`build_problem` (windows -> :class:`~swgcal.loop.Problem`),
:func:`calibrate` (-> :class:`~swgcal.loop.CalibrationResult`),
:func:`summarize` (-> ``summary.json``), :func:`make_figures` (-> ``figures/*.png``),
and :data:`REPORT`, what its report (-> ``report.md``) and simulation option
(-> ``sensor_effects.yaml``) add to the shared renderer (:mod:`swgcal.report`). The
kind-independent entry points are in :mod:`swgcal`.

Modules: docs/ARCHITECTURE.md, "Calibration loop".
"""

from .data import StrainWindows, strain_windows
from .figures import make_figures
from .model import StrainModel
from .problem import OPTIONS, StrainOptions, build_problem, calibrate, strain_problem
from .report import REPORT, summarize

__all__ = [
    "OPTIONS",
    "REPORT",
    "StrainOptions",
    "StrainModel",
    "StrainWindows",
    "build_problem",
    "calibrate",
    "make_figures",
    "strain_problem",
    "strain_windows",
    "summarize",
]
