"""One job of the paper's study (:func:`run_study_job`, ``swgsim-train``'s task ``study``:
one protocol, one feature selection or signal input, one model, all splits)."""

from __future__ import annotations

import logging

import numpy as np

from learn.inputs.features import extract_features
from learn.studies.protocols import ProtocolResult, class_labels, evaluate, window_groups
from learn.tasks.config import typed_app
from swgsim.base.typed import plain

log = logging.getLogger(__name__)


def run_study_job(cfg) -> dict:
    """One job: a model under a protocol on one feature selection or signal input, all
    splits.

    Reads ``data.path``, ``features`` (:class:`learn.inputs.features.FeatureSettings`),
    ``input`` (None: the features; else one of :data:`learn.inputs.signals.INPUTS`, e.g.
    ``raw`` or ``diff`` for the torch nets: ``swgsim-train model=mlp_torch input=raw
    protocol=ood_disturbed``), ``model`` (a ``_target_`` config, instantiated with Hydra;
    its ``n_aux`` set to the input's scalar channels), ``protocol``
    (:class:`learn.studies.protocols.ProtocolConfig`), ``logger``
    (:class:`learn.tracking.config.LoggerConfig`; None: no tracking) and ``n_jobs``.

    Parameters
    ----------
    cfg : swgcli.schema.TrainApp or omegaconf.DictConfig
        The typed app config (:func:`learn.tasks.config.typed_app`).

    Returns
    -------
    dict
        ``protocol``, ``selection`` (the feature selection, or the input with ``input``
        set), ``input`` (None for features), ``model`` (the name of the pipeline's
        classifier step), ``splits`` (labels), ``train_accuracy`` and ``test_accuracy``
        (lists, per split), ``mean_train_accuracy``, ``mean_test_accuracy``,
        ``n_samples``, ``run_id`` (None without logger).

    Raises
    ------
    ValueError
        An ``input`` not among :data:`learn.inputs.signals.INPUTS`, or a signal input for
        a model that reads no signals (before the data set is read).
    """
    from swgsim.datasets.schema import load

    app = typed_app(cfg)
    settings, protocol = app.features, app.protocol
    estimator = _estimator(app)  # checks the input against the model, before any work
    ds = load(app.stored.path)
    if app.input is None:
        feats = extract_features(ds, settings.selection, **settings.kwargs())
        X, meta, name = feats.X, feats.meta, settings.name
    else:
        from learn.inputs.signals import build_input

        inp = build_input(ds, app.input, disturbed=protocol.disturbed,
                          feature_kwargs=settings.kwargs())
        X, meta, name = inp.X, inp.meta, app.input
        estimator = _estimator(app, inp.n_aux)
    y = meta["fault"].to_numpy()
    splits = protocol.splits(meta)
    model = _step_name(estimator)
    result = evaluate(estimator, X, y, splits, labels=class_labels(y), n_jobs=app.n_jobs,
                      groups=window_groups(meta))
    log.info("%s / %s / %s: test accuracy %s, mean %.4f", protocol.name, name,
             model, np.round(result.test_accuracy, 4), result.mean_test_accuracy)
    run_id = None if app.logger is None else _log(app, result, protocol.name, estimator,
                                                  X, y, splits[-1], model)
    return {
        "task": "study",
        "protocol": protocol.name,
        "selection": name,
        "input": app.input,
        "model": model,
        "splits": [s.label for s in splits],
        "train_accuracy": result.train_accuracy.tolist(),
        "test_accuracy": result.test_accuracy.tolist(),
        "mean_train_accuracy": result.mean_train_accuracy,
        "mean_test_accuracy": result.mean_test_accuracy,
        "n_samples": int(sum(len(s.test) for s in splits)),
        "run_id": run_id,
    }


def _estimator(app, n_aux: int = 0):
    """The job's model; with a signal input, its ``n_aux`` (the input's scalar channels)
    and seed set as in the transfer comparison (:func:`learn.studies.runs.make_estimator`).

    Raises
    ------
    ValueError
        ``input`` not among :data:`learn.inputs.signals.INPUTS`, a signal input
        (:data:`learn.inputs.signals.SIGNAL_INPUTS`) for a model that reads no (n, C, T)
        signals, or a model setting its ``check_params`` refuses.
    """
    from hydra.utils import instantiate

    from learn.inputs.signals import INPUTS, SIGNAL_INPUTS
    from learn.studies.runs import check_estimator, final_step, make_estimator

    if app.input is None:
        return check_estimator(instantiate(app.model, _convert_="all"), "model.estimator")
    if app.input not in INPUTS:
        raise ValueError(f"input must be null (the features) or one of {INPUTS}, got "
                         f"{app.input!r}")
    est = make_estimator(app.model, app.seed, n_aux)
    if (app.input in SIGNAL_INPUTS
            and not final_step(est).__sklearn_tags__().input_tags.three_d_array):
        raise ValueError(f"input={app.input}: (n, C, T) signals need a model that reads "
                         f"them (mlp_torch, cnn, minirocket), not model "
                         f"{_step_name(est)}")
    return check_estimator(est, "model.estimator")


def _step_name(estimator) -> str:
    """The name of a pipeline's classifier step (the model's config name,
    :func:`learn.learners.models.make_pipeline`), else the estimator's class."""
    from sklearn.pipeline import Pipeline

    if isinstance(estimator, Pipeline):
        return str(estimator.steps[-1][0])
    return type(estimator).__name__


def _log(app, result: ProtocolResult, protocol: str, estimator, X, y, last,
         model_name: str) -> str:
    """Log the job; with a signal input, a run name left at its default
    (``<features.name>-<model>``) becomes ``<input>-<model>``."""
    from learn.learners.devices import net_record
    from learn.tracking import hydra_sweep, log_job

    lcfg = app.logger
    resolved = plain(app)
    run_name = lcfg.run_name
    if app.input is not None and run_name == f"{app.features.name}-{model_name}":
        run_name = f"{app.input}-{model_name}"
    model = _last_split_model(estimator, X, y, last) if lcfg.log_models else None
    return log_job(result, experiment=lcfg.experiment, run_name=run_name,
                   tracking_uri=lcfg.tracking_uri, confusion_plot=lcfg.confusion_plot,
                   params={**resolved, **net_record(estimator)}, config=resolved,
                   tags={"task": "study", "protocol": protocol,
                         "input": app.input or app.features.name},
                   dataset=str(app.stored.path), model=model, model_tags={"split": last.label},
                   X_sample=X[last.test[:5]], group=hydra_sweep())


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
