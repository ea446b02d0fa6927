"""Calibration against a joint's measured temperatures (data kind 3: a joint log).

The kind's steps, with the same names and shapes as :mod:`swgcal.friction` and
:mod:`swgcal.strain`: :func:`build_problem` (joint log -> :class:`~swgcal.loop.Problem`,
one joint), :func:`calibrate`, :func:`summarize`, :func:`make_figures`, and :data:`REPORT`
(its report and simulation option, ``joint_thermal.yaml``, for :mod:`swgcal.report`).

Modules: docs/ARCHITECTURE.md, "Calibration loop".
"""

from .library import THERMAL_LIBRARY
from .options import ThermalOptions
from .problem import OPTIONS, build_problem, calibrate, thermal_problem
from .report import REPORT, make_figures, summarize

__all__ = ["OPTIONS", "REPORT", "THERMAL_LIBRARY", "ThermalOptions", "build_problem",
           "calibrate", "make_figures", "summarize", "thermal_problem"]
