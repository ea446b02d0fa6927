"""``swgsim-train``'s task dispatch (:func:`run_train`, :data:`TASKS`) and one job of the
paper's study (:func:`run_study_job`: one protocol, one feature selection, one model, all
splits)."""

from __future__ import annotations

import logging

import numpy as np

from learn.inputs.features import FeatureSettings, extract_features
from learn.studies.protocols import ProtocolConfig, ProtocolResult, class_labels, evaluate
from learn.tasks.config import typed

log = logging.getLogger(__name__)

#: Task name -> function ``f(cfg) -> dict`` (dotted path, imported on use).
TASKS: dict[str, str] = {
    "study": "learn.tasks.train.run_study_job",
    "paper_study": "learn.tasks.paper.run_paper_study_task",
    "transfer": "learn.tasks.transfer.run_transfer",
}


def run_train(cfg) -> dict:
    """Run the task named by ``cfg.task``.

    Parameters
    ----------
    cfg : omegaconf.DictConfig
        Composed ``conf/train.yaml`` (:class:`swgcli.schema.TrainApp`).

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

    if cfg.task not in TASKS:
        raise ValueError(f"task must be one of {sorted(TASKS)}, got {cfg.task!r}")
    if cfg.logger is not None:
        from learn.tracking import check_tracking

        check_tracking(cfg.logger.tracking_uri, "logger.tracking_uri")
    log.info("task %s -> %s", cfg.task, TASKS[cfg.task])
    return get_method(TASKS[cfg.task])(cfg)


def run_study_job(cfg) -> dict:
    """One job: a model under a protocol on one feature selection, all splits.

    Reads ``cfg.data.path``, ``cfg.features`` (:class:`learn.inputs.features.FeatureSettings`),
    ``cfg.model`` (instantiated with Hydra), ``cfg.protocol``
    (:class:`learn.studies.protocols.ProtocolConfig`), ``cfg.logger`` (None: no tracking)
    and ``cfg.n_jobs``.

    Parameters
    ----------
    cfg : omegaconf.DictConfig

    Returns
    -------
    dict
        ``protocol``, ``selection``, ``model``, ``splits`` (labels), ``train_accuracy``
        and ``test_accuracy`` (lists, per split), ``mean_train_accuracy``,
        ``mean_test_accuracy``, ``n_samples``, ``run_id`` (None without logger).
    """
    from hydra.utils import instantiate

    from swgsim.data import load

    ds = load(cfg.data.path)
    settings = typed(cfg.features, FeatureSettings)
    protocol = typed(cfg.protocol, ProtocolConfig)
    feats = extract_features(ds, settings.selection, **settings.kwargs())
    y = feats.meta["fault"].to_numpy()
    splits = protocol.splits(feats.meta)
    estimator = instantiate(cfg.model, _convert_="all")
    result = evaluate(estimator, feats.X, y, splits, labels=class_labels(y), n_jobs=cfg.n_jobs)
    log.info("%s / %s / %s: test accuracy %s, mean %.4f", protocol.name, settings.name,
             cfg.model.name, np.round(result.test_accuracy, 4), result.mean_test_accuracy)
    run_id = None if cfg.logger is None else _log(cfg, result, protocol.name, estimator,
                                                  feats, splits[-1])
    return {
        "task": "study",
        "protocol": protocol.name,
        "selection": settings.name,
        "model": cfg.model.name,
        "splits": [s.label for s in splits],
        "train_accuracy": result.train_accuracy.tolist(),
        "test_accuracy": result.test_accuracy.tolist(),
        "mean_train_accuracy": result.mean_train_accuracy,
        "mean_test_accuracy": result.mean_test_accuracy,
        "n_samples": int(sum(len(s.test) for s in splits)),
        "run_id": run_id,
    }


def _log(cfg, result: ProtocolResult, protocol: str, estimator, feats, last) -> str:
    from omegaconf import OmegaConf

    from learn.tracking import hydra_sweep, log_job

    lcfg = cfg.logger
    resolved = OmegaConf.to_container(cfg, resolve=True)
    model = (_last_split_model(estimator, feats.X, feats.meta["fault"].to_numpy(), last)
             if lcfg.log_models else None)
    return log_job(result, experiment=str(lcfg.experiment), run_name=str(lcfg.run_name),
                   tracking_uri=lcfg.tracking_uri, confusion_plot=bool(lcfg.confusion_plot),
                   params=resolved, config=resolved, tags={"task": "study", "protocol": protocol},
                   dataset=str(cfg.data.path), model=model, model_tags={"split": last.label},
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
