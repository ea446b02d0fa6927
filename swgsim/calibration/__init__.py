"""Calibration loop: fit the model to measured data, diagnose the residual, add the
library effect that explains it, refit, and report the error before and after on
held-out data (docs/ARCHITECTURE.md, "Calibration loop").

numpy and scipy only. Typical use::

    from swgsim.calibration import build_problem, calibrate, summarize
    problem = build_problem("franka_joint2_slow.csv")
    result = calibrate(problem)
    summary = summarize(result)          # JSON-ready dict
    markdown = render_report(result, summary, figures={})

Modules: :mod:`.terms` (Param, Term: the term interface), :mod:`.core` (separable least
squares, results, uncertainties), :mod:`.friction` (recordings, paper-law baseline),
:mod:`.friction_effects` (the effect library),
:mod:`.split` (held-out splits), :mod:`.diagnose` (residual probes, noise floor),
:mod:`.loop` (selection loop), :mod:`.problems` (kind detection, problem builders),
:mod:`.report` (summary and markdown), :mod:`.chain` (accepted effects as a simulation
option), :mod:`.synthetic` (planted-effect data); :mod:`.friction_ranges`,
:mod:`.strain_ranges` (physical ranges with sources), :mod:`.friction_ripples`,
:mod:`.ripple_groups` (ripples in gear orders, harmonics grouped); strain side:
:mod:`.strain` (problem builder, runner), :mod:`.strain_data` (measured windows, held-out
split), :mod:`.strain_model` (chain prediction per operating point, alignment),
:mod:`.strain_signals` (signals, constraint basis), :mod:`.strain_effects` (effect
library), :mod:`.strain_probes` (residual probes), :mod:`.strain_report` (summary,
report, figures), :mod:`.strain_align`, :mod:`.strain_checks`, :mod:`.strain_power`;
:mod:`.discovery` (terms beyond the library).
"""

from .chain import FrictionEffects, friction_effects_from_config, parse_effects
from .core import FitResult, Param, ParamEstimate, Term, fit_terms
from .diagnose import Diagnosis, diagnose, friction_probes, noise_floor
from .friction import FrictionRecording, FrictionSignals, PaperLaw, load_friction_csv
from .friction_effects import FRICTION_LIBRARY, make_effect
from .loop import CalibrationResult, Problem, SelectionConfig, calibrate
from .problems import (
                       MeasuredDataError,
                       build_problem,
                       calibrate_friction,
                       detect_kind,
                       friction_problem,
)
from .report import render_report, summarize
from .split import HeldOutSplit, group_split, time_block_split

__all__ = [
    "friction_effects_from_config",
    "FRICTION_LIBRARY",
    "CalibrationResult",
    "Diagnosis",
    "FitResult",
    "FrictionEffects",
    "FrictionRecording",
    "FrictionSignals",
    "HeldOutSplit",
    "MeasuredDataError",
    "PaperLaw",
    "Param",
    "ParamEstimate",
    "Problem",
    "SelectionConfig",
    "Term",
    "build_problem",
    "calibrate",
    "calibrate_friction",
    "detect_kind",
    "diagnose",
    "fit_terms",
    "friction_probes",
    "friction_problem",
    "group_split",
    "load_friction_csv",
    "make_effect",
    "noise_floor",
    "parse_effects",
    "render_report",
    "summarize",
    "time_block_split",
]
