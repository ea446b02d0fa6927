"""The transfer comparison's MLflow runs (:func:`log_transfer`): a parent run with the
report and one child per cell of :data:`learn.transfer.report.CELL_KEYS`."""

from __future__ import annotations

import dataclasses
from collections.abc import Mapping, Sequence
from pathlib import Path
from typing import Any

from learn.tracking.config import LoggerConfig
from learn.transfer.report import CELL_KEYS
from learn.transfer.study import TransferConfig
from swgsim.base.lazy import lazy_module

pd = lazy_module("pandas")


def log_transfer(results: pd.DataFrame, files: Mapping[str, Path], logger: LoggerConfig,
                 tc: TransferConfig, data_sets: Sequence[tuple[str, str]], timings: Mapping,
                 latency: pd.DataFrame | None = None,
                 config: Mapping[str, Any] | None = None) -> str:
    """Log the comparison to MLflow through :func:`learn.tracking.log_run`.

    Two levels, each run with the git commit and its data set(s) as dataset inputs:

    * a parent run: the ``transfer.*`` params, where the nets ran (``timings["nets"]``:
      ``device``, ``deterministic``, ... of :func:`learn.learners.devices.device_record`),
      ``config.yaml``, the report files, metric ``wall_s``, every data set compared;
    * one child per (dataset, protocol, model, input, k): params of those five and
      ``seeds`` (the list), metrics over the seeds ``<split>/accuracy_mean``,
      ``<split>/accuracy_std`` (population), ``<split>/accuracy_min``,
      ``mean_accuracy``, ``worst_split_accuracy``, ``train_s`` (sum) and ``latency_ms``
      where measured. Every metric is one value of its run (step 0); the per-seed
      accuracies are in the parent's ``results.csv``. (A run per seed would hold them too,
      at 5 runs more per cell: measured 1.1 s more per cell on a local SQLite store, 2
      busy cores, against 0.25 s for the cell's own run.)

    Parameters
    ----------
    results : pandas.DataFrame
        :data:`learn.transfer.study.RESULT_COLUMNS`, one row per (cell, split, seed).
    files : mapping of str to Path
        Report files, stored as artifacts of the parent.
    logger : LoggerConfig
        Tracking URI, experiment and parent run name.
    tc : TransferConfig
        The comparison, logged as the parent's ``transfer.*`` params (without the
        data-set configs, which are in ``config.yaml``).
    data_sets : sequence of (str, str)
        (name, path) of the compared data sets; those in ``results`` are logged as
        dataset inputs.
    timings : mapping
        ``wall_s`` [s] at least; ``nets``, a mapping of params, where given.
    latency : pandas.DataFrame, optional
        ``model``, ``input``, ``model_ms`` per (model, input).
    config : mapping, optional
        The resolved config of the run, stored as the parent's ``config.yaml``.

    Returns
    -------
    str
        The parent run id.
    """
    from learn.tracking import log_run
    from learn.tracking.provenance import dataset_ref

    compared = set(results["dataset"])
    refs = {d: dataset_ref(p, d) for d, p in data_sets if d in compared}
    params = dataclasses.asdict(tc)
    params.pop("datasets")  # the data-set configs are in config.yaml
    with log_run(logger.experiment, logger.run_name, tracking_uri=logger.tracking_uri,
                 params={"transfer": params, **dict(timings.get("nets", {}))},
                 config=config, dataset=list(refs.values()),
                 tags={"task": "transfer"}) as parent:
        parent.log_metrics({"wall_s": float(timings["wall_s"])})
        for f in files.values():
            parent.log_artifact(f)
        for key, g in results.groupby(CELL_KEYS):
            _log_cell(logger, parent.run_id, key, g, refs, latency)
    return parent.run_id


def _log_cell(logger: LoggerConfig, parent_id: str, key: tuple, g: pd.DataFrame,
              refs: Mapping, latency: pd.DataFrame | None) -> None:
    """The child run of one (dataset, protocol, model, input, k): seed statistics."""
    from learn.tracking import log_run

    d, p, m, i, k = key
    keys = {"dataset": d, "protocol": p, "model": m, "input": i, "k_shot": int(k)}
    means = g.groupby("split")["accuracy"].mean()
    with log_run(logger.experiment, f"{d}-{p}-{m}-{i}-k{k}", tracking_uri=logger.tracking_uri,
                 params={**keys, "seeds": sorted(int(x) for x in set(g["seed"]))},
                 dataset=refs.get(d), parent_run_id=parent_id,
                 tags={"task": "transfer", "dataset": d, "protocol": p,
                       "splits": ";".join(sorted(means.index))}) as cell:
        per_seed = g.groupby(["split", "seed"])["accuracy"].mean().unstack("seed")
        mets = {}
        for s, row in per_seed.iterrows():
            mets.update({f"{s}/accuracy_mean": float(row.mean()),
                         f"{s}/accuracy_std": float(row.std(ddof=0)),
                         f"{s}/accuracy_min": float(row.min())})
        mets.update(mean_accuracy=float(means.mean()), worst_split_accuracy=float(means.min()),
                    train_s=float(g["train_s"].sum()))
        if latency is not None and len(latency):
            lat = latency[(latency["model"] == m.split("+")[0]) & (latency["input"] == i)]
            if len(lat):
                mets["latency_ms"] = float(lat["model_ms"].iloc[0])
        cell.log_metrics(mets)
