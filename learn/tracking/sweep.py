"""A Hydra sweep's runs as one group: the group of a job (:func:`hydra_sweep`) and, at the
sweep's end, its summary on the parent run and the console (:class:`SweepSummary`).

Every job of ``swgsim-train -m`` logs its run as a child of the sweep's parent run
(:func:`learn.tracking.mlflow_runs.group_parent`, tagged with the sweep's folder). Once
the sweep ends, :func:`summarize_sweep` writes the children's table to the parent (metrics
``n_runs``, ``best_<metric>``, the tag ``best_run`` and the artifact
``sweep_summary.md``), so MLflow's list and chart views show what the sweep found, and
returns the table the app prints.
"""

from __future__ import annotations

from pathlib import Path
from typing import Any

from hydra.experimental.callback import Callback

from swgsim.base.markdown import md_table

from .mlflow_runs import GROUP_PARENT_TAG
from .store import tracking_client

__all__ = ["SUMMARY_METRIC", "SweepSummary", "hydra_sweep", "summarize_sweep"]

#: The metric a sweep is ranked by (each study job's, :func:`learn.tracking.log_job`).
SUMMARY_METRIC = "mean_test_accuracy"


def hydra_sweep() -> str | None:
    """Group name of the Hydra multirun this process runs a job of, else None.

    Returns
    -------
    str or None
        ``"sweep <absolute sweep dir>"`` (Hydra's default sweep dir holds the start date
        and time, so each sweep has its own); None outside Hydra or in a single run.
    """
    try:
        from hydra.core.hydra_config import HydraConfig
        from hydra.types import RunMode
    except ImportError:
        return None
    if not HydraConfig.initialized():
        return None
    hc = HydraConfig.get()
    if hc.mode != RunMode.MULTIRUN:
        return None
    return sweep_group(hc.sweep.dir)


def sweep_group(sweep_dir: str | Path) -> str:
    """The group of a sweep's runs: ``"sweep <absolute sweep dir>"``."""
    return f"sweep {Path(str(sweep_dir)).resolve()}"


def summarize_sweep(tracking_uri: str | None, group: str,
                    metric: str = SUMMARY_METRIC) -> str | None:
    """Write a sweep's summary to its parent run(s) and return it as a markdown table.

    Parameters
    ----------
    tracking_uri : str or None
        The store (None: :func:`learn.tracking.store.default_tracking_uri`).
    group : str
        The sweep's group (:func:`sweep_group`).
    metric : str, default :data:`SUMMARY_METRIC`
        The metric the runs are ranked by, highest first.

    Returns
    -------
    str or None
        One row per child run (experiment, run, the metric, fit time, status), best
        first; None where the store holds no run of the group.
    """
    client = tracking_client(tracking_uri)
    group = group.replace("'", "_").replace('"', "_")
    names = {e.experiment_id: e.name for e in client.search_experiments()}
    exps = list(names)
    if not exps:
        return None
    runs = client.search_runs(exps, filter_string=f"tags.group = '{group}'", max_results=5000)
    parents = client.search_runs(exps, filter_string=f"tags.{GROUP_PARENT_TAG} = '{group}'")
    if not runs:
        return None
    runs = sorted(runs, key=lambda r: -float(r.data.metrics.get(metric, float("-inf"))))
    rows = [[names.get(r.info.experiment_id, ""), r.info.run_name,
             r.data.metrics.get(metric), r.data.metrics.get("fit_time_s"), r.info.status]
            for r in runs]
    table = md_table(["experiment", "run", metric, "fit time [s]", "status"], rows)
    best = runs[0]
    for p in parents:
        mine = [r for r in runs if r.data.tags.get("mlflow.parentRunId") == p.info.run_id]
        if not mine:
            continue
        top = mine[0]
        client.log_metric(p.info.run_id, "n_runs", float(len(mine)))
        if metric in top.data.metrics:
            client.log_metric(p.info.run_id, f"best_{metric}", top.data.metrics[metric])
        client.set_tag(p.info.run_id, "best_run", top.info.run_name)
        client.log_text(p.info.run_id, table + "\n", "sweep_summary.md")
    return f"best: {best.info.run_name} ({metric} {best.data.metrics.get(metric)})\n{table}"


class SweepSummary(Callback):
    """Hydra callback (``hydra.callbacks`` of ``conf/train.yaml``): at a multirun's end,
    :func:`summarize_sweep` on the sweep's runs, printed. Tracking off (``~logger``): no
    summary."""

    def on_multirun_end(self, config: Any, **kwargs: Any) -> None:
        logger = config.get("logger") if hasattr(config, "get") else None
        if logger is None:
            return
        text = summarize_sweep(logger.get("tracking_uri"), sweep_group(config.hydra.sweep.dir))
        if text:
            print(f"sweep summary ({config.hydra.sweep.dir}):\n{text}")
