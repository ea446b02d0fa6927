"""MLflow tracking: one helper, :func:`log_run`, through which every run is logged.

Every run carries the provenance a result needs to be reproduced
(:mod:`learn.tracking.provenance`): git commit and dirty flag, the data set as an MLflow
dataset input with its manifest's digest, the resolved config (params and
``config.yaml``) and the fitted model where there is one (:meth:`TrackedRun.log_model`).
Runs that belong together are children of one parent run (``parent_run_id`` or
``group``). A study job is one run holding every split (:func:`log_job`). Everything goes
through an explicit :class:`mlflow.MlflowClient`: nothing here changes MLflow's global
state; how a process opens the store: :mod:`learn.tracking.store`.
"""

from __future__ import annotations

import json
import logging
import os
from collections.abc import Iterator, Mapping, Sequence
from contextlib import contextmanager
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from learn.tracking.provenance import (
    DatasetRef,
    dataset_ref,
    model_requirements,
    provenance_tags,
    sklearn_only,
)
from learn.tracking.store import get_experiment_id, quiet_mlflow, tracking_client

log = logging.getLogger(__name__)

#: Tag that marks the parent run of a group (:func:`log_run`'s ``group``).
GROUP_PARENT_TAG = "group_parent"


def _flatten(obj: Any, prefix: str = "") -> Iterator[tuple[str, Any]]:
    if isinstance(obj, Mapping):
        for k, v in obj.items():
            yield from _flatten(v, f"{prefix}.{k}" if prefix else str(k))
    elif isinstance(obj, (list, tuple)) and any(isinstance(v, Mapping) for v in obj):
        for i, v in enumerate(obj):
            yield from _flatten(v, f"{prefix}.{i}")
    else:
        yield prefix, obj


def flatten_config(config: Mapping[str, Any]) -> dict[str, str]:
    """Flatten a nested config to ``{"model.estimator.max_depth": "7", ...}``.

    Parameters
    ----------
    config : mapping
        Plain nested dict (e.g. ``OmegaConf.to_container(cfg, resolve=True)``).

    Returns
    -------
    dict of str to str
        Values as strings, cut to MLflow's parameter length limit (6000 characters).
    """
    return {k: str(v)[:6000] for k, v in _flatten(config)}


class ConfusionFigure:
    """A confusion-matrix figure (matplotlib, no pyplot state), laid out once and redrawn
    for each job (:meth:`draw`).

    The axes are placed from the longest class name (no layout engine: a figure is drawn
    for every logged job, and the constrained layout's extra draws doubled its cost).
    Building the figure (axes, colour bar, ticks, a text per cell) costs a third of
    rendering it, and the jobs of a study share their classes: the figure is kept and only
    its colours, counts, title and width change from job to job; other labels build it anew.
    """

    def __init__(self) -> None:
        self._fig: Any = None
        self._labels: tuple[str, ...] = ()

    def draw(self, confusion: np.ndarray, labels: Sequence[str], title: str = ""):
        """The figure of one confusion matrix.

        Parameters
        ----------
        confusion : ndarray of int, shape (n_classes, n_classes)
            Rows: true class, columns: predicted class.
        labels : sequence of str, length n_classes
        title : str, optional

        Returns
        -------
        matplotlib.figure.Figure
            Colours: row-normalised rate; numbers: counts. The same figure each call, until
            the labels change: save it before the next call.
        """
        labels = tuple(str(s) for s in labels)
        if self._fig is None or labels != self._labels:
            self._build(labels)
        cm = np.asarray(confusion)
        rate = cm / np.maximum(cm.sum(axis=1, keepdims=True), 1)
        fig = self._fig
        self._image.set_data(rate)
        for (i, j), text in np.ndenumerate(self._cells):
            text.set_text(str(int(cm[i, j])))
            text.set_color("white" if rate[i, j] > 0.5 else "black")
        # the figure is as wide as the title (9 pt, about 0.075 in a character)
        left, bottom, side, h = self._inches
        w = max(left + side + 1.2, 0.075 * len(title) + 0.4)
        fig.set_size_inches(w, h)
        fig.axes[0].set_position((left / w, bottom / h, side / w, side / h))
        fig.axes[1].set_position(((left + side + 0.2) / w, bottom / h, 0.15 / w, side / h))
        self._title.set_text(title)
        return fig

    def _build(self, labels: tuple[str, ...]) -> None:
        """The figure's artists for ``labels``, at zero counts."""
        from matplotlib.figure import Figure

        n = len(labels)
        # inches: class names at 8 pt (about 0.07 in a character) and the axis label beside
        left = 0.07 * max(len(s) for s in labels) + 0.3
        bottom, side = 0.75 * left + 0.2, 0.6 * n
        h = bottom + side + 0.6
        self._inches = (left, bottom, side, h)
        fig = Figure(figsize=(left + side + 1.2, h))
        ax = fig.add_axes((0.0, 0.0, 1.0, 1.0))
        self._image = ax.imshow(np.zeros((n, n)), vmin=0.0, vmax=1.0, cmap="Blues")
        self._cells = np.array([[ax.text(j, i, "", ha="center", va="center", fontsize=8)
                                 for j in range(n)] for i in range(n)], dtype=object)
        ax.set_xticks(range(n), labels, rotation=45, ha="right", fontsize=8)
        ax.set_yticks(range(n), labels, fontsize=8)
        ax.set_xlabel("predicted class", fontsize=9)
        ax.set_ylabel("true class", fontsize=9)
        self._title = fig.suptitle("", fontsize=9, y=1.0 - 0.15 / h, va="center")
        cax = fig.add_axes((0.0, 0.0, 1.0, 1.0))
        fig.colorbar(self._image, cax=cax, label="fraction of true class")
        self._fig, self._labels = fig, labels


def confusion_figure(confusion: np.ndarray, labels: Sequence[str], title: str = ""):
    """Confusion-matrix figure (matplotlib, no pyplot state) on a new figure: the
    parameters and the figure of :meth:`ConfusionFigure.draw`, whose figure this one does
    not share."""
    return ConfusionFigure().draw(confusion, labels, title)


@dataclass
class TrackedRun:
    """An open MLflow run, yielded by :func:`log_run`; every method logs to it.

    Params and metrics are buffered and sent in as few ``log_batch`` calls as MLflow
    allows (each call is a database transaction, ~15 ms on a local SQLite store) when the
    run ends, or on :meth:`flush`; artifacts, data sets and models are sent at once.

    Attributes
    ----------
    client : mlflow.MlflowClient
    run_id, experiment_id : str
    """

    client: Any
    run_id: str
    experiment_id: str
    _params: list = field(default_factory=list, repr=False)
    _metrics: list = field(default_factory=list, repr=False)

    def log_params(self, params: Mapping[str, Any]) -> None:
        """Log params, nested mappings flattened with dots (:func:`flatten_config`)."""
        from mlflow.entities import Param

        self._params += [Param(k, v) for k, v in sorted(flatten_config(params).items())]

    def log_metrics(self, metrics: Mapping[str, float], step: int = 0) -> None:
        """Log metrics ``{name: value}``, all at ``step`` (an iteration, never a seed)."""
        import time

        from mlflow.entities import Metric

        ts = int(time.time() * 1000)
        self._metrics += [Metric(k, float(v), ts, int(step)) for k, v in metrics.items()]

    def flush(self) -> None:
        """Send the buffered params and metrics (MLflow: per batch <= 100 params, <= 1000
        entries in all)."""
        while self._params or self._metrics:
            params, self._params = self._params[:100], self._params[100:]
            n = 1000 - len(params)
            metrics, self._metrics = self._metrics[:n], self._metrics[n:]
            self.client.log_batch(self.run_id, metrics=metrics, params=params)

    def log_learning_curve(self, model) -> int:
        """Log a fitted net's learning curve: each epoch's ``epoch/<key>`` (``loss``,
        ``val_loss``, ``val_accuracy``) at step = the epoch, from the ``history_`` of the
        model or of a pipeline's last step (:mod:`learn.learners.nets`).

        Parameters
        ----------
        model : fitted estimator
            Anything; one without a ``history_`` logs nothing.

        Returns
        -------
        int
            The epochs logged.
        """
        est = model.steps[-1][1] if hasattr(model, "steps") else model
        history = getattr(est, "history_", None) or []
        for rec in history:
            self.log_metrics({f"epoch/{k}": v for k, v in rec.items() if k != "epoch"},
                             step=int(rec["epoch"]))
        return len(history)

    def log_figure(self, figure, name: str) -> None:
        """Store a matplotlib figure as the artifact ``name`` (e.g. ``"confusion.png"``)."""
        self.client.log_figure(self.run_id, figure, name)

    def log_artifact(self, path: str | os.PathLike, artifact_path: str | None = None) -> None:
        """Store a file, or a folder's files under ``artifact_path``."""
        if Path(path).is_dir():
            self.client.log_artifacts(self.run_id, str(path), artifact_path)
        else:
            self.client.log_artifact(self.run_id, str(path), artifact_path)

    def log_dataset(self, dataset: DatasetRef | str | os.PathLike,
                    context: str = "training") -> DatasetRef:
        """Log a data set as an MLflow dataset input (``mlflow.data`` MetaDataset).

        The input carries the name, the source (``local``, the absolute path), the digest
        (:attr:`DatasetRef.digest`) and a profile (JSON: the full SHA-256 and what it is
        of, windows, shards, config hash); its tag ``mlflow.data.context`` is ``context``.
        Runs can then be searched by data set (``datasets.digest = '...'``).

        Returns
        -------
        DatasetRef

        Raises
        ------
        ValueError
            See :func:`dataset_ref`.
        """
        from mlflow.data.meta_dataset import MetaDataset
        from mlflow.data.sources import LocalArtifactDatasetSource
        from mlflow.entities import Dataset, DatasetInput, InputTag

        ref = dataset if isinstance(dataset, DatasetRef) else dataset_ref(dataset)
        meta = MetaDataset(LocalArtifactDatasetSource(ref.path), name=ref.name,
                           digest=ref.digest).to_dict()
        profile = {"sha256": ref.sha256, "digest_of": ref.digest_of, "n_samples": ref.n_samples,
                   "n_shards": ref.n_shards, "config_hash": ref.config_hash}
        entity = Dataset(name=meta["name"], digest=meta["digest"],
                         source_type=meta["source_type"], source=meta["source"],
                         schema=meta.get("schema"), profile=json.dumps(profile))
        self.client.log_inputs(self.run_id, datasets=[
            DatasetInput(entity, tags=[InputTag("mlflow.data.context", context)])])
        return ref

    def log_model(self, model, name: str = "model", *, X_sample: np.ndarray | None = None,
                  tags: Mapping[str, Any] | None = None) -> str | None:
        """Log a fitted scikit-learn-compatible model (``mlflow.sklearn``) as this run's output.

        An MLflow 3 logged model (``models:/<model_id>``, linked to the run) whose
        artifacts lie in the experiment's artifact folder; load it with
        ``mlflow.sklearn.load_model(uri)``, ``uri`` being
        ``client.get_logged_model(model_id).artifact_location`` (or ``models:/<model_id>``
        with the tracking URI set). Stored with cloudpickle (tag ``serialization_format``),
        which also holds the torch nets (:mod:`learn.learners.nets`) and MiniRocket
        (:mod:`learn.learners.rocket`) inside their pipelines: for the study's random forest
        (4860 training windows) 0.6 MiB written in 3 ms, where skops (MLflow's default)
        writes 2.8 MiB in about 0.9 s (dump, MLflow's check load, and the scan for
        scikit-learn types it does not trust by default). MLflow 3.17 gates loading either
        format behind ``MLFLOW_ALLOW_PICKLE_DESERIALIZATION`` (default on), so skops
        would add no safety there: load only models you logged. The pip requirements
        are given (:func:`learn.tracking.provenance.model_requirements`), not inferred (MLflow
        would load the model in a subprocess for that).

        Parameters
        ----------
        model : fitted estimator
            Anything with ``predict`` that pickles (a ``Pipeline`` of
            :func:`learn.learners.models.make_pipeline`).
        name : str, default "model"
        X_sample : ndarray, shape (n, n_features), optional
            A few input rows: the model's signature (input and output types) is inferred
            from them.
        tags : mapping, optional
            Tags of the logged model (e.g. the split it was fitted on).

        Returns
        -------
        str or None
            The logged model's id; None (with a warning naming the error) if the model
            cannot be stored - the run itself is not failed for that.
        """
        import tempfile

        import mlflow.sklearn
        from mlflow.entities import LoggedModelOutput
        from mlflow.models import Model, infer_signature

        quiet_mlflow()
        fmt = "cloudpickle"
        signature = None if X_sample is None else infer_signature(X_sample,
                                                                  model.predict(X_sample))
        lm = self.client.create_logged_model(
            self.experiment_id, name=name, source_run_id=self.run_id,
            tags={"serialization_format": fmt, **{k: str(v) for k, v in (tags or {}).items()}},
            model_type=type(model).__name__)
        try:
            with tempfile.TemporaryDirectory() as tmp:
                path = str(Path(tmp) / "model")
                mlflow.sklearn.save_model(
                    model, path, serialization_format=fmt, signature=signature,
                    pip_requirements=model_requirements(fmt, not sklearn_only(model)),
                    mlflow_model=Model(artifact_path=lm.artifact_location, run_id=self.run_id,
                                       model_uuid=lm.model_id, model_id=lm.model_id))
                self.client.log_model_artifacts(lm.model_id, path)
        except Exception as e:  # noqa: BLE001 - the run's results stand without the model
            self.client.finalize_logged_model(lm.model_id, "FAILED")
            log.warning("run %s: model %s (%s) not logged: %s", self.run_id, name,
                        type(model).__name__, str(e).splitlines()[0] if str(e) else e)
            return None
        self.client.log_outputs(self.run_id, [LoggedModelOutput(lm.model_id, step=0)])
        self.client.finalize_logged_model(lm.model_id, "READY")
        return lm.model_id


_GROUP_PARENTS: dict[tuple[str, str, str], str] = {}
_FAILED_GROUPS: set[str] = set()
_EXPERIMENTS: dict[tuple[str, str], str] = {}


def group_display_name(group: str) -> str:
    """A group parent's run name: a sweep's by its folder's last two parts (Hydra's date
    and time, ``"sweep 2026-11-29/12-00-00"``), the group itself otherwise; the tag
    :data:`GROUP_PARENT_TAG` keeps the whole group."""
    if group.startswith("sweep "):
        return "sweep " + "/".join(Path(group[6:]).parts[-2:])
    return group


def group_parent(client, experiment_id: str, group: str,
                 datasets: Sequence[DatasetRef] = ()) -> str:
    """Run id of the parent run of ``group`` in an experiment, created on first use.

    The parent is the run tagged :data:`GROUP_PARENT_TAG` = ``group`` (run name
    :func:`group_display_name`), found by a search, else created with the git tags and
    the data sets.
    Looked up once per process (cached). Parallel processes starting a group at the same
    moment may each create a parent; their children still share the tag ``group``.

    Parameters
    ----------
    client : mlflow.MlflowClient
    experiment_id : str
    group : str
        E.g. ``"sweep /abs/multirun/2026-01-01/12-00-00"``; quotes are replaced by ``_``.
    datasets : sequence of DatasetRef, optional
        Logged as the parent's inputs when it is created.

    Returns
    -------
    str
    """
    group = group.replace("'", "_").replace('"', "_")
    key = (client.tracking_uri, experiment_id, group)
    if key in _GROUP_PARENTS:
        return _GROUP_PARENTS[key]
    found = client.search_runs([experiment_id],
                               filter_string=f"tags.{GROUP_PARENT_TAG} = '{group}'",
                               max_results=1)
    if found:
        pid = found[0].info.run_id
    else:
        run = client.create_run(experiment_id, run_name=group_display_name(group),
                                tags={**provenance_tags(), GROUP_PARENT_TAG: group})
        pid = run.info.run_id
        parent = TrackedRun(client, pid, experiment_id)
        for d in datasets:
            parent.log_dataset(d)
    _GROUP_PARENTS[key] = pid
    return pid


def _create_run(client, experiment: str, run_name: str, tags: Mapping[str, Any] | None,
                parent_run_id: str | None, group: str | None,
                refs: list[DatasetRef]) -> tuple[TrackedRun, str | None]:
    """Create the run of :func:`log_run` with its tags and parent; return it and the
    group's parent run id (None outside a group)."""
    key = (client.tracking_uri, experiment)
    if key not in _EXPERIMENTS:  # looked up once per process
        _EXPERIMENTS[key] = get_experiment_id(client, experiment)
    exp_id = _EXPERIMENTS[key]
    all_tags = {**provenance_tags(), **{k: str(v) for k, v in (tags or {}).items()}}
    group_pid = None
    if group is not None:
        group = group.replace("'", "_").replace('"', "_")
        all_tags["group"] = group
        if parent_run_id is None:
            parent_run_id = group_pid = group_parent(client, exp_id, group, refs)
    if parent_run_id is not None:
        all_tags["mlflow.parentRunId"] = parent_run_id
    run = client.create_run(exp_id, run_name=run_name, tags=all_tags)
    return TrackedRun(client, run.info.run_id, exp_id), group_pid


@contextmanager
def log_run(
    experiment: str,
    run_name: str,
    *,
    tracking_uri: str | None = None,
    params: Mapping[str, Any] | None = None,
    config: Mapping[str, Any] | None = None,
    dataset: str | os.PathLike | DatasetRef | Sequence[str | os.PathLike | DatasetRef]
    | None = None,
    tags: Mapping[str, Any] | None = None,
    parent_run_id: str | None = None,
    group: str | None = None,
) -> Iterator[TrackedRun]:
    """Open one MLflow run with its provenance; the one way runs are logged here.

    On entry the run is created with the provenance tags (git state and library versions,
    :func:`provenance_tags`), ``tags``, the parent
    (``parent_run_id``, or the parent of ``group``, :func:`group_parent`), the data sets
    as dataset inputs (:meth:`TrackedRun.log_dataset`), ``params`` flattened and
    ``config`` as ``config.yaml``; the body logs metrics, figures, files and the model
    through the yielded :class:`TrackedRun`. On exit the run is ``FINISHED``, or
    ``FAILED`` if the body raised (the exception propagates); a group's parent is
    terminated with it (its end time is that of its last child).

    Parameters
    ----------
    experiment : str
        MLflow experiment name (created if absent, :func:`learn.tracking.store.get_experiment_id`).
    run_name : str
    tracking_uri : str, optional
        Default :func:`learn.tracking.store.default_tracking_uri`.
    params : mapping, optional
        Params; nested mappings are flattened with dots (:func:`flatten_config`).
    config : mapping, optional
        Resolved config, stored as the artifact ``config.yaml``.
    dataset : path-like or DatasetRef, or a sequence of them, optional
        Data-set folders or files the run read (:func:`dataset_ref`).
    tags : mapping, optional
        Run tags.
    parent_run_id : str, optional
        Make the run a child of this run (tag ``mlflow.parentRunId``).
    group : str, optional
        Make the run a child of the group's parent run (created on first use) and tag it
        ``group``; e.g. :func:`learn.tracking.sweep.hydra_sweep` for the jobs of a sweep.

    Yields
    ------
    TrackedRun

    Raises
    ------
    ValueError
        A data set that :func:`dataset_ref` cannot read, before the run is created; a
        store another process is creating for too long
        (:func:`learn.tracking.store.tracking_client`).

    Examples
    --------
    >>> with log_run("demo", "rf", params=cfg, config=cfg, dataset="data/paper") as run:
    ...     run.log_metrics({"accuracy": 0.98})
    ...     run.log_model(pipeline, X_sample=X[:5])
    """
    quiet_mlflow()
    items = [] if dataset is None else (
        [dataset] if isinstance(dataset, (str, os.PathLike, DatasetRef)) else list(dataset))
    refs = [d if isinstance(d, DatasetRef) else dataset_ref(d) for d in items]
    client = tracking_client(tracking_uri)
    tracked, group_pid = _create_run(client, experiment, run_name, tags, parent_run_id,
                                     group, refs)
    status = "FAILED"
    try:
        for ref in refs:
            tracked.log_dataset(ref)
        if params is not None:
            tracked.log_params(params)
        if config is not None:
            client.log_dict(tracked.run_id, dict(config), "config.yaml")
        yield tracked
        status = "FINISHED"
    finally:
        try:
            tracked.flush()
        finally:
            client.set_terminated(tracked.run_id, status=status)
            if group_pid is not None:  # a group with a failed child stays FAILED
                if status == "FAILED":
                    _FAILED_GROUPS.add(group_pid)
                client.set_terminated(
                    group_pid, status="FAILED" if group_pid in _FAILED_GROUPS else status)


def log_job(
    result,
    *,
    experiment: str,
    run_name: str,
    params: Mapping[str, Any],
    config: Mapping[str, Any] | None = None,
    tracking_uri: str | None = None,
    tags: Mapping[str, str] | None = None,
    confusion_plot: bool = True,
    figure: ConfusionFigure | None = None,
    dataset: str | os.PathLike | DatasetRef | None = None,
    model=None,
    model_tags: Mapping[str, Any] | None = None,
    X_sample: np.ndarray | None = None,
    parent_run_id: str | None = None,
    group: str | None = None,
) -> str:
    """Log one job (all splits of one model under one protocol) as one MLflow run, through
    :func:`log_run`.

    Parameters
    ----------
    result : learn.studies.protocols.ProtocolResult
        Per-split accuracies and the summed confusion matrix.
    experiment, run_name, params, config, tracking_uri, tags, parent_run_id, group
        As :func:`log_run` (``run_name`` e.g. ``"selection3-rf"``).
    confusion_plot : bool, default True
        Store ``confusion_matrix.png``.
    figure : ConfusionFigure, optional
        Where the confusion matrix is drawn; a caller logging many jobs passes one for all
        (laid out once). Default a new one.
    dataset : path-like or DatasetRef, optional
        The data set the job read (a dataset input of the run).
    model : fitted estimator, optional
        Logged with :meth:`TrackedRun.log_model` (e.g. the last split's model).
    model_tags : mapping, optional
        Tags of the logged model (e.g. ``{"split": "gear3"}``).
    X_sample : ndarray, shape (n, n_features), optional
        Rows for the model's signature.

    Returns
    -------
    str
        The MLflow run id.
    """
    with log_run(experiment, run_name, tracking_uri=tracking_uri, params=params,
                 config=config, dataset=dataset,
                 tags={**dict(tags or {}), "splits": ";".join(s.label for s in result.splits)},
                 parent_run_id=parent_run_id, group=group) as run:
        metrics: dict[str, float] = {}
        for i, s in enumerate(result.splits):
            metrics[f"{s.name}/train_accuracy"] = float(result.train_accuracy[i])
            metrics[f"{s.name}/test_accuracy"] = float(result.test_accuracy[i])
        metrics["mean_train_accuracy"] = result.mean_train_accuracy
        metrics["mean_test_accuracy"] = result.mean_test_accuracy
        if len(result.fit_time_s):
            metrics["fit_time_s"] = float(np.sum(result.fit_time_s))
        run.log_metrics(metrics)
        if confusion_plot:
            run.log_figure((figure or ConfusionFigure()).draw(
                result.confusion, result.labels,
                f"{run_name}: mean test accuracy {100 * result.mean_test_accuracy:.1f} %"),
                "confusion_matrix.png")
        if model is not None:
            run.log_learning_curve(model)
            run.log_model(model, X_sample=X_sample, tags=model_tags)
    log.info("MLflow run %s (%s/%s)", run.run_id, experiment, run_name)
    return run.run_id
