"""Deep learners and transfer to the unseen gear: the whole comparison in one task.

``swgsim-train -m experiment=transfer`` -> :func:`run_transfer`: per data set, protocol
(:data:`learn.studies.protocols.PROTOCOLS`), split and seed, every (model, input) run
trained, adapted with k shots or unlabelled healthy windows, and scored; the jobs share
one pool of workers (:func:`run_comparisons`, :class:`JobProgress`). Files: ``results.csv``
(:data:`RESULT_COLUMNS`), ``confusion.csv`` (:data:`CONFUSION_COLUMNS`), ``run_times.csv``
(:data:`RUN_TIME_COLUMNS`), ``table.md``. Design (which windows each step sees, the files,
MLflow): docs/learners_transfer.md, "The comparison" and "What was chosen on what data".
"""

from __future__ import annotations

import logging
import time
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field, replace
from typing import Any

import numpy as np

from learn.inputs.signals import INPUTS, ResidualSettings, build_input, window_meta
from learn.studies.kshot import check_no_leak, kshot_split
from learn.studies.protocols import ALL_PROTOCOLS, OOD_PROTOCOLS, PROTOCOLS, protocol_splits
from learn.studies.runs import (
    ADAPT,
    FT_MODES,
    FinetuneSettings,
    JobProgress,
    RunRef,
    RunSpec,
    check_estimator,
    final_step,
    fit_and_adapt,
    fit_at_once,
    make_estimator,
    net_device_settings,
)
from swgsim.base.lazy import lazy_module
from swgsim.base.registry import travelling
from swgsim.base.typed import check_tree
from swgsim.datasets.config import DatasetConfig

pd = lazy_module("pandas")
torch = lazy_module("torch")

log = logging.getLogger(__name__)

RESULT_COLUMNS = ("dataset", "protocol", "split", "model", "input", "k_shot", "seed",
                  "accuracy", "train_s", "n_test")
CONFUSION_COLUMNS = ("dataset", "protocol", "split", "seed", "model", "input", "k_shot",
                     "true", "predicted", "count")
#: Wall and CPU time [s] of one run (model, input) in one job: fit, adaptations, scoring.
RUN_TIME_COLUMNS = ("dataset", "protocol", "split", "seed", "model", "input", "seconds",
                    "cpu_s")


# --------------------------------------------------------------------------- config


@dataclass
class TargetSpec:
    """What a data set's comparison should reach (checked in the report).

    Attributes
    ----------
    protocol : str
        Evaluation protocol the targets refer to.
    accuracy : dict of int to float
        k -> least worst-split mean accuracy (0..1) of the best run.
    recall : dict of str to float
        Class -> least recall (0..1) of the best run at k = 0.
    """

    protocol: str = "ood_disturbed"
    accuracy: dict[int, float] = field(default_factory=dict)
    recall: dict[str, float] = field(default_factory=dict)


@dataclass
class TransferConfig:
    """``transfer`` of ``swgsim-train experiment=transfer`` (``conf/experiment/transfer.yaml``).

    Attributes
    ----------
    run_on : list of str
        Keys of ``datasets`` to run, in order; empty: the data set at ``data.path``.
    datasets : dict of str to DatasetConfig
        Data-set presets; each is generated in ``<data_root>/<key>`` when not there.
    data_root : str
        Folder of the generated data sets (shared with ``swgsim-paper``'s).
    protocols : list of str
        Evaluation protocols (:data:`learn.transfer.report.ALL_PROTOCOLS`).
    seeds, cv_seeds : list of int
        Model seeds and k-shot draws (leave-one-gear-out); model seeds of the CV
        protocols (null: ``seeds``).
    k_shots : list of int
        Labelled windows per class of the held-out gear, >= 0.
    adapt_windows : int
        Least number of the held-out gear's unlabelled healthy windows, the target data of
        the unsupervised adaptations (whole healthy variants outside the k-shot pool,
        removed from the evaluation windows); 0: none (no run may adapt). 60 = ten healthy
        passes over the paper grid's six operating points [choice]; it leaves 288 of a
        gear's 360 healthy windows of a kind for evaluation.
    aux : list of str
        Scalars appended to the signal inputs (:data:`learn.inputs.signals.AUX`).
    residual : ResidualSettings
        Settings of the residual inputs.
    finetune : FinetuneSettings
    runs : list of RunSpec
        ``{model, input, finetune, adapt, params}`` each (:class:`learn.studies.runs.RunSpec`).
    primary : RunRef or None
        ``{model, input}`` declared before the comparison (reported beside the best);
        None: none.
    targets : dict of str to TargetSpec
    n_threads, n_jobs, threads_per_job : int
        Torch threads of the main process; (protocol, split, seed) cells in parallel
        processes; torch threads per process.
    stack_seeds : bool or None
        Run the seeds of a split as one job whose torch nets are trained at once
        (:func:`learn.learners.stacked.fit_seeds`; with dropout, in distribution what one
        by one gives); None: where a net runs on a GPU, which stacking fills (on a CPU it
        is no faster: ``docs/results/speed.md``, "Nets on a GPU").
    latency, latency_repeats, progress : bool, int, bool
    report_dir : str
    group : int or None
        One data set of ``run_on`` by index (a job of an array): its cells saved in
        ``report_dir/parts``, no report; None: every data set, the finished cells resumed
        from ``parts``, then the report.
    models : dict
        Model name -> ``_target_`` config (``conf/model/*.yaml``).
    """

    run_on: list[str] = field(default_factory=lambda: ["paper", "bench", "robot_joint"])
    datasets: dict[str, DatasetConfig] = field(default_factory=dict)
    data_root: str = "data"
    protocols: list[str] = field(default_factory=lambda: ["ood_disturbed"])
    seeds: list[int] = field(default_factory=lambda: [0, 1, 2, 3, 4])
    cv_seeds: list[int] | None = field(default_factory=lambda: [0])
    k_shots: list[int] = field(default_factory=lambda: [0, 1, 5, 10])
    adapt_windows: int = 60
    aux: list[str] = field(default_factory=lambda: ["eta2_rel", "eta_rel"])
    residual: ResidualSettings = field(default_factory=ResidualSettings)
    finetune: FinetuneSettings = field(default_factory=FinetuneSettings)
    runs: list[RunSpec] = field(default_factory=list)
    primary: RunRef | None = None
    targets: dict[str, TargetSpec] = field(default_factory=dict)
    n_threads: int = 1
    n_jobs: int = 2
    threads_per_job: int | None = 1
    stack_seeds: bool | None = None
    latency: bool = True
    latency_repeats: int = 100
    progress: bool = True
    report_dir: str = "reports/transfer"
    group: int | None = None
    models: dict[str, Any] = field(default_factory=dict)

    def check(self, where: str) -> None:
        """Refuse a comparison the study cannot run, before any work (run by
        :func:`swgsim.base.typed.check_tree`, after its data sets' own checks).

        Parameters
        ----------
        where : str
            Full name of the config for messages, ``transfer``.

        Raises
        ------
        ValueError
            One line naming the key (``transfer.<key>``) and what is allowed: protocols,
            ``run_on`` and ``group`` against ``datasets``, seeds, k-shots, worker and
            thread counts, the fine-tuning, each run (its model, input, adaptation and
            the estimator's settings), the primary run, the targets.
        """
        bad = [p for p in self.protocols if p not in ALL_PROTOCOLS]
        if bad or not self.protocols:
            raise ValueError(f"{where}.protocols: must list some of {ALL_PROTOCOLS}, got "
                             f"{list(self.protocols)}")
        unknown = [d for d in self.run_on if d not in self.datasets]
        if unknown:
            raise ValueError(f"{where}.run_on: {unknown} not among {where}.datasets "
                             f"{sorted(self.datasets)}")
        if len(set(self.run_on)) != len(self.run_on):
            raise ValueError(f"{where}.run_on must not repeat, got {list(self.run_on)}")
        names = list(self.run_on) or ["the stored data set"]
        if self.group is not None and not 0 <= int(self.group) < len(names):
            pairs = ", ".join(f"{k}: {n}" for k, n in enumerate(names))
            raise ValueError(f"{where}.group must lie in [0, {len(names) - 1}] ({pairs}), "
                             f"got {self.group}")
        if not self.seeds:
            raise ValueError(f"{where}.seeds: must list at least one seed")
        if any(int(k) < 0 for k in self.k_shots) or 0 not in [int(k) for k in self.k_shots]:
            raise ValueError(f"{where}.k_shots: must hold 0 and values >= 0, got "
                             f"{list(self.k_shots)}")
        for key in ("n_jobs", "n_threads", "latency_repeats"):
            if int(getattr(self, key)) < 1:
                raise ValueError(f"{where}.{key}: must be >= 1, got {getattr(self, key)}")
        if int(self.adapt_windows) < 0:
            raise ValueError(f"{where}.adapt_windows: must be >= 0, got {self.adapt_windows}")
        _check_finetune(self.finetune, where)
        _check_runs(self, where)
        _check_targets(self.targets, where)


def _check_finetune(ft: FinetuneSettings, where: str) -> None:
    if not float(ft.replay) > 0:
        raise ValueError(f"{where}.finetune.replay: must be > 0, got {ft.replay}")
    bad = [m for m in ft.modes if m not in FT_MODES]
    if bad:
        raise ValueError(f"{where}.finetune.modes: must be among {FT_MODES}, got {bad}")


def _check_runs(tc: TransferConfig, where: str) -> None:
    if not tc.runs:
        raise ValueError(f"{where}.runs: must list at least one {{model, input}}")
    for i, s in enumerate(tc.runs):
        if s.model not in tc.models:
            raise ValueError(f"{where}.runs[{i}].model: {s.model!r} not among "
                             f"{where}.models {sorted(tc.models)}")
        if s.input not in INPUTS:
            raise ValueError(f"{where}.runs[{i}].input: {s.input!r} not among {INPUTS}")
        if s.adapt not in (None, *ADAPT):
            raise ValueError(f"{where}.runs[{i}].adapt: must be one of {ADAPT} or null, "
                             f"got {s.adapt!r}")
        if s.adapt is not None and int(tc.adapt_windows) < 1:
            raise ValueError(f"{where}.runs[{i}].adapt: {s.adapt} needs unlabelled "
                             f"target windows; set {where}.adapt_windows >= 1")
        _check_model(tc, i, s, where)
    pr = tc.primary
    if pr is not None and pr.label not in {s.label for s in tc.runs}:
        raise ValueError(f"{where}.primary: {pr.label} is not one of {where}.runs; name "
                         f"one of them, or {where}.primary=null for none")


def _check_model(tc: TransferConfig, i: int, spec: RunSpec, where: str) -> None:
    """The run's estimator instantiated (not fitted): its ``params`` and the settings its
    ``check_params`` refuses, named by key."""
    est = make_estimator(tc.models[spec.model], 0, 0)
    final = final_step(est)
    bad = sorted(set(spec.params or {}) - set(final.get_params(deep=False)))
    if bad:
        raise ValueError(f"{where}.runs[{i}].params: {bad} are not parameters of "
                         f"{type(final).__name__}; it has "
                         f"{sorted(final.get_params(deep=False))}")
    final.set_params(**dict(spec.params or {}))
    check_estimator(est, f"{where}.models.{spec.model}.estimator" + (
        f" with {where}.runs[{i}].params" if spec.params else ""))


def _check_targets(targets: Mapping[str, TargetSpec], where: str) -> None:
    for name, t in targets.items():
        if t.protocol not in ALL_PROTOCOLS:
            raise ValueError(f"{where}.targets.{name}.protocol: must be one of "
                             f"{ALL_PROTOCOLS}, got {t.protocol!r}")
        for k, v in {**t.accuracy, **t.recall}.items():
            if not 0.0 <= float(v) <= 1.0:
                raise ValueError(f"{where}.targets.{name}.{k}: a fraction in [0, 1], "
                                 f"got {v}")


# --------------------------------------------------------------------------- runs


def _cell(protocol: str, split, seeds: Sequence[int], specs, model_cfgs, inputs, k_max: int,
          k_shots, ft: FinetuneSettings, adapt_windows: int, threads: int | None,
          stack: bool) -> list[tuple[list[dict], dict[str, tuple[float, float]]]]:
    """Every (model, input) of one (protocol, split) for each of ``seeds`` (a *job*); with
    ``stack`` each torch net trained for all seeds at once (:func:`fit_at_once`). Returns
    per seed the result rows and, by run label, the wall and CPU time of each run [s] (fit
    or a stacked fit's share, adaptations, fine-tuning, scoring; CPU: this process's).
    ``threads``: torch threads, set again before each run (fitting MiniRocket puts them
    back to the number of cores, :mod:`learn.studies.latency`)."""
    meta = next(iter(inputs.values())).meta
    shots = [_shots(meta, protocol, split, seed, k_max, adapt_windows) for seed in seeds]
    out = [([], {}) for _ in seeds]
    before = torch.get_num_threads()
    try:
        for spec in specs:
            if threads:
                torch.set_num_threads(int(threads))
            inp = inputs[spec.input]
            t0, c0 = time.perf_counter(), time.process_time()
            fitted = fit_at_once(spec, model_cfgs[spec.model], inp, split.train, seeds) \
                if stack else None
            share = ((time.perf_counter() - t0) / len(seeds),
                     (time.process_time() - c0) / len(seeds)) if fitted else (None, 0.0)
            for i, seed in enumerate(seeds):
                t0, c0 = time.perf_counter(), time.process_time()
                est = fitted[i] if fitted else make_estimator(model_cfgs[spec.model], seed,
                                                              inp.n_aux, spec.params)
                rows = fit_and_adapt(spec, est, inp, split.train, shots[i][1], shots[i][0],
                                     k_shots, ft, seed, fitted_s=share[0])
                out[i][0].extend({"protocol": protocol, "split": split.name, **r}
                                 for r in rows)
                out[i][1][spec.label] = (time.perf_counter() - t0 + (share[0] or 0.0),
                                         time.process_time() - c0 + share[1])
    finally:
        torch.set_num_threads(before)
    return out


def _shots(meta, protocol: str, split, seed: int, k_max: int, adapt_windows: int):
    """The held-out gear's k-shot split of ``seed`` (None outside leave-one-gear-out) and
    the windows scored."""
    if protocol not in OOD_PROTOCOLS:
        return None, split.test
    kshot = kshot_split(meta, split.test, k_max, seed, n_unlabelled=adapt_windows)
    check_no_leak(meta, split.train, kshot)
    return kshot, kshot.evaluation


def stacks_seeds(tc: TransferConfig) -> bool:
    """Whether the comparison runs each split's seeds as one job (``tc.stack_seeds``;
    None: where a run's torch net resolves to a GPU on this machine)."""
    if tc.stack_seeds is not None:
        return bool(tc.stack_seeds)
    return any(d.type == "cuda" for d in net_device_settings(tc.runs, tc.models).values())


# --------------------------------------------------------------------------- comparison


def _protocols_with_data(ds, protocols: Sequence[str]) -> list[str]:
    """The protocols whose windows (clean or disturbed) the data set holds."""
    present = set(np.unique(ds["disturbed"].values.astype(bool)).tolist())
    todo = [p for p in protocols if p.endswith("disturbed") in present]
    if len(todo) < len(protocols):
        log.warning("skipping protocols without data: %s", sorted(set(protocols) - set(todo)))
    return todo


def _cells_of(meta, protocols: Sequence[str], tc: TransferConfig, split_seed: int) -> list:
    """(protocol, split, seed) of every cell: model seeds per split, the splits fixed by
    ``split_seed`` so that a split name means the same windows for every seed."""
    cv_seeds = tc.seeds if tc.cv_seeds is None else tc.cv_seeds
    return [(p, sp, int(seed)) for p in protocols
            for sp in protocol_splits(meta, p, random_state=split_seed)
            for seed in (tc.seeds if p in OOD_PROTOCOLS else cv_seeds)]


def planned_jobs(tc: TransferConfig) -> int:
    """Jobs, (protocol, split, seed), that the comparison plans per data set: the splits
    each protocol plans (:attr:`learn.studies.protocols.ProtocolConfig.n_planned`) times
    its seeds."""
    cv_seeds = tc.seeds if tc.cv_seeds is None else tc.cv_seeds
    return sum(PROTOCOLS[p].n_planned * len(tc.seeds if p in OOD_PROTOCOLS else cv_seeds)
               for p in tc.protocols)


@dataclass
class _Gathered:
    """What the jobs of one data set gave back, cell by cell in the planned order: its
    tables do not depend on the order the workers finished in, nor on a resume."""

    order: list = field(default_factory=list)
    cells: dict = field(default_factory=dict)
    input_s: float = 0.0
    latency: pd.DataFrame | None = None

    def planned(self, c: tuple) -> None:
        """Cell ``c`` = (protocol, split, seed) is next in the order."""
        self.order.append((c[0], c[1].name, c[2]))

    def rows(self, i: int = 0) -> list:
        """The result rows (``i`` 0) or the run times (1) of the finished cells, in order."""
        return [r for k in self.order if k in self.cells for r in self.cells[k][i]]


def _jobs(sources, tc: TransferConfig, feature_kwargs, split_seed: int, latency: bool,
          progress: JobProgress, got: dict[str, _Gathered], on_load, parts):
    """The jobs of every data set in turn, as ``(function, args, kwargs)``: a data set is
    loaded and its inputs built when its first job is asked for, i.e. (in a pool) while
    the workers run the previous data set's last jobs. A cell that ``parts`` holds is
    gathered from it instead, and a data set whose cells it all holds builds no input."""
    k_shots = [int(k) for k in tc.k_shots]
    threads = tc.n_threads if tc.n_jobs == 1 else tc.threads_per_job
    stack = stacks_seeds(tc)
    cell = travelling(_with_cells)  # a user's learners travel with the jobs
    labels = {s.label: s for s in tc.runs}
    for name, load in sources:
        ds = load()
        if on_load is not None:
            on_load(name, ds)
        planned = planned_jobs(tc)  # counted in progress, not yet adjusted
        todo = _protocols_with_data(ds, tc.protocols)
        first = all(g.latency is None for g in got.values())
        for flag in (False, True):
            prots = [p for p in todo if p.endswith("disturbed") == flag]
            if not prots:
                continue
            n_plan = planned_jobs(replace(tc, protocols=prots))
            planned -= n_plan
            cells = [] if parts is None else _cells_of(window_meta(ds, flag)[0], prots, tc,
                                                      split_seed)
            if cells and all(parts.load(name, c) is not None for c in cells):
                progress.adjust(len(cells) - n_plan)
                for c in cells:
                    got[name].planned(c)
                    _gather(got, labels, name, c, *parts.load(name, c), progress)
                if latency and first:
                    got[name].latency = parts.latency(name)
                continue
            t0 = time.perf_counter()
            inputs = _inputs(ds, tc.runs, tc, flag, feature_kwargs)
            got[name].input_s += time.perf_counter() - t0
            cells = _cells_of(next(iter(inputs.values())).meta, prots, tc, split_seed)
            progress.adjust(len(cells) - n_plan)
            if latency and first and got[name].latency is None:
                got[name].latency = _latency(ds, name, tc, inputs, feature_kwargs, parts)
            args = (tc.runs, tc.models, inputs, max([0, *k_shots]), k_shots, tc.finetune,
                    int(tc.adapt_windows), threads, stack)
            left = []
            for c in cells:
                got[name].planned(c)
                done = None if parts is None else parts.load(name, c)
                if done is not None:
                    _gather(got, labels, name, c, *done, progress)
                else:
                    left.append(c)
            for group in _job_cells(left, stack):
                yield cell, (name, group, *args), {}
            del inputs
        progress.adjust(-planned)  # protocols without data
        del ds


def _latency(ds, name, tc, inputs, feature_kwargs, parts):
    """The inference latency on the first data set, before its jobs are handed out (on a
    machine without this comparison's jobs running), or as ``parts`` kept it."""
    from learn.studies.latency import measure_latency

    kept = None if parts is None else parts.latency(name)
    if kept is not None:
        return kept
    lat = measure_latency(ds, tc.runs, tc.models, inputs, aux=tc.aux,
                          feature_kwargs=feature_kwargs, residual=tc.residual,
                          repeats=tc.latency_repeats)
    if parts is not None:
        parts.save_latency(name, lat)
    return lat


def _gather(got: dict[str, _Gathered], labels: Mapping, name: str, c: tuple, rows: list,
            seconds: Mapping, progress: JobProgress) -> None:
    """One finished cell's rows and run times into ``got`` and the progress line."""
    got[name].cells[(c[0], c[1].name, c[2])] = (rows, [
        {"dataset": name, "protocol": c[0], "split": c[1].name, "seed": c[2],
         "model": labels[k].model, "input": labels[k].input, "seconds": v[0],
         "cpu_s": v[1]} for k, v in seconds.items()])
    progress.finished(name, c, seconds, rows)


def _job_cells(cells: list, stack: bool) -> list[list]:
    """The cells of each job: one each, or with ``stack`` a (protocol, split)'s together."""
    if not stack:
        return [[c] for c in cells]
    groups: dict[tuple, list] = {}
    for c in cells:
        groups.setdefault((c[0], c[1].name), []).append(c)
    return list(groups.values())


def _with_cells(name: str, cells: list, *args) -> list[tuple]:
    """:func:`_cell` of ``cells`` (one protocol and split), each result beside its data
    set and cell (results come back unordered)."""
    out = _cell(cells[0][0], cells[0][1], [c[2] for c in cells], *args)
    return [(name, c, o) for c, o in zip(cells, out, strict=True)]


def _tables(rows: list[dict], dataset: str) -> tuple[pd.DataFrame, pd.DataFrame]:
    """``results`` (:data:`RESULT_COLUMNS`) and ``confusion`` per split and seed."""
    for r in rows:
        r["dataset"] = dataset
    conf = [{"dataset": dataset, "protocol": r["protocol"], "split": r["split"],
             "seed": r["seed"], "model": r["model"], "input": r["input"],
             "k_shot": r["k_shot"], "true": t, "predicted": p, "count": c}
            for r in rows for t, p, c in r["confusion"]]
    keys = list(CONFUSION_COLUMNS[:-1])
    confusion = (pd.DataFrame(conf).groupby(keys, as_index=False)["count"].sum()
                 if conf else pd.DataFrame(columns=list(CONFUSION_COLUMNS)))
    return pd.DataFrame(rows, columns=list(RESULT_COLUMNS)), confusion


def run_comparisons(sources: Sequence[tuple[str, Any]], tc: TransferConfig, *,
                    feature_kwargs: Mapping[str, Any] | None = None, split_seed: int = 0,
                    latency: bool | None = None, checked: bool = False,
                    progress: JobProgress | None = None, on_load=None,
                    parts=None) -> dict[str, dict]:
    """Run every (protocol, split, seed, model, input) of the comparison on several data
    sets, with one pool of ``tc.n_jobs`` worker processes for all of them.

    The jobs of all data sets form one queue: the next data set is loaded and its inputs
    built while the workers run the last jobs of the previous one, and no worker waits
    at a data set's end for the other's last job.

    Parameters
    ----------
    sources : sequence of (str, callable)
        Name of a data set (its ``dataset`` column) and a function returning it
        (xarray.Dataset, schema v1 with clean and/or disturbed windows and reference
        windows), called when its jobs come up; one data set is in memory at a time.
    tc : TransferConfig
        The comparison: ``runs`` and ``models`` (:meth:`TransferConfig.check`), ``protocols`` (a
        protocol without data, no clean or no disturbed windows, is skipped with a
        warning), ``seeds`` and ``cv_seeds``, ``k_shots``, ``finetune``, ``aux``,
        ``residual``, ``n_jobs`` (jobs in parallel processes; 1: in this process),
        ``threads_per_job``, ``latency_repeats`` and ``progress``.
    feature_kwargs : mapping, optional
        ``orders``, ``floor_rel`` of :func:`learn.inputs.features.extract_features`.
    split_seed : int
        Seed of the CV folds (the same folds for every model seed).
    latency : bool, optional
        Measure the inference latency (batch 1, one torch thread, on each model's
        device: :mod:`learn.studies.latency`) of every (model, input)
        on the first data set, before its jobs start; default ``tc.latency``.
    checked : bool
        ``tc`` has passed :meth:`TransferConfig.check` already (the task checks it before any
        work).
    progress : JobProgress, optional
        The progress line; default one over these data sets' :func:`planned_jobs`, shown
        when ``tc.progress``.
    on_load : callable, optional
        ``on_load(name, ds)`` when a data set is loaded (e.g. its separability), in the
        thread that hands out the jobs.
    parts : learn.transfer.task.CellParts, optional
        Finished cells kept on disk: ``load(name, cell)`` -> ``(rows, seconds)`` or None,
        ``save(name, cell, rows, seconds)`` (returns them as they will be read back),
        ``latency(name)`` and ``save_latency(name, table)``; a cell it holds is not run
        again (a stopped comparison resumes, the data sets of a job array meet).

    Returns
    -------
    dict of str to dict
        Per data set: ``results`` (DataFrame, :data:`RESULT_COLUMNS`), ``confusion``
        (DataFrame, :data:`CONFUSION_COLUMNS`, per split and seed), ``latency``
        (DataFrame: model, input, input_ms, model_ms; empty but for the first data
        set), ``run_s`` (DataFrame, :data:`RUN_TIME_COLUMNS`: wall and CPU time of every
        run in every job), ``input_s`` (building its inputs) and ``wall_s`` (the whole
        call, every data set).

    Raises
    ------
    ValueError
        For a bad ``tc`` (:meth:`TransferConfig.check`), an adaptation a run's model cannot
        take, or a k-shot split that would leak.
    """
    from joblib import Parallel

    if not checked:
        check_tree(tc, "transfer")
    latency = tc.latency if latency is None else latency
    t_all = time.perf_counter()
    own = progress is None
    if own:
        progress = JobProgress(planned_jobs(tc) * len(sources), tc.progress)
    got = {name: _Gathered() for name, _ in sources}
    jobs = _jobs(sources, tc, feature_kwargs, split_seed, latency, progress, got, on_load,
                 parts)
    if tc.n_jobs == 1:
        done = (f(*a, **kw) for f, a, kw in jobs)
    else:
        done = Parallel(n_jobs=tc.n_jobs, return_as="generator_unordered",
                        batch_size=1)(jobs)
    labels = {s.label: s for s in tc.runs}
    for name, c, (rows, seconds) in (r for job in done for r in job):
        if parts is not None:
            rows, seconds = parts.save(name, c, rows, seconds)
        _gather(got, labels, name, c, rows, seconds, progress)
    if own:
        progress.close()
    wall = time.perf_counter() - t_all
    out = {}
    for name, g in got.items():
        results, confusion = _tables(g.rows(), name)
        out[name] = {"results": results, "confusion": confusion,
                     "latency": g.latency if g.latency is not None else pd.DataFrame(),
                     "run_s": pd.DataFrame(g.rows(1), columns=list(RUN_TIME_COLUMNS)),
                     "input_s": g.input_s, "wall_s": wall}
    return out


def run_comparison(ds, tc: TransferConfig, *, dataset: str = "data", **kwargs) -> dict:
    """:func:`run_comparisons` on one data set ``ds`` (xarray.Dataset), named ``dataset``;
    keywords as there. Returns its dict."""
    return run_comparisons([(dataset, lambda: ds)], tc, **kwargs)[dataset]


def _inputs(ds, specs, tc: TransferConfig, disturbed: bool, feature_kwargs) -> dict:
    """Every input kind of the runs, on the clean or the disturbed windows."""
    cache: dict = {}  # the residual that the residual inputs share
    return {kind: build_input(ds, kind, aux=tuple(tc.aux), disturbed=disturbed,
                              feature_kwargs=dict(feature_kwargs or {}),
                              residual=tc.residual, cache=cache)
            for kind in sorted({s.input for s in specs})}
