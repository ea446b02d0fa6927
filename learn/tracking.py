"""MLflow tracking of study jobs.

One MLflow run per job, i.e. per (protocol, feature selection, model), holding every
split: params (the flattened config), metrics ``<split>/train_accuracy``,
``<split>/test_accuracy`` and their means, the resolved config as ``config.yaml`` and the
test confusion matrix summed over splits as ``confusion_matrix.png``. One MLflow
experiment per protocol (or per study). Everything goes through an explicit
:class:`mlflow.MlflowClient`, so nothing here changes MLflow's global state.

The default tracking URI is ``sqlite:///<repo root>/mlflow.db`` (MLflow 3's database
store; its file store is deprecated): ``MLFLOW_TRACKING_URI`` wins if set, as in MLflow
itself. Artifacts of a ``sqlite:///`` store go to ``mlruns/<experiment>/`` beside the
database file (rather than MLflow's default ``./mlruns`` in the working directory); a
server URI keeps the server's artifact store. Browse with ``mlflow ui --backend-store-uri
sqlite:///mlflow.db``.
"""

from __future__ import annotations

import logging
import os
import re
from collections.abc import Iterator, Mapping, Sequence
from pathlib import Path
from typing import Any

import numpy as np

log = logging.getLogger(__name__)


def repo_root() -> Path:
    """Root of the source checkout.

    Returns
    -------
    Path
        The parent of the ``learn`` package if it holds ``pyproject.toml`` (a source
        checkout or editable install), otherwise the current working directory.
    """
    here = Path(__file__).resolve().parents[1]
    return here if (here / "pyproject.toml").is_file() else Path.cwd()


def default_tracking_uri() -> str:
    """``MLFLOW_TRACKING_URI`` if set, else ``sqlite:///<repo root>/mlflow.db``."""
    env = os.environ.get("MLFLOW_TRACKING_URI")
    return env if env else f"sqlite:///{repo_root() / 'mlflow.db'}"


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


def _artifact_location(tracking_uri: str, experiment: str) -> str | None:
    if not tracking_uri.startswith("sqlite:///"):
        return None
    db = Path(tracking_uri.removeprefix("sqlite:///"))
    safe = re.sub(r"[^\w.-]+", "_", experiment)
    return (db.resolve().parent / "mlruns" / safe).as_uri()


def check_tracking(tracking_uri: str | None = None, key: str = "tracking_uri") -> str:
    """Check that an MLflow store can be written, before any work is done.

    Parameters
    ----------
    tracking_uri : str, optional
        Default :func:`default_tracking_uri`.
    key : str
        Config key named in messages.

    Returns
    -------
    str
        The URI.

    Raises
    ------
    ValueError
        One line naming ``key`` and the URI: an SQLite store whose folder is missing or
        not writable, or whose file is not an SQLite database; a local folder store that
        is not writable; an HTTP server that does not answer within 5 s.
    """
    import os
    import sqlite3

    uri = tracking_uri or default_tracking_uri()
    if uri.startswith("sqlite:///"):
        db = Path(uri.removeprefix("sqlite:///"))
        folder = db.parent
        if not folder.is_dir():
            raise ValueError(f"{key}={uri}: folder {folder} does not exist")
        if not os.access(folder, os.W_OK) or (db.exists() and not os.access(db, os.W_OK)):
            raise ValueError(f"{key}={uri}: {db if db.exists() else folder} is not writable")
        if db.exists():
            try:
                con = sqlite3.connect(f"file:{db}?mode=ro", uri=True)
                try:
                    con.execute("select name from sqlite_master limit 1").fetchall()
                finally:
                    con.close()
            except sqlite3.DatabaseError as e:
                raise ValueError(f"{key}={uri}: {db} is not an SQLite database ({e})") from None
    elif uri.startswith(("http://", "https://")):
        import urllib.request

        try:
            urllib.request.urlopen(uri.rstrip("/") + "/health", timeout=5).close()
        except OSError as e:
            raise ValueError(f"{key}={uri}: the tracking server does not answer ({e})") \
                from None
    else:
        folder = Path(uri.removeprefix("file://"))
        probe = folder if folder.exists() else folder.parent
        if not probe.is_dir() or not os.access(probe, os.W_OK):
            raise ValueError(f"{key}={uri}: {probe} is not a writable folder")
    return uri


def quiet_mlflow() -> None:
    """Keep MLflow's own INFO messages (database set-up, migrations) off the console.

    MLflow logs through its logger ``mlflow`` with a handler of its own; its warnings and
    errors still show.
    """
    lg = logging.getLogger("mlflow")
    if lg.getEffectiveLevel() < logging.WARNING:
        lg.setLevel(logging.WARNING)


def get_experiment_id(client, experiment: str) -> str:
    """Id of MLflow experiment ``experiment``, created if absent.

    Parameters
    ----------
    client : mlflow.MlflowClient
    experiment : str
        Experiment name.

    Returns
    -------
    str
    """
    from mlflow.exceptions import MlflowException

    exp = client.get_experiment_by_name(experiment)
    if exp is not None:
        return exp.experiment_id
    try:
        return client.create_experiment(
            experiment, artifact_location=_artifact_location(client.tracking_uri, experiment)
        )
    except MlflowException:  # created meanwhile by a parallel job
        exp = client.get_experiment_by_name(experiment)
        if exp is None:
            raise
        return exp.experiment_id


def confusion_figure(confusion: np.ndarray, labels: Sequence[str], title: str = ""):
    """Confusion-matrix figure (matplotlib, no pyplot state).

    Parameters
    ----------
    confusion : ndarray of int, shape (n_classes, n_classes)
        Rows: true class, columns: predicted class.
    labels : sequence of str, length n_classes
    title : str, optional

    Returns
    -------
    matplotlib.figure.Figure
        Colours: row-normalised rate; numbers: counts.
    """
    from matplotlib.figure import Figure

    cm = np.asarray(confusion)
    rate = cm / np.maximum(cm.sum(axis=1, keepdims=True), 1)
    n = len(labels)
    fig = Figure(figsize=(1.2 * n + 2.5, 1.0 * n + 2.0), layout="constrained")
    ax = fig.add_subplot()
    im = ax.imshow(rate, vmin=0.0, vmax=1.0, cmap="Blues")
    for i in range(n):
        for j in range(n):
            ax.text(j, i, str(int(cm[i, j])), ha="center", va="center",
                    color="white" if rate[i, j] > 0.5 else "black", fontsize=8)
    ax.set_xticks(range(n), labels, rotation=45, ha="right", fontsize=8)
    ax.set_yticks(range(n), labels, fontsize=8)
    ax.set_xlabel("predicted class")
    ax.set_ylabel("true class")
    if title:
        ax.set_title(title, fontsize=9)
    fig.colorbar(im, ax=ax, label="fraction of true class")
    return fig


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
) -> str:
    """Log one job (all splits of one model under one protocol) as one MLflow run.

    Parameters
    ----------
    result : learn.protocols.ProtocolResult
        Per-split accuracies and the summed confusion matrix.
    experiment : str
        MLflow experiment name (created if absent).
    run_name : str
        Run name, e.g. ``"selection3-rf"``.
    params : mapping
        Parameters; nested mappings are flattened with dots (:func:`flatten_config`).
    config : mapping, optional
        Resolved config, stored as the artifact ``config.yaml``.
    tracking_uri : str, optional
        Default :func:`default_tracking_uri`.
    tags : mapping, optional
        Run tags.
    confusion_plot : bool, default True
        Store ``confusion_matrix.png``.

    Returns
    -------
    str
        The MLflow run id.
    """
    import mlflow
    from mlflow.entities import Metric, Param, RunTag

    quiet_mlflow()
    client = mlflow.MlflowClient(tracking_uri or default_tracking_uri())
    exp_id = get_experiment_id(client, experiment)
    run = client.create_run(exp_id, run_name=run_name, tags=dict(tags or {}))
    run_id = run.info.run_id
    status = "FAILED"
    try:
        ts = run.info.start_time
        metrics = []
        for i, s in enumerate(result.splits):
            metrics.append(Metric(f"{s.name}/train_accuracy", float(result.train_accuracy[i]),
                                  ts, 0))
            metrics.append(Metric(f"{s.name}/test_accuracy", float(result.test_accuracy[i]),
                                  ts, 0))
        metrics.append(Metric("mean_train_accuracy", result.mean_train_accuracy, ts, 0))
        metrics.append(Metric("mean_test_accuracy", result.mean_test_accuracy, ts, 0))
        if len(result.fit_time_s):
            metrics.append(Metric("fit_time_s", float(np.sum(result.fit_time_s)), ts, 0))
        flat = sorted(flatten_config(params).items())
        for start in range(0, max(len(flat), 1), 100):  # MLflow: <= 100 params per batch
            chunk = [Param(k, v) for k, v in flat[start:start + 100]]
            client.log_batch(run_id, metrics=metrics if start == 0 else [], params=chunk,
                             tags=[RunTag("splits", ";".join(s.label for s in result.splits))]
                             if start == 0 else [])
        if config is not None:
            client.log_dict(run_id, dict(config), "config.yaml")
        if confusion_plot:
            fig = confusion_figure(result.confusion, result.labels,
                                   f"{run_name}: mean test accuracy "
                                   f"{100 * result.mean_test_accuracy:.1f} %")
            client.log_figure(run_id, fig, "confusion_matrix.png")
        status = "FINISHED"
    finally:
        client.set_terminated(run_id, status=status)
    log.info("MLflow run %s (%s/%s)", run_id, experiment, run_name)
    return run_id
