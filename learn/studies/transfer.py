"""Deep learners and transfer to the unseen gear: the whole comparison in one task.

``swgsim-train -m experiment=transfer`` -> :func:`run_transfer`. For every data set of
``transfer.run_on`` (presets: the paper's protocol, a bench's, a robot joint's; generated
in ``transfer.data_root`` when missing), every evaluation protocol
(:data:`learn.studies.protocols.PROTOCOLS`, default the leave-one-gear-out one on disturbed
data), split and seed it trains each configured (model, input) run
(:class:`learn.studies.runs.RunSpec`) on the training windows and scores it; under the
leave-one-gear-out protocols it also

* adapts every run marked ``finetune`` with k labelled windows per class of the held-out
  gear, for each k in ``k_shots``: torch nets fine-tuned on all layers and on the last
  layer only, MiniRocket's ridge refitted (its kernels stay);
* runs the unsupervised adaptations: AdaBN for the torch nets (batch-norm statistics
  re-estimated on unlabelled target windows) and CORAL for feature models
  (:mod:`learn.learners.adapt`). Their unlabelled windows are the held-out gear's
  *healthy stream* (``adapt_windows`` healthy windows, whole healthy variants), what a
  real gear offers at commissioning, not the class-balanced k-shot pool.

The k-shot split and the healthy stream are :func:`learn.studies.kshot.kshot_split`; both
are removed from the evaluation windows of every run. Nothing in training, early stopping,
model choice or hyper-parameters sees an evaluation window: early stopping, where
enabled, splits the *source* gears; fine-tuning has a fixed step budget; MiniRocket's
ridge penalty stays the one chosen on the source windows. Model sizes, epochs and
kernels were set for the CPU budget on the earlier default data set, not on these.

Files in ``report_dir`` (default ``reports/transfer``): ``results.csv`` (one row per
run: :data:`RESULT_COLUMNS`, accuracy in 0..1), ``confusion.csv``
(:data:`CONFUSION_COLUMNS`, counts per split and seed),
``table.md`` (:func:`learn.reports.transfer_report.write_table`), ``accuracy_vs_k.png``,
``separability_<dataset>_<clean|disturbed>.png``, ``latency.csv``. One MLflow run per
(data set, protocol, model, input, k) with the per-split, per-seed accuracies, and a
parent run holding the report and the resolved config. """

from __future__ import annotations

import copy
import logging
import time
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field, replace
from typing import Any

import numpy as np
import pandas as pd

from learn.inputs.signals import ResidualSettings
from learn.studies.kshot import KShotSplit, check_no_leak, kshot_split
from learn.studies.protocols import ALL_PROTOCOLS, OOD_PROTOCOLS, window_groups
from learn.studies.runs import (
    ADAPT,
    RunRef,
    RunSpec,
    final_step,
    fit_with_groups,
    make_estimator,
    pre_transform,
    score,
)
from swgsim.datasets.config import DatasetConfig

log = logging.getLogger(__name__)

RESULT_COLUMNS = ("dataset", "protocol", "split", "model", "input", "k_shot", "seed",
                  "accuracy", "train_s", "n_test")
CONFUSION_COLUMNS = ("dataset", "protocol", "split", "seed", "model", "input", "k_shot",
                     "true", "predicted", "count")
#: Wall and CPU time [s] of one run (model, input) in one job: fit, adaptations, scoring.
RUN_TIME_COLUMNS = ("dataset", "protocol", "split", "seed", "model", "input", "seconds",
                    "cpu_s")
FT_MODES = ("all", "last")


# --------------------------------------------------------------------------- config


@dataclass
class FinetuneSettings:
    """Adaptation with k labelled target windows per class (and CORAL's ridge)."""

    modes: list[str] = field(default_factory=lambda: list(FT_MODES))  # torch nets
    steps: int = 50                 # fixed budget: no validation data exists on the target
    lr_all: float | None = None     # null: model lr / 10
    lr_last: float | None = None    # null: model lr
    replay: float = 1.0             # source windows per target window (batches, weights)
    coral_reg: float = 1.0          # CORAL's identity term


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
        Evaluation protocols (:data:`learn.reports.transfer_report.ALL_PROTOCOLS`).
    seeds, cv_seeds : list of int
        Model seeds and k-shot draws (leave-one-gear-out); model seeds of the CV
        protocols (null: ``seeds``).
    k_shots : list of int
        Labelled windows per class of the held-out gear, >= 0.
    adapt_windows : int
        Least number of windows of the held-out gear's healthy stream, the unlabelled
        target data of the unsupervised adaptations (whole healthy variants outside the
        k-shot pool, removed from the evaluation windows); 0: none (no run may adapt).
        60 = ten healthy passes over the paper grid's six operating points, about the
        size of the class-balanced pool the adaptations saw before (72 windows), so the
        rule changes what they see, not how much; it leaves 288 of a gear's 360 healthy
        windows of a kind for evaluation.
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
    latency, latency_repeats, progress : bool, int, bool
    report_dir : str
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
    latency: bool = True
    latency_repeats: int = 100
    progress: bool = True
    report_dir: str = "reports/transfer"
    models: dict[str, Any] = field(default_factory=dict)


def check_config(tc: TransferConfig) -> None:
    """Check ``transfer`` before any work.

    Raises
    ------
    ValueError
        One line naming the key (``transfer.<key>``) and what is allowed.
    """
    bad = [p for p in tc.protocols if p not in ALL_PROTOCOLS]
    if bad or not tc.protocols:
        raise ValueError(f"transfer.protocols: must list some of {ALL_PROTOCOLS}, got "
                         f"{list(tc.protocols)}")
    unknown = [d for d in tc.run_on if d not in tc.datasets]
    if unknown:
        raise ValueError(f"transfer.run_on: {unknown} not among transfer.datasets "
                         f"{sorted(tc.datasets)}")
    if len(set(tc.run_on)) != len(tc.run_on):
        raise ValueError(f"transfer.run_on must not repeat, got {list(tc.run_on)}")
    if not tc.seeds:
        raise ValueError("transfer.seeds: must list at least one seed")
    if any(int(k) < 0 for k in tc.k_shots) or 0 not in [int(k) for k in tc.k_shots]:
        raise ValueError(f"transfer.k_shots: must hold 0 and values >= 0, got "
                         f"{list(tc.k_shots)}")
    for key in ("n_jobs", "n_threads", "latency_repeats"):
        if int(getattr(tc, key)) < 1:
            raise ValueError(f"transfer.{key}: must be >= 1, got {getattr(tc, key)}")
    if int(tc.adapt_windows) < 0:
        raise ValueError(f"transfer.adapt_windows: must be >= 0, got {tc.adapt_windows}")
    _check_finetune(tc.finetune)
    _check_runs(tc)
    _check_targets(tc.targets)


def _check_finetune(ft: FinetuneSettings) -> None:
    if not float(ft.replay) > 0:
        raise ValueError(f"transfer.finetune.replay: must be > 0, got {ft.replay}")
    bad = [m for m in ft.modes if m not in FT_MODES]
    if bad:
        raise ValueError(f"transfer.finetune.modes: must be among {FT_MODES}, got {bad}")


def _check_runs(tc: TransferConfig) -> None:
    from learn.inputs.signals import INPUTS

    if not tc.runs:
        raise ValueError("transfer.runs: must list at least one {model, input}")
    for i, s in enumerate(tc.runs):
        if s.model not in tc.models:
            raise ValueError(f"transfer.runs[{i}].model: {s.model!r} not among "
                             f"transfer.models {sorted(tc.models)}")
        if s.input not in INPUTS:
            raise ValueError(f"transfer.runs[{i}].input: {s.input!r} not among {INPUTS}")
        if s.adapt not in (None, *ADAPT):
            raise ValueError(f"transfer.runs[{i}].adapt: must be one of {ADAPT} or null, "
                             f"got {s.adapt!r}")
        if s.adapt is not None and int(tc.adapt_windows) < 1:
            raise ValueError(f"transfer.runs[{i}].adapt: {s.adapt} needs unlabelled "
                             "target windows; set transfer.adapt_windows >= 1")
    pr = tc.primary
    if pr is not None and pr.label not in {s.label for s in tc.runs}:
        raise ValueError(f"transfer.primary: {pr.label} is not one of transfer.runs; name "
                         "one of them, or transfer.primary=null for none")


def _check_targets(targets: Mapping[str, TargetSpec]) -> None:
    for name, t in targets.items():
        if t.protocol not in ALL_PROTOCOLS:
            raise ValueError(f"transfer.targets.{name}.protocol: must be one of "
                             f"{ALL_PROTOCOLS}, got {t.protocol!r}")
        for k, v in {**t.accuracy, **t.recall}.items():
            if not 0.0 <= float(v) <= 1.0:
                raise ValueError(f"transfer.targets.{name}.{k}: a fraction in [0, 1], "
                                 f"got {v}")


# --------------------------------------------------------------------------- runs


class _Scorer:
    """Collects the result rows of one (model, input) run and its adaptations."""

    def __init__(self, spec: RunSpec, X, y, evaluation, seed: int):
        self.X_eval, self.y_eval = X[evaluation], y[evaluation]
        self.base = {"model": spec.model, "input": spec.input, "seed": seed,
                     "n_test": len(evaluation)}
        self.rows: list[dict] = []

    def add(self, model: str, k: int, m, seconds: float, pred=None) -> None:
        acc, conf = score(m, self.X_eval, self.y_eval, pred)
        self.rows.append({**self.base, "model": model, "k_shot": k, "accuracy": acc,
                          "train_s": seconds, "confusion": conf})


def _run_cell(spec: RunSpec, est, inp, train, evaluation, kshot: KShotSplit | None,
              k_shots: Sequence[int], ft: FinetuneSettings, seed: int):
    """Fit one (model, input) on ``train``; score it (and its adaptations) on
    ``evaluation``. Returns result rows (without data set, protocol and split; each with
    a ``confusion`` list) and the fitted estimator."""
    X, y = inp.X, inp.y
    groups = window_groups(inp.meta)
    t0 = time.perf_counter()
    fit_with_groups(est, X[train], y[train], groups[train])
    sc = _Scorer(spec, X, y, evaluation, seed)
    sc.add(spec.model, 0, est, time.perf_counter() - t0)
    if kshot is None:
        return sc.rows, est
    _adapt_unsupervised(sc, spec, est, X, y, train, kshot, ft)
    if not spec.finetune:
        return sc.rows, est
    ks = [k for k in k_shots if k > 0]
    if hasattr(final_step(est), "refit_head"):  # MiniRocket: the ridge only
        _refit_heads(sc, spec, est, X, y, train, evaluation, kshot, ks, ft)
    else:
        _fine_tune(sc, spec, est, X, y, train, kshot, ks, ft, seed)
    return sc.rows, est


def _adapt_unsupervised(sc: _Scorer, spec: RunSpec, est, X, y, train, kshot: KShotSplit,
                        ft: FinetuneSettings) -> None:
    """AdaBN (torch nets) or CORAL (feature models) on the held-out gear's healthy
    stream (``kshot.unlabelled``, labels unused)."""
    if spec.adapt == "adabn":
        if not hasattr(final_step(est), "adapt_bn"):
            raise ValueError(f"{spec.label}: AdaBN needs a torch net")
        t0 = time.perf_counter()
        m = copy.deepcopy(est)
        final_step(m).adapt_bn(pre_transform(m, X[kshot.unlabelled]))
        sc.add(f"{spec.model}+adabn", 0, m, time.perf_counter() - t0)
    elif spec.adapt == "coral":
        from learn.learners.adapt import CoralClassifier

        if X.ndim != 2:
            raise ValueError(f"{spec.label}: CORAL needs a feature input")
        t0 = time.perf_counter()
        m = CoralClassifier(est, reg=float(ft.coral_reg))
        m.fit(X[train], y[train], X[kshot.unlabelled])
        sc.add(f"{spec.model}+coral", 0, m, time.perf_counter() - t0)
    elif spec.adapt is not None:
        raise ValueError(f"adapt must be one of {ADAPT} or null, got {spec.adapt!r}")


def _refit_heads(sc: _Scorer, spec: RunSpec, est, X, y, train, evaluation,
                 kshot: KShotSplit, ks: Sequence[int], ft: FinetuneSettings) -> None:
    """MiniRocket: the ridge refitted on k shots per class, on cached kernel features."""
    net = final_step(est)
    t0 = time.perf_counter()
    f_src = net.transform(pre_transform(est, X[train]))
    cache_s = time.perf_counter() - t0
    f_eval = net.transform(pre_transform(est, X[evaluation]))
    for k in ks:
        shots = kshot.shots(k)
        t0 = time.perf_counter()
        m = copy.deepcopy(est)
        final_step(m).refit_head(pre_transform(m, X[shots]), y[shots], y_source=y[train],
                                 source_features=f_src, replay=float(ft.replay))
        seconds = cache_s + time.perf_counter() - t0
        sc.add(f"{spec.model}+ft_head", k, m, seconds, final_step(m).ridge_.predict(f_eval))


def _fine_tune(sc: _Scorer, spec: RunSpec, est, X, y, train, kshot: KShotSplit,
               ks: Sequence[int], ft: FinetuneSettings, seed: int) -> None:
    """Torch nets: fine-tuned on k shots per class, all layers and the last layer."""
    if not hasattr(final_step(est), "fine_tune"):
        raise ValueError(f"{spec.label}: k-shot adaptation needs a torch net or MiniRocket")
    replay = float(ft.replay)
    for mode in ft.modes:
        for k in ks:
            shots = kshot.shots(k)
            t0 = time.perf_counter()
            m = copy.deepcopy(est)
            lr = getattr(ft, f"lr_{mode}")
            final_step(m).fine_tune(
                pre_transform(m, X[shots]), y[shots], mode=mode, steps=int(ft.steps),
                lr=None if lr is None else float(lr),
                X_replay=pre_transform(m, X[train]) if replay > 0 else None,
                y_replay=y[train] if replay > 0 else None, replay=replay,
                random_state=seed * 1000 + k)
            sc.add(f"{spec.model}+ft_{mode}", k, m, time.perf_counter() - t0)


def _cell(protocol: str, split, seed: int, specs, model_cfgs, inputs, k_max: int,
          k_shots, ft: FinetuneSettings, adapt_windows: int,
          threads: int | None) -> tuple[list[dict], dict[str, tuple[float, float]]]:
    """Every (model, input) of one (protocol, split, seed): a unit of parallel work (a
    *job*). Returns the result rows and, by run label, the wall and CPU time of each run
    [s] (fit, adaptations, fine-tuning and scoring; CPU: this process's)."""
    if threads:
        import torch

        torch.set_num_threads(int(threads))
    meta = next(iter(inputs.values())).meta
    kshot, evaluation = None, split.test
    if protocol in OOD_PROTOCOLS:
        kshot = kshot_split(meta, split.test, k_max, seed, n_unlabelled=adapt_windows)
        evaluation = kshot.evaluation
        check_no_leak(meta, split.train, kshot)
    rows, seconds = [], {}
    for spec in specs:
        t0, c0 = time.perf_counter(), time.process_time()
        inp = inputs[spec.input]
        est = make_estimator(model_cfgs[spec.model], seed, inp.n_aux, spec.params)
        out, _ = _run_cell(spec, est, inp, split.train, evaluation, kshot, k_shots, ft, seed)
        for r in out:
            rows.append({"protocol": protocol, "split": split.name, **r})
        seconds[spec.label] = (time.perf_counter() - t0, time.process_time() - c0)
    return rows, seconds


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
    from learn.studies.protocols import protocol_splits

    cv_seeds = tc.seeds if tc.cv_seeds is None else tc.cv_seeds
    return [(p, sp, int(seed)) for p in protocols
            for sp in protocol_splits(meta, p, random_state=split_seed)
            for seed in (tc.seeds if p in OOD_PROTOCOLS else cv_seeds)]


class JobProgress:
    """One progress line over every job of the comparison, all data sets together: jobs
    done, jobs left and the time left estimated from the mean time per finished job; a
    log line per finished job (its data set, protocol, split and seed, the wall time of
    each run and their accuracies at k = 0).

    Parameters
    ----------
    total : int
        Jobs planned (:func:`planned_jobs` summed over the data sets); corrected with
        :meth:`adjust` when a data set turns out to have other splits.
    enabled : bool
        Show the progress line (the log lines are written either way).
    """

    def __init__(self, total: int, enabled: bool = True):
        from tqdm.auto import tqdm

        self.total, self.done, self.t0 = int(total), 0, time.perf_counter()
        self.bar = tqdm(total=self.total, desc="transfer", unit="job", smoothing=0.0,
                        disable=not enabled, bar_format=(
                            "{desc}: {percentage:3.0f}%|{bar}| {n_fmt}/{total_fmt} jobs "
                            "done{postfix} [{elapsed}, about {remaining} left]"))

    def adjust(self, delta: int) -> None:
        """Change the number of planned jobs by ``delta`` (a skipped protocol, a data set
        with more or fewer splits than planned)."""
        if delta:
            self.total += int(delta)
            self.bar.total = self.total
            self.bar.refresh()

    def finished(self, dataset: str, cell: tuple, seconds: Mapping[str, tuple],
                 rows: Sequence[dict]) -> None:
        """Count one finished job ``cell`` = (protocol, split, seed) and log it;
        ``seconds``: run label -> (wall, CPU) [s], ``rows``: its result rows."""
        self.done += 1
        left = max(self.total - self.done, 0)
        elapsed = time.perf_counter() - self.t0
        protocol, split, seed = cell[0], cell[1].name, cell[2]
        acc = {f"{r['model']}/{r['input']}": round(r["accuracy"], 4) for r in rows
               if r["k_shot"] == 0}
        log.info("job %d/%d done, %d left (about %.1f min): %s %s %s seed %d in %.1f s; "
                 "run seconds %s; accuracy at k = 0 %s", self.done, self.total, left,
                 elapsed / self.done * left / 60, dataset, protocol, split, seed,
                 sum(v[0] for v in seconds.values()),
                 {k: round(v[0], 1) for k, v in seconds.items()}, acc)
        self.bar.set_postfix_str(f", {left} left ({dataset})", refresh=False)
        self.bar.update(1)

    def close(self) -> None:
        self.bar.close()


def planned_jobs(tc: TransferConfig) -> int:
    """Jobs, (protocol, split, seed), that the comparison plans per data set: the splits
    each protocol plans (:attr:`learn.studies.protocols.ProtocolConfig.n_planned`) times
    its seeds."""
    from learn.studies.protocols import PROTOCOLS

    cv_seeds = tc.seeds if tc.cv_seeds is None else tc.cv_seeds
    return sum(PROTOCOLS[p].n_planned * len(tc.seeds if p in OOD_PROTOCOLS else cv_seeds)
               for p in tc.protocols)


def _run_cells(cells: list, specs, tc: TransferConfig, inputs, progress: JobProgress,
               dataset: str) -> tuple[list[dict], list[dict]]:
    """Every cell, in-process (``n_jobs`` 1) or in parallel processes. Returns the result
    rows and the wall time of every run of every cell (:data:`RUN_TIME_COLUMNS`)."""
    from joblib import Parallel, delayed

    k_shots = [int(k) for k in tc.k_shots]
    args = (specs, tc.models, inputs, max([0, *k_shots]), k_shots, tc.finetune,
            int(tc.adapt_windows))
    rows: list[dict] = []
    times: list[dict] = []

    def collect(c, out):
        cell_rows, seconds = out
        rows.extend(cell_rows)
        labels = {s.label: s for s in specs}
        times.extend({"dataset": dataset, "protocol": c[0], "split": c[1].name,
                      "seed": c[2], "model": labels[k].model, "input": labels[k].input,
                      "seconds": v[0], "cpu_s": v[1]} for k, v in seconds.items())
        progress.finished(dataset, c, seconds, cell_rows)

    if tc.n_jobs == 1:
        for c in cells:
            collect(c, _cell(*c, *args, None))
        return rows, times
    jobs = (delayed(_with_cell)(c, *args, tc.threads_per_job) for c in cells)
    for c, out in Parallel(n_jobs=tc.n_jobs, return_as="generator_unordered")(jobs):
        collect(c, out)
    return rows, times


def _with_cell(c: tuple, *args):
    """:func:`_cell` of ``c`` with ``c`` beside its result (results come back unordered)."""
    return c, _cell(*c, *args)


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


def run_comparison(ds, tc: TransferConfig, *, dataset: str = "data",
                   feature_kwargs: Mapping[str, Any] | None = None, split_seed: int = 0,
                   latency: bool | None = None, checked: bool = False,
                   progress: JobProgress | None = None) -> dict:
    """Run every (protocol, split, seed, model, input) of the comparison on one data set.

    Parameters
    ----------
    ds : xarray.Dataset
        Schema v1 with clean and/or disturbed windows and reference windows.
    tc : TransferConfig
        The comparison: ``runs`` and ``models`` (:func:`check_config`), ``protocols`` (a
        protocol without data, no clean or no disturbed windows, is skipped with a
        warning), ``seeds`` and ``cv_seeds``, ``k_shots``, ``finetune``, ``aux``,
        ``residual``, ``n_jobs`` ((protocol, split, seed) cells in parallel processes),
        ``threads_per_job``, ``latency_repeats`` and ``progress``.
    dataset : str
        Name written to the ``dataset`` column.
    feature_kwargs : mapping, optional
        ``orders``, ``floor_rel`` of :func:`learn.inputs.features.extract_features`.
    split_seed : int
        Seed of the CV folds (the same folds for every model seed).
    latency : bool, optional
        Measure the inference latency (CPU, batch 1, one thread) of every (model, input);
        default ``tc.latency``.
    checked : bool
        ``tc`` has passed :func:`check_config` already (the task checks it once per run,
        before any work, and runs one comparison per data set).
    progress : JobProgress, optional
        The progress line of a comparison over several data sets (it counts this data
        set's :func:`planned_jobs`); default: one of this data set's own, shown when
        ``tc.progress``.

    Returns
    -------
    dict
        ``results`` (DataFrame, :data:`RESULT_COLUMNS`), ``confusion`` (DataFrame,
        :data:`CONFUSION_COLUMNS`, per split and seed), ``latency`` (DataFrame:
        model, input, input_ms, model_ms), ``run_s`` (DataFrame,
        :data:`RUN_TIME_COLUMNS`: the wall time of every run in every job), ``wall_s``
        (total), ``input_s`` (building inputs).

    Raises
    ------
    ValueError
        For a bad ``tc`` (:func:`check_config`), an unknown adaptation, or a k-shot split
        that would leak.
    """
    if not checked:
        check_config(tc)
    specs = tc.runs
    latency = tc.latency if latency is None else latency
    t_all, input_s = time.perf_counter(), 0.0
    planned = planned_jobs(tc)  # jobs counted in progress and not yet run or adjusted
    own = progress is None
    progress = JobProgress(planned, tc.progress) if own else progress
    todo = _protocols_with_data(ds, tc.protocols)
    rows: list[dict] = []
    times: list[dict] = []
    lat = None
    for flag in (False, True):
        prots = [p for p in todo if p.endswith("disturbed") == flag]
        if not prots:
            continue
        t0 = time.perf_counter()
        inputs = _inputs(ds, specs, tc, flag, feature_kwargs)
        input_s += time.perf_counter() - t0
        cells = _cells_of(next(iter(inputs.values())).meta, prots, tc, split_seed)
        n_plan = planned_jobs(replace(tc, protocols=prots))
        progress.adjust(len(cells) - n_plan)
        planned -= n_plan
        r, t = _run_cells(cells, specs, tc, inputs, progress, dataset)
        rows += r
        times += t
        if latency and lat is None:  # once, while this flag's inputs are in memory
            from learn.studies.latency import measure_latency

            lat = measure_latency(ds, specs, tc.models, inputs, aux=tc.aux,
                                  feature_kwargs=feature_kwargs,
                                  residual=tc.residual,
                                  repeats=tc.latency_repeats)
        del inputs
    progress.adjust(-planned)  # protocols without data
    if own:
        progress.close()
    results, confusion = _tables(rows, dataset)
    return {"results": results, "confusion": confusion,
            "latency": lat if lat is not None else pd.DataFrame(),
            "run_s": pd.DataFrame(times, columns=list(RUN_TIME_COLUMNS)),
            "wall_s": time.perf_counter() - t_all, "input_s": input_s}


def _inputs(ds, specs, tc: TransferConfig, disturbed: bool, feature_kwargs) -> dict:
    """Every input kind of the runs, on the clean or the disturbed windows."""
    from learn.inputs.signals import build_input

    return {kind: build_input(ds, kind, aux=tuple(tc.aux), disturbed=disturbed,
                              feature_kwargs=dict(feature_kwargs or {}),
                              residual=tc.residual)
            for kind in sorted({s.input for s in specs})}
