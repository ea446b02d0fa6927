"""``swgsim-train``'s task dispatch (:func:`run_train`, :data:`TASKS`) and one job of the
paper's study (:func:`run_study_job`: one protocol, one feature selection, one model, all
splits)."""

from __future__ import annotations

import logging

import numpy as np

from learn.inputs.features import extract_features
from learn.studies.protocols import ProtocolResult, class_labels, evaluate
from learn.tasks.config import plain, typed_app

log = logging.getLogger(__name__)

#: Task name -> function ``f(cfg) -> dict`` (dotted path, imported on use).
TASKS: dict[str, str] = {
    "study": "learn.tasks.train.run_study_job",
    "paper_study": "learn.tasks.paper.run_paper_study_task",
    "transfer": "learn.tasks.transfer.run_transfer",
    "monitor": "learn.tasks.monitor_evaluation.run_monitor_evaluation",
}


def run_train(cfg) -> dict:
    """Run the task named by ``cfg.task``.

    Parameters
    ----------
    cfg : omegaconf.DictConfig or swgcli.schema.TrainApp
        Composed ``conf/train.yaml`` (:class:`swgcli.schema.TrainApp`); turned into the
        typed object here, once (:func:`learn.tasks.config.typed_app`), and handed on.

    Returns
    -------
    dict
        Whatever the task returns (metrics, run ids, paths).

    Raises
    ------
    ValueError
        For a task not in :data:`TASKS`.
    """
    from hydra.utils import get_method

    app = typed_app(cfg)
    if app.task not in TASKS:
        raise ValueError(f"task must be one of {sorted(TASKS)}, got {app.task!r}")
    if app.logger is not None:
        from learn.tracking.store import check_tracking

        check_tracking(app.logger.tracking_uri, "logger.tracking_uri")
    log.info("task %s -> %s", app.task, TASKS[app.task])
    return get_method(TASKS[app.task])(app)


def run_study_job(cfg) -> dict:
    """One job: a model under a protocol on one feature selection, all splits.

    Reads ``data.path``, ``features`` (:class:`learn.inputs.features.FeatureSettings`),
    ``model`` (a ``_target_`` config, instantiated with Hydra), ``protocol``
    (:class:`learn.studies.protocols.ProtocolConfig`), ``logger``
    (:class:`learn.tracking.config.LoggerConfig`; None: no tracking) and ``n_jobs``.

    Parameters
    ----------
    cfg : swgcli.schema.TrainApp or omegaconf.DictConfig
        The typed app config (:func:`learn.tasks.config.typed_app`).

    Returns
    -------
    dict
        ``protocol``, ``selection``, ``model`` (the name of the pipeline's classifier
        step), ``splits`` (labels), ``train_accuracy`` and ``test_accuracy`` (lists, per
        split), ``mean_train_accuracy``, ``mean_test_accuracy``, ``n_samples``, ``run_id``
        (None without logger).
    """
    from hydra.utils import instantiate

    from swgsim.datasets.schema import load

    app = typed_app(cfg)
    ds = load(app.stored.path)
    settings, protocol = app.features, app.protocol
    feats = extract_features(ds, settings.selection, **settings.kwargs())
    y = feats.meta["fault"].to_numpy()
    splits = protocol.splits(feats.meta)
    estimator = instantiate(app.model, _convert_="all")
    model = _step_name(estimator)
    result = evaluate(estimator, feats.X, y, splits, labels=class_labels(y), n_jobs=app.n_jobs)
    log.info("%s / %s / %s: test accuracy %s, mean %.4f", protocol.name, settings.name,
             model, np.round(result.test_accuracy, 4), result.mean_test_accuracy)
    run_id = None if app.logger is None else _log(app, result, protocol.name, estimator,
                                                  feats, splits[-1])
    return {
        "task": "study",
        "protocol": protocol.name,
        "selection": settings.name,
        "model": model,
        "splits": [s.label for s in splits],
        "train_accuracy": result.train_accuracy.tolist(),
        "test_accuracy": result.test_accuracy.tolist(),
        "mean_train_accuracy": result.mean_train_accuracy,
        "mean_test_accuracy": result.mean_test_accuracy,
        "n_samples": int(sum(len(s.test) for s in splits)),
        "run_id": run_id,
    }


def _step_name(estimator) -> str:
    """The name of a pipeline's classifier step (the model's config name,
    :func:`learn.learners.models.make_pipeline`), else the estimator's class."""
    from sklearn.pipeline import Pipeline

    if isinstance(estimator, Pipeline):
        return str(estimator.steps[-1][0])
    return type(estimator).__name__


def _log(app, result: ProtocolResult, protocol: str, estimator, feats, last) -> str:
    from learn.tracking import hydra_sweep, log_job

    lcfg = app.logger
    resolved = plain(app)
    model = (_last_split_model(estimator, feats.X, feats.meta["fault"].to_numpy(), last)
             if lcfg.log_models else None)
    return log_job(result, experiment=lcfg.experiment, run_name=lcfg.run_name,
                   tracking_uri=lcfg.tracking_uri, confusion_plot=lcfg.confusion_plot,
                   params=resolved, config=resolved, tags={"task": "study", "protocol": protocol},
                   dataset=str(app.stored.path), model=model, model_tags={"split": last.label},
                   X_sample=feats.X[last.test[:5]], group=hydra_sweep())


def _last_split_model(estimator, X: np.ndarray, y: np.ndarray, split):
    """A clone of ``estimator`` fitted on the last split's training rows (to be logged).

    The protocol's fits run in worker processes and return scores only; this refit (one
    more fit per job) is what ``logger.log_models`` costs. Its warnings were already
    reported by the protocol's identical fit.
    """
    import warnings

    from sklearn.base import clone

    est = clone(estimator)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        est.fit(X[split.train], np.asarray(y).astype(str)[split.train])
    return est
