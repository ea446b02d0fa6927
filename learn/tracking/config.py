"""What a task logs to MLflow: :class:`LoggerConfig`, the ``logger`` group of
``swgsim-train`` (registered by :mod:`swgcli.schema`)."""

from __future__ import annotations

from dataclasses import dataclass


@dataclass
class LoggerConfig:
    """MLflow tracking of ``swgsim-train`` (``~logger`` switches it off).

    Attributes
    ----------
    tracking_uri : str or None
        None: ``$MLFLOW_TRACKING_URI``, else ``sqlite:///<repo>/mlflow.db``
        (:func:`learn.tracking.store.default_tracking_uri`).
    experiment, run_name : str
        MLflow experiment and run name; interpolations of the app's config: a job of
        ``swgsim-train`` goes to ``paper/<data set>/<protocol>``, as the main job's jobs
        do, named ``<features>-<model>`` (the naming scheme: docs/apps.md, "MLflow
        experiments and runs").
    confusion_plot : bool
        Store the confusion matrix as a figure.
    log_models : bool
        Log each job's model, fitted on its last split, with mlflow.sklearn. The study
        (task paper_study) keeps the model of its own last-split fit (no refit); a single
        job (task study) refits it once. Measured per job (paper data set, selection 1,
        4860 training windows, 2 cores): storing 0.03-0.15 s and 0.6 MiB (RF, SVM, KNN;
        MLP, NB < 0.1 MiB); a single job's refit RF 0.7-0.9 s, SVM 1.4 s, MLP 4.0 s.
    """

    tracking_uri: str | None = None
    experiment: str = "paper/${oc.select:stored.name,data}/${oc.select:protocol.name,run}"
    run_name: str = "${oc.select:features.name,run}-${oc.select:model.name,run}"
    confusion_plot: bool = True
    log_models: bool = True
