"""``swgsim-train``'s task dispatch: :data:`TASKS` (each task's function, imported here),
:func:`check_inputs` and :func:`run_train`. In the apps' package, above :mod:`learn` and
:mod:`swgmon`, whose tasks it names; the tasks themselves live there."""

from __future__ import annotations

import logging
from collections.abc import Callable

from learn.paper.job import run_study_job
from learn.paper.task import run_paper_study_task
from learn.tasks.config import typed_app
from learn.tracking.store import check_tracking
from learn.transfer.task import run_transfer
from swgmon.evaluation.benchmark_task import run_benchmark
from swgmon.evaluation.own_joint import run_own_joint
from swgmon.evaluation.prognosis_task import run_prognosis_evaluation
from swgmon.evaluation.task import run_monitor_evaluation
from swgsim.datasets.schema import read_manifest

log = logging.getLogger(__name__)

#: Task name (``swgsim-train task=...``, set by ``conf/experiment/*.yaml``) -> its function
#: ``f(cfg) -> dict`` of the typed app config.
TASKS: dict[str, Callable[..., dict]] = {
    "study": run_study_job,
    "paper_study": run_paper_study_task,
    "transfer": run_transfer,
    "monitor": run_monitor_evaluation,
    "prognosis": run_prognosis_evaluation,
    "benchmark": run_benchmark,
    "own_joint": run_own_joint,
}


def check_inputs(cfg) -> None:
    """What ``swgsim-train`` reads, checked before any work and before its libraries are
    imported (:func:`swgcli.app.hydra_app`'s ``inputs``): the task's name and, for a task
    that reads a data set already on disk (``study``, ``paper_study``, ``transfer``
    without ``transfer.run_on``), that data set's manifest.

    Parameters
    ----------
    cfg : omegaconf.DictConfig or swgcli.schema.TrainApp
        Composed ``conf/train.yaml``.

    Raises
    ------
    ValueError
        A task not in :data:`TASKS`, or ``stored.path`` not a data set
        (:class:`swgsim.datasets.schema.DataSetError`, naming the path).
    """
    _check_task(cfg.task)
    reads_stored = cfg.task in ("study", "paper_study") or (
        cfg.task == "transfer" and cfg.transfer is not None and not cfg.transfer.run_on)
    if reads_stored:
        read_manifest(cfg.stored.path)


def _check_task(task: str) -> None:
    if task not in TASKS:
        raise ValueError(f"task must be one of {sorted(TASKS)}, got {task!r}")


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
    app = typed_app(cfg)
    _check_task(app.task)  # the rest of check_inputs, the app's, in the task's own order
    if app.logger is not None:
        check_tracking(app.logger.tracking_uri, "logger.tracking_uri")
    task = TASKS[app.task]
    log.info("task %s -> %s.%s", app.task, task.__module__, task.__qualname__)
    return task(app)
