"""Calibration against a joint's measured temperatures (data kind 3: a joint log).

The kind's steps, with the same names and shapes as :mod:`swgcal.friction` and
:mod:`swgcal.strain`: :func:`build_problem` (joint log -> :class:`~swgcal.loop.Problem`,
one joint), :func:`calibrate`, :func:`summarize`, :func:`render_report`,
:func:`make_figures`, :func:`simulation_files` (-> ``joint_thermal.yaml``).

Modules: :mod:`.library` (the project's first-order model as the base and the candidate
effects it lacks, with ranges), :mod:`.options`, :mod:`.problem` (signals, probes,
held-out split, builder), :mod:`.arm` (an effect kept on one joint checked on the
joints not used in its fit), :mod:`.report`, :mod:`.synthetic` (recordings with known
constants and planted effects). The log is read by
:func:`swgsim.datasets.joint_log.read_joint_log`; the model it calibrates is
:func:`swgsim.gear.thermal.joint_temperature`'s.
"""

from .library import THERMAL_LIBRARY
from .options import ThermalOptions
from .problem import OPTIONS, build_problem, calibrate, thermal_problem
from .report import make_figures, render_report, simulation_files, summarize

__all__ = ["OPTIONS", "THERMAL_LIBRARY", "ThermalOptions", "build_problem", "calibrate",
           "make_figures", "render_report", "simulation_files", "summarize",
           "thermal_problem"]
