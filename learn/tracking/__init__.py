"""Experiment tracking: MLflow runs (:mod:`learn.tracking.mlflow_runs`; ``log_run`` is the
one helper every run goes through), the MLflow store they go to
(:mod:`learn.tracking.store`) and their provenance, git commit, data set and model
requirements (:mod:`learn.tracking.provenance`); what a task logs
(:class:`learn.tracking.config.LoggerConfig`). Imports no other part of :mod:`learn`.

The public names are imported on first use (no MLflow import at package import).
"""

from __future__ import annotations

from swgsim.base.lazy import lazy_exports

_EXPORTS = {
    **dict.fromkeys(("GROUP_PARENT_TAG", "TrackedRun", "flatten_config", "log_job",
                     "log_run"), "mlflow_runs"),
    **dict.fromkeys(("SweepSummary", "hydra_sweep", "summarize_sweep"), "sweep"),
    **dict.fromkeys(("check_tracking", "default_tracking_uri", "quiet_mlflow", "store_lock",
                     "tracking_client"), "store"),
    **dict.fromkeys(("DatasetRef", "dataset_ref", "git_tags", "provenance_tags", "repo_root"),
                    "provenance"),
    "LoggerConfig": "config",
}

__all__ = list(_EXPORTS)

__getattr__, __dir__ = lazy_exports(__name__, _EXPORTS)
