"""learn: the paper's fault-classification study and the learners beyond it.

Layers, each importing only those before it:

* :mod:`learn.inputs` - the paper's features (Selections 1-3) and the signal inputs;
  :mod:`learn.tracking` - MLflow runs and their provenance;
* :mod:`learn.learners` - the classifiers (the paper's Table VI and the model registry,
  torch MLP and 1D-CNN, MiniRocket, CORAL);
* :mod:`learn.studies` - protocols, the runs and k-shot splits of transfer to the gear
  not seen in training, the separability of faults in the signals;
* :mod:`learn.tasks` - what the workflows' tasks share: the typed app config, the
  resumable parts of an evaluation;
  :mod:`learn.observability` - one workflow's folder beside them: the observability of
  faults in the signals, its study and the task ``swgsim-observability`` runs;
  :mod:`learn.paper` - the paper study's folder above them: Tables VII-X, its report and
  summary, the task ``paper_study`` and ``run_paper_study`` (``swgsim-paper``) and one job
  of the study, the task ``study``;
  :mod:`learn.transfer` - the transfer comparison's folder above the paper's (its report quotes
  the paper's numbers): its study, report and the task ``transfer``
  (``swgsim-train -m experiment=transfer``).

The condition monitor, its prognosis and their evaluations are their own package,
:mod:`swgmon`; ``swgsim-train``'s dispatch of every task is :mod:`swgcli.tasks`.

The public API is listed in ``__all__``; names are imported on first use (torch only
when a net is asked for).
"""

from __future__ import annotations

from importlib.metadata import PackageNotFoundError, version

from swgsim.base.lazy import lazy_exports

try:
    __version__ = version("swg-monitor")
except PackageNotFoundError:  # not installed (source tree on sys.path)
    __version__ = "0+unknown"

_EXPORTS = {
    "FeatureSettings": "inputs.features", "extract_features": "inputs.features",
    "feature_names": "inputs.features", "order_spectrum": "inputs.features",
    "ModelSpec": "learners.models", "register_model": "learners.models",
    "MLPClassifierTorch": "learners.nets", "CNN1DClassifier": "learners.nets",
    "MiniRocketClassifier": "learners.rocket",
    "ProtocolConfig": "studies.protocols", "make_splits": "studies.protocols",
    "evaluate": "studies.protocols",
    "StudyOptions": "paper.tables", "run_paper_study": "paper.task",
    "run_comparison": "transfer.study", "TransferConfig": "transfer.study",
    "separation_records": "studies.separability",
    "observability_table": "observability.study",
}

__all__ = ["__version__", *_EXPORTS]


__getattr__, __dir__ = lazy_exports(__name__, _EXPORTS)
