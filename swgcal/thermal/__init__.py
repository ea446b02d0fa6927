"""Calibration against a joint's measured temperatures (data kind 3: a joint log).

The kind's steps, with the same names and shapes as :mod:`swgcal.friction` and
:mod:`swgcal.strain`: :func:`build_problem` (joint log -> :class:`~swgcal.loop.Problem`,
one joint), :func:`calibrate`, :func:`summarize`, :func:`make_figures`, and :data:`REPORT`
(its report and simulation option, ``joint_thermal.yaml``, for :mod:`swgcal.report`).

Modules: :mod:`.library` (the project's first-order model as the base and the candidate
effects it lacks, with ranges), :mod:`.options`, :mod:`.problem` (signals, probes,
held-out split, builder), :mod:`.report`. An effect kept on one joint checked on the
joints not used in its fit is a study of ``scripts/thermal_ur3.py``'s; logs with known
constants and planted effects are the tests' (``tests/planted_thermal.py``). The log is
read by :func:`swgsim.datasets.joint_log.read_joint_log`; the model it calibrates is
:func:`swgsim.gear.thermal.joint_temperature`'s.
"""

from .library import THERMAL_LIBRARY
from .options import ThermalOptions
from .problem import OPTIONS, build_problem, calibrate, thermal_problem
from .report import REPORT, make_figures, summarize

__all__ = ["OPTIONS", "REPORT", "THERMAL_LIBRARY", "ThermalOptions", "build_problem",
           "calibrate", "make_figures", "summarize", "thermal_problem"]
