"""learn: the paper's fault-classification study and the learners beyond it.

Features of the paper (Selections 1-3, :mod:`learn.features`), its protocols (4-fold CV
and leave-one-gear-out on clean and disturbed data, :mod:`learn.protocols`), the study
of Tables VII-X (:mod:`learn.study`), torch MLP and 1D-CNN and MiniRocket as
scikit-learn estimators (:mod:`learn.nets`, :mod:`learn.rocket`), transfer to the gear
not seen in training (:mod:`learn.transfer`) and the observability of faults in the
signals (:mod:`learn.separability`, :mod:`learn.observability`).

The public API is listed in ``__all__``; names are imported on first use (torch only
when a net is asked for).
"""

from __future__ import annotations

from importlib.metadata import PackageNotFoundError, version

from swgsim.lazy import lazy_exports

try:
    __version__ = version("swg-monitor")
except PackageNotFoundError:  # not installed (source tree on sys.path)
    __version__ = "0+unknown"

_EXPORTS = {
    "FeatureSettings": "features", "extract_features": "features",
    "feature_names": "features", "order_spectrum": "features",
    "ProtocolConfig": "protocols", "make_splits": "protocols", "evaluate": "protocols",
    "run_paper_study": "study",
    "MLPClassifierTorch": "nets", "CNN1DClassifier": "nets",
    "MiniRocketClassifier": "rocket",
    "run_comparison": "transfer", "TransferConfig": "transfer",
    "separation_records": "separability", "observability_table": "observability",
}

__all__ = ["__version__", *_EXPORTS]


__getattr__, __dir__ = lazy_exports(__name__, _EXPORTS)
