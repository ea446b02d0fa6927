"""swgmon: the condition monitor of a strain wave gear, laid out by the blocks of ISO 13374
(condition monitoring and diagnostics of machines, data processing), lowest first:

* :mod:`swgmon.detection` - state detection: the gear's own normal behaviour and its
  laws, conformal p-values and their CUSUM (the alarm rule);
* :mod:`swgmon.assessment` - health assessment: the diagnosis model that names the
  fault and its severity, the hypotheses an alarm is weighed against (the sensors'
  faults, the unexplained change, one's own), and one gear's monitor that holds them;
* :mod:`swgmon.prognosis` - prognostic assessment: the growth law's remaining useful
  life, its baselines, scores and calibration, and the prognosis along a stream;
* :mod:`swgmon.advisories` - advisory generation: a stream through the monitor, its
  maintenance log, recommissioning and advisories, and its figures;
* :mod:`swgmon.evaluation` - the studies: families of benign changes, the training on
  simulated gears, the monitor's, the prognosis's and the benchmark's evaluations;
* :mod:`swgmon.export` - the monitor's per-window stage as C for a microcontroller.

The health features of a window are the learners' inputs (:mod:`learn.inputs.health`).
Docs: ``docs/monitor.md``.
"""

from __future__ import annotations

from learn import __version__  # one distribution, one version
from swgsim.base.lazy import lazy_exports

#: The front door: a name -> its module under swgmon (imported on first use).
_EXPORTS = {
    "RuleConfig": "detection.rule", "NormalConfig": "detection.normal",
    "DiagnosisModel": "assessment.model", "GearMonitor": "assessment.gear_monitor",
    "load_model": "assessment.model_io", "save_model": "assessment.model_io",
    "NamingConfig": "assessment.sensor_check", "register_hypothesis": "assessment.hypotheses",
    "StreamPrognosis": "prognosis.stream", "predict_growth": "prognosis.growth",
    "monitor_stream": "advisories.stream",
    "MonitorStudyConfig": "evaluation.study", "train_model": "evaluation.training",
}

__all__ = ["__version__", *_EXPORTS]

__getattr__, __dir__ = lazy_exports(__name__, _EXPORTS)
