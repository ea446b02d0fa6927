"""Data-set generation: a checked plan simulated in resumable shards.

The orchestration only: a data-set config (a :class:`~swgsim.datasets.config.
DatasetConfig`, a mapping, or an already checked :class:`~swgsim.datasets.plan.
DatasetPlan`) is checked once by :func:`swgsim.datasets.plan.plan`, the output folder is
prepared (:mod:`swgsim.datasets.outdir`), and the shards that are not done yet are
simulated in worker processes, each by the runner of its data set's kind
(:data:`RUNNERS`): the grid of variants at steady operating points
(:mod:`swgsim.datasets.grid_shard`), every variant along an operating profile
(:mod:`swgsim.datasets.profile_shard`), or a gear's life (:mod:`swgsim.datasets.life`).

Resumable and atomic: a shard file is written to a temporary name and renamed, then a
sidecar ``<shard>.json`` records its SHA-256; a rerun skips shards whose file matches its
sidecar. The manifest is written last, when every shard is there. A run writes only into a
folder it claimed and replaces only what it can prove it wrote (:mod:`swgsim.files.ownership`).
"""

from __future__ import annotations

import logging
import os
import time
from collections.abc import Callable, Mapping
from pathlib import Path
from typing import Any

from joblib import Parallel, delayed
from tqdm.auto import tqdm

from swgsim.base.registry import travelling
from swgsim.datasets.config import DatasetConfig
from swgsim.datasets.grid_shard import simulate_grid_shard
from swgsim.datasets.life import simulate_life_shard
from swgsim.datasets.outdir import (
    APP,
    check_disk_space,
    finalize,
    finished,
    prepare_out_dir,
    shard_done,
)
from swgsim.datasets.plan import DatasetPlan, ShardSpec, plan
from swgsim.datasets.profile_shard import simulate_profile_shard
from swgsim.datasets.resources import check_memory
from swgsim.datasets.schema import write_shard
from swgsim.datasets.steps import gear_influences
from swgsim.files import ownership
from swgsim.files.ownership import atomic_write_json
from swgsim.gear.influence import Influence

log = logging.getLogger(__name__)


#: The shard runner of each kind of data set (:attr:`DatasetPlan.kind`): ``runner(plan,
#: shard, influences) -> (xarray.Dataset, n_windows)``.
RUNNERS: dict[str, Callable] = {"grid": simulate_grid_shard,
                                "profile": simulate_profile_shard,
                                "life": simulate_life_shard}


def simulate_shard(plan: DatasetPlan, shard: ShardSpec,
                   influences: dict[tuple | None, Influence]):
    """Simulate one shard with the runner of its data set's kind (:data:`RUNNERS`).

    Parameters
    ----------
    plan : DatasetPlan
        The checked data set (:func:`swgsim.datasets.plan.plan`).
    shard : ShardSpec
    influences : dict
        This gear's influences (:func:`swgsim.datasets.steps.gear_influences`).

    Returns
    -------
    (xarray.Dataset, int)
        The shard as a schema-v1 data set and its number of windows.
    """
    return RUNNERS[plan.kind](plan, shard, influences)


def run_shard(plan: DatasetPlan, shard: ShardSpec, out_dir: str | os.PathLike,
              influences: dict[tuple | None, Influence]) -> dict:
    """Simulate and write one shard atomically, then its sidecar; return the sidecar."""
    t0 = time.perf_counter()
    ds, n = simulate_shard(plan, shard, influences)
    path = Path(out_dir) / shard.name
    sha = write_shard(ds, path)
    side = {"sha256": sha, "n_samples": int(n), "config_hash": plan.config_hash,
            "content_sha256": ds.attrs["content_sha256"]}
    atomic_write_json(path.with_suffix(".json"), side)
    log.info("shard %s: %d windows in %.1f s", shard.name, n, time.perf_counter() - t0)
    return side


def _warm() -> None:
    """Import the simulation stack in a worker (runs while the parent factorises)."""
    import h5netcdf  # noqa: F401  (third-party, imported early in the worker)
    import xarray  # noqa: F401


def _run_shard_in_worker(p: DatasetPlan, s: ShardSpec, out: Path,
                         influences: dict) -> dict:
    """:func:`run_shard` in a worker process, registered in the stamp of the folder its
    parent claimed, so that its temporary and finished files are ours."""
    with ownership.join(out, APP):
        return run_shard(p, s, out, influences)


def _run(p: DatasetPlan, todo: list[ShardSpec], out: Path, n_workers: int, bar) -> None:
    """Simulate and write the shards ``todo``, in-process or in ``n_workers`` workers."""
    if n_workers <= 1:
        infl = gear_influences(p, todo) if todo else {}
        for s in todo:
            run_shard(p, s, out, infl[s.gear])
            bar.update()
        return

    def tasks():
        # the workers start and import while the parent factorises the truss: joblib
        # takes the first tasks before it asks for the shards
        for _ in range(n_workers):
            yield delayed(_warm)()
        infl = gear_influences(p, todo)
        run = travelling(_run_shard_in_worker)  # a user's sensor faults, effects, ...
        for s in todo:
            yield delayed(run)(p, s, out, infl[s.gear])

    par = Parallel(n_jobs=n_workers, return_as="generator_unordered",
                   pre_dispatch=f"{n_workers + 1}")
    for r in par(tasks()):
        if r is not None:
            bar.update()


def generate(cfg: DatasetConfig | DatasetPlan | Mapping[str, Any], out_dir: str | os.PathLike,
             n_jobs: int = 1, overwrite: bool = False, shard_index: int | None = None,
             progress: bool = True) -> dict:
    """Generate (or complete) a data set.

    Parameters
    ----------
    cfg : DatasetConfig, DatasetPlan or mapping
        The data set (:class:`swgsim.datasets.config.DatasetConfig`, e.g. its defaults, the paper
        preset); a plan from :func:`swgsim.datasets.plan.plan` is not checked again.
    out_dir : path-like
        Target directory.
    n_jobs : int
        Worker processes for the shards (joblib, loky backend); 1 runs in-process.
    overwrite : bool
        Replace a finished data set of another config in ``out_dir`` (only files its
        ownership stamp proves a run of this project wrote).
    shard_index : int, optional
        Compute only this shard (for cluster array jobs, e.g. the Hydra submitit
        launcher); the manifest is written by whichever call finds all shards present.
    progress : bool
        Show a progress bar.

    Returns
    -------
    dict
        Summary: ``out_dir``, ``windows`` (samples written), ``computed`` and ``skipped``
        shard names, ``wall_s``, ``complete``, ``content_sha256`` (when complete),
        ``replaced`` (what an ``overwrite`` replaced, or None).

    Raises
    ------
    ValueError
        On any invalid config value (see :func:`swgsim.datasets.plan.plan`), ``n_jobs`` or
        ``shard_index``, shards too large for the memory available
        (:func:`swgsim.datasets.resources.check_memory`), or an ``out_dir`` holding a file not
        provably this project's (named) or another config's finished data set without
        ``overwrite``
        (:func:`swgsim.datasets.outdir.prepare_out_dir`); before anything is written or deleted.
        A finished data set of this config is used as it is (nothing is written).
    """
    t0 = time.perf_counter()
    if int(n_jobs) < 1:
        raise ValueError(f"n_jobs must be >= 1, got {n_jobs}")
    p = plan(cfg)
    shards = p.shards
    if shard_index is not None and not 0 <= int(shard_index) < len(shards):
        raise ValueError(f"shard must lie in [0, {len(shards) - 1}], got {shard_index}")
    out = Path(out_dir)
    todo_all = list(shards) if shard_index is None else [shards[int(shard_index)]]
    done = finished(out, p)
    if done is not None:  # nothing to write, so nothing to prove: used as it is
        return {"out_dir": str(out), "computed": [], "skipped": [s.name for s in todo_all],
                "complete": True, "replaced": None, "windows": int(done.get("n_samples", 0)),
                "content_sha256": done.get("content_sha256"),
                "wall_s": time.perf_counter() - t0}
    todo = [s for s in todo_all if not shard_done(out, s, p.config_hash)]
    check_disk_space(out, todo, p)  # before anything is written
    check_memory(p, todo, min(int(n_jobs), len(todo)))
    replaced, claim = prepare_out_dir(out, p, overwrite)
    with claim:
        skipped = [s.name for s in todo_all if s not in todo]
        if skipped:
            log.info("resuming: %d shard(s) already done, skipped", len(skipped))
        bar = tqdm(total=len(todo), desc=f"generate {p.config.name}", unit="shard",
                   disable=not progress or not todo)
        try:
            _run(p, todo, out, min(int(n_jobs), len(todo)), bar)
        finally:
            bar.close()
        complete = all(shard_done(out, s, p.config_hash) for s in shards)
        summary: dict[str, Any] = {"out_dir": str(out), "computed": [s.name for s in todo],
                                   "skipped": skipped, "complete": complete,
                                   "replaced": replaced}
        if complete:
            manifest = finalize(out, p)
            summary["windows"] = manifest["n_samples"]
            summary["content_sha256"] = manifest["content_sha256"]
        else:
            summary["windows"] = int(sum(s.n_windows for s in todo))
    summary["wall_s"] = time.perf_counter() - t0
    return summary


__all__ = ["RUNNERS", "generate", "run_shard", "simulate_shard"]
