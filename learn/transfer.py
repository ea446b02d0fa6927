"""Deep learners and transfer to the unseen gear: the whole comparison in one task.

``swgsim-train -m experiment=transfer`` -> :func:`run_transfer`. For every data set of
``transfer.run_on`` (presets: the paper's protocol, a bench's, a robot joint's; generated
in ``transfer.data_root`` when missing), every evaluation protocol
(:data:`learn.protocols.PROTOCOLS`, default the leave-one-gear-out one on disturbed
data), split and seed it trains each configured (model, input) run
(:class:`learn.runs.RunSpec`) on the training windows and scores it; under the
leave-one-gear-out protocols it also

* adapts every run marked ``finetune`` with k labelled windows per class of the held-out
  gear, for each k in ``k_shots``: torch nets fine-tuned on all layers and on the last
  layer only, MiniRocket's ridge refitted (its kernels stay);
* runs the unsupervised adaptations: AdaBN for the torch nets (batch-norm statistics
  re-estimated on unlabelled target windows) and CORAL for feature models
  (:mod:`learn.adapt`).

The k-shot split is :func:`learn.kshot.kshot_split`. Nothing in training, early stopping,
model choice or hyper-parameters sees an evaluation window: early stopping, where
enabled, splits the *source* gears; fine-tuning has a fixed step budget; MiniRocket's
ridge penalty stays the one chosen on the source windows. Model sizes, epochs and
kernels were set for the CPU budget on the earlier default data set, not on these.

Files in ``report_dir`` (default ``reports/transfer``): ``results.csv`` (one row per
run: :data:`RESULT_COLUMNS`, accuracy in 0..1), ``confusion.csv``
(:data:`learn.transfer_report.CONFUSION_COLUMNS`, counts summed over splits and seeds),
``table.md`` (:func:`learn.transfer_report.write_table`), ``accuracy_vs_k.png``,
``separability_<dataset>_<clean|disturbed>.png``, ``latency.csv``. One MLflow run per
(data set, protocol, model, input, k) with the per-split, per-seed accuracies, and a
parent run holding the report and the resolved config. """

from __future__ import annotations

import copy
import logging
import os
import time
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np
import pandas as pd

from learn.inputs import ResidualSettings
from learn.kshot import KShotSplit, check_no_leak, kshot_split
from learn.runs import (
    ADAPT,
    RunSpec,
    final_step,
    fit_with_groups,
    make_estimator,
    pre_transform,
    score,
    specs_from_config,
)
from learn.transfer_report import ALL_PROTOCOLS, CONFUSION_COLUMNS, OOD_PROTOCOLS
from swgsim.config import DatasetConfig

log = logging.getLogger(__name__)

RESULT_COLUMNS = ("dataset", "protocol", "split", "model", "input", "k_shot", "seed",
                  "accuracy", "train_s", "n_test")
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
        Evaluation protocols (:data:`learn.transfer_report.ALL_PROTOCOLS`).
    seeds, cv_seeds : list of int
        Model seeds and k-shot draws (leave-one-gear-out); model seeds of the CV
        protocols (null: ``seeds``).
    k_shots : list of int
        Labelled windows per class of the held-out gear, >= 0.
    aux : list of str
        Scalars appended to the signal inputs (:data:`learn.inputs.AUX`).
    residual : ResidualSettings
        Settings of the residual inputs.
    finetune : FinetuneSettings
    runs : list of mapping
        ``{model, input, finetune, adapt, params}`` each (:class:`learn.runs.RunSpec`).
    primary : dict
        ``{model, input}`` declared before the comparison (reported beside the best);
        empty: none.
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
    aux: list[str] = field(default_factory=lambda: ["eta2_rel", "eta_rel"])
    residual: ResidualSettings = field(default_factory=ResidualSettings)
    finetune: FinetuneSettings = field(default_factory=FinetuneSettings)
    runs: list[Any] = field(default_factory=list)
    primary: dict[str, str] = field(default_factory=dict)
    targets: dict[str, TargetSpec] = field(default_factory=dict)
    n_threads: int = 1
    n_jobs: int = 2
    threads_per_job: int | None = 1
    latency: bool = True
    latency_repeats: int = 100
    progress: bool = True
    report_dir: str = "reports/transfer"
    models: dict[str, Any] = field(default_factory=dict)


def check_config(tc: Mapping[str, Any]) -> list[RunSpec]:
    """Check ``transfer`` before any work; return the runs.

    Raises
    ------
    ValueError
        One line naming the key (``transfer.<key>``) and what is allowed.
    """
    from learn.inputs import INPUTS

    bad = [p for p in tc["protocols"] if p not in ALL_PROTOCOLS]
    if bad or not tc["protocols"]:
        raise ValueError(f"transfer.protocols: must list some of {ALL_PROTOCOLS}, got "
                         f"{list(tc['protocols'])}")
    unknown = [d for d in tc["run_on"] if d not in tc["datasets"]]
    if unknown:
        raise ValueError(f"transfer.run_on: {unknown} not among transfer.datasets "
                         f"{sorted(tc['datasets'])}")
    if len(set(tc["run_on"])) != len(tc["run_on"]):
        raise ValueError(f"transfer.run_on must not repeat, got {list(tc['run_on'])}")
    if not tc["seeds"]:
        raise ValueError("transfer.seeds: must list at least one seed")
    if any(int(k) < 0 for k in tc["k_shots"]) or 0 not in [int(k) for k in tc["k_shots"]]:
        raise ValueError(f"transfer.k_shots: must hold 0 and values >= 0, got "
                         f"{list(tc['k_shots'])}")
    for key in ("n_jobs", "n_threads", "latency_repeats"):
        if int(tc[key]) < 1:
            raise ValueError(f"transfer.{key}: must be >= 1, got {tc[key]}")
    if not float(tc["finetune"]["replay"]) > 0:
        raise ValueError(f"transfer.finetune.replay: must be > 0, got "
                         f"{tc['finetune']['replay']}")
    bad = [m for m in tc["finetune"]["modes"] if m not in FT_MODES]
    if bad:
        raise ValueError(f"transfer.finetune.modes: must be among {FT_MODES}, got {bad}")
    specs = specs_from_config(tc["runs"])
    if not specs:
        raise ValueError("transfer.runs: must list at least one {model, input}")
    for i, s in enumerate(specs):
        if s.model not in tc["models"]:
            raise ValueError(f"transfer.runs[{i}].model: {s.model!r} not among "
                             f"transfer.models {sorted(tc['models'])}")
        if s.input not in INPUTS:
            raise ValueError(f"transfer.runs[{i}].input: {s.input!r} not among {INPUTS}")
    pr = tc.get("primary") or {}
    if pr and (pr.get("model"), pr.get("input")) not in {(s.model, s.input) for s in specs}:
        raise ValueError(f"transfer.primary: {pr} is not one of transfer.runs; name one "
                         "of them, or transfer.primary={} for none")
    for name, t in (tc.get("targets") or {}).items():
        if t["protocol"] not in ALL_PROTOCOLS:
            raise ValueError(f"transfer.targets.{name}.protocol: must be one of "
                             f"{ALL_PROTOCOLS}, got {t['protocol']!r}")
        for k, v in {**t["accuracy"], **t["recall"]}.items():
            if not 0.0 <= float(v) <= 1.0:
                raise ValueError(f"transfer.targets.{name}.{k}: a fraction in [0, 1], "
                                 f"got {v}")
    return specs


# --------------------------------------------------------------------------- runs


def _run_cell(spec: RunSpec, est, inp, train, evaluation, kshot: KShotSplit | None,
              k_shots: Sequence[int], ft: Mapping[str, Any], seed: int):
    """Fit one (model, input) on ``train``; score it (and its adaptations) on
    ``evaluation``. Returns result rows (without data set, protocol and split; each with
    a ``confusion`` list) and the fitted estimator."""
    X, y = inp.X, inp.y
    rows = []
    groups = (inp.meta["gear"].astype(str) + ":" + inp.meta["fault"].astype(str) + ":"
              + inp.meta["variant"].astype(str)).to_numpy()
    t0 = time.perf_counter()
    fit_with_groups(est, X[train], y[train], groups[train])
    train_s = time.perf_counter() - t0
    base = {"model": spec.model, "input": spec.input, "seed": seed, "n_test": len(evaluation)}

    def add(model, k, m, seconds, pred=None):
        acc, conf = score(m, X[evaluation], y[evaluation], pred)
        rows.append({**base, "model": model, "k_shot": k, "accuracy": acc, "train_s": seconds,
                     "confusion": conf})

    add(spec.model, 0, est, train_s)
    if kshot is None:
        return rows, est
    net = final_step(est)
    if spec.adapt == "adabn":
        if not hasattr(net, "adapt_bn"):
            raise ValueError(f"{spec.label}: AdaBN needs a torch net")
        t0 = time.perf_counter()
        m = copy.deepcopy(est)
        final_step(m).adapt_bn(pre_transform(m, X[kshot.pool]))
        add(f"{spec.model}+adabn", 0, m, time.perf_counter() - t0)
    elif spec.adapt == "coral":
        from learn.adapt import CoralClassifier

        if X.ndim != 2:
            raise ValueError(f"{spec.label}: CORAL needs a feature input")
        t0 = time.perf_counter()
        m = CoralClassifier(est, reg=float(ft.get("coral_reg", 1.0)))
        m.fit(X[train], y[train], X[kshot.pool])
        add(f"{spec.model}+coral", 0, m, time.perf_counter() - t0)
    elif spec.adapt is not None:
        raise ValueError(f"adapt must be one of {ADAPT} or null, got {spec.adapt!r}")
    if not spec.finetune:
        return rows, est
    replay = float(ft.get("replay", 1.0))
    ks = [k for k in k_shots if k > 0]
    if hasattr(net, "refit_head"):  # MiniRocket: the ridge only, on cached features
        t0 = time.perf_counter()
        f_src = net.transform(pre_transform(est, X[train]))
        cache_s = time.perf_counter() - t0
        f_eval = net.transform(pre_transform(est, X[evaluation]))
        for k in ks:
            shots = kshot.shots(k)
            t0 = time.perf_counter()
            m = copy.deepcopy(est)
            final_step(m).refit_head(pre_transform(m, X[shots]), y[shots], y_source=y[train],
                                     source_features=f_src, replay=replay)
            seconds = cache_s + time.perf_counter() - t0
            add(f"{spec.model}+ft_head", k, m, seconds, final_step(m).ridge_.predict(f_eval))
        return rows, est
    if not hasattr(net, "fine_tune"):
        raise ValueError(f"{spec.label}: k-shot adaptation needs a torch net or MiniRocket")
    for mode in ft.get("modes", FT_MODES):
        for k in ks:
            shots = kshot.shots(k)
            t0 = time.perf_counter()
            m = copy.deepcopy(est)
            lr = ft.get(f"lr_{mode}")
            final_step(m).fine_tune(
                pre_transform(m, X[shots]), y[shots], mode=mode,
                steps=int(ft.get("steps", 100)), lr=None if lr is None else float(lr),
                X_replay=pre_transform(m, X[train]) if replay > 0 else None,
                y_replay=y[train] if replay > 0 else None, replay=replay,
                random_state=seed * 1000 + k)
            add(f"{spec.model}+ft_{mode}", k, m, time.perf_counter() - t0)
    return rows, est


def _cell(protocol: str, split, seed: int, specs, model_cfgs, inputs, k_max: int,
          k_shots, ft, threads: int | None) -> list[dict]:
    """Every (model, input) of one (protocol, split, seed): a unit of parallel work."""
    if threads:
        import torch

        torch.set_num_threads(int(threads))
    meta = next(iter(inputs.values())).meta
    kshot, evaluation = None, split.test
    if protocol in OOD_PROTOCOLS:
        kshot = kshot_split(meta, split.test, k_max, seed)
        evaluation = kshot.evaluation
        check_no_leak(meta, split.train, kshot)
    rows = []
    for spec in specs:
        inp = inputs[spec.input]
        est = make_estimator(model_cfgs[spec.model], seed, inp.n_aux, dict(spec.params))
        out, _ = _run_cell(spec, est, inp, split.train, evaluation, kshot, k_shots, ft, seed)
        for r in out:
            rows.append({"protocol": protocol, "split": split.name, **r})
        log.info("%s %s seed %d %s: %s", protocol, split.name, seed, spec.label,
                 [round(r["accuracy"], 4) for r in out])
    return rows


def run_comparison(
    ds,
    specs: Sequence[RunSpec],
    model_cfgs: Mapping[str, Mapping[str, Any]],
    *,
    dataset: str = "data",
    protocols: Sequence[str] = ("ood_disturbed",),
    seeds: Sequence[int] = (0, 1, 2, 3, 4),
    cv_seeds: Sequence[int] | None = None,
    k_shots: Sequence[int] = (0, 1, 5, 10),
    finetune: Mapping[str, Any] | None = None,
    aux: Sequence[str] = ("eta2_rel", "eta_rel"),
    feature_kwargs: Mapping[str, Any] | None = None,
    residual: Mapping[str, Any] | None = None,
    split_seed: int = 0,
    n_jobs: int = 1,
    threads_per_job: int | None = None,
    latency: bool = True,
    latency_repeats: int = 100,
    progress: bool = True,
) -> dict:
    """Run every (protocol, split, seed, model, input) of the comparison on one data set.

    Parameters
    ----------
    ds : xarray.Dataset
        Schema v1 with clean and/or disturbed windows and reference windows.
    specs : sequence of RunSpec
    model_cfgs : mapping
        Model name -> config with ``_target_`` (``conf/model/*.yaml``).
    dataset : str
        Name written to the ``dataset`` column.
    protocols : sequence of str
        Among :data:`ALL_PROTOCOLS`; a protocol without data (no clean or no disturbed
        windows) is skipped with a warning.
    seeds : sequence of int
        Model seeds (and k-shot draws) of the leave-one-gear-out protocols.
    cv_seeds : sequence of int, optional
        Model seeds of the CV protocols; default ``seeds``. The folds themselves are fixed
        by ``split_seed`` so that a split name means the same windows for every seed.
    k_shots : sequence of int
        Labelled target windows per class; 0 = none.
    finetune : mapping, optional
        :class:`FinetuneSettings` as a mapping.
    aux : sequence of str
        Scalars appended to the signal inputs (:data:`learn.inputs.AUX`).
    feature_kwargs : mapping, optional
        ``orders``, ``floor_rel`` of :func:`learn.features.extract_features`.
    residual : mapping, optional
        Settings of the residual inputs (:data:`learn.inputs.RESIDUAL_DEFAULTS`).
    split_seed : int
        Seed of the CV folds.
    n_jobs : int
        (protocol, split, seed) cells run in parallel processes (joblib); 1: in-process.
    threads_per_job : int, optional
        Torch threads in each parallel process (default: leave torch's setting).
    latency : bool
        Measure the inference latency (CPU, batch 1, one thread) of every (model, input).
    latency_repeats : int
    progress : bool
        tqdm progress bar over cells.

    Returns
    -------
    dict
        ``results`` (DataFrame, :data:`RESULT_COLUMNS`), ``confusion`` (DataFrame,
        :data:`CONFUSION_COLUMNS`, summed over splits and seeds), ``latency`` (DataFrame:
        model, input, input_ms, model_ms), ``wall_s`` (total), ``input_s`` (building
        inputs).

    Raises
    ------
    ValueError
        For an unknown protocol, model or adaptation, or a k-shot split that would leak.
    """
    from joblib import Parallel, delayed
    from tqdm.auto import tqdm

    from learn.inputs import build_input
    from learn.latency import measure_latency
    from learn.protocols import protocol_splits

    bad = set(protocols) - set(ALL_PROTOCOLS)
    if bad:
        raise ValueError(f"protocols must be among {ALL_PROTOCOLS}, got {sorted(bad)}")
    missing = {s.model for s in specs} - set(model_cfgs)
    if missing:
        raise ValueError(f"no model config for {sorted(missing)}")
    ft = dict(finetune or {})
    cv_seeds = list(seeds if cv_seeds is None else cv_seeds)
    k_max = max([0, *k_shots])
    t_all = time.perf_counter()
    input_s = 0.0
    rows: list[dict] = []
    present = set(np.unique(ds["disturbed"].values.astype(bool)).tolist())
    todo = [p for p in protocols if p.endswith("disturbed") in present]
    if len(todo) < len(protocols):
        log.warning("skipping protocols without data: %s", sorted(set(protocols) - set(todo)))
    n_cells = sum((3 if p in OOD_PROTOCOLS else 4) * len(seeds if p in OOD_PROTOCOLS
                                                          else cv_seeds) for p in todo)
    bar = tqdm(total=n_cells, desc=f"transfer {dataset}", unit="cell",
               disable=not progress)
    kinds = sorted({s.input for s in specs})
    lat = None
    for flag in (False, True):
        prots = [p for p in todo if p.endswith("disturbed") == flag]
        if not prots:
            continue
        t0 = time.perf_counter()
        inputs = {kind: build_input(ds, kind, aux=tuple(aux), disturbed=flag,
                                    feature_kwargs=dict(feature_kwargs or {}),
                                    residual=dict(residual or {})) for kind in kinds}
        input_s += time.perf_counter() - t0
        meta = next(iter(inputs.values())).meta
        cells = []
        for p in prots:
            ood = p in OOD_PROTOCOLS
            for sp in protocol_splits(meta, p, random_state=split_seed):
                for seed in (seeds if ood else cv_seeds):
                    cells.append((p, sp, int(seed)))
        if n_jobs == 1:
            for c in cells:
                bar.set_description(f"{dataset} {c[0]} {c[1].name} seed {c[2]}")
                rows += _cell(*c, specs, model_cfgs, inputs, k_max, k_shots, ft, None)
                bar.update(1)
        else:
            jobs = (delayed(_cell)(*c, specs, model_cfgs, inputs, k_max, k_shots, ft,
                                   threads_per_job) for c in cells)
            for out in Parallel(n_jobs=n_jobs, return_as="generator_unordered")(jobs):
                rows += out
                bar.update(1)
        if latency and lat is None:  # once, while this flag's inputs are in memory
            lat = measure_latency(ds, specs, model_cfgs, inputs, aux=aux,
                                  feature_kwargs=feature_kwargs, residual=residual,
                                  repeats=latency_repeats)
        del inputs
    bar.close()
    for r in rows:
        r["dataset"] = dataset
    conf = [{"dataset": dataset, "protocol": r["protocol"], "model": r["model"],
             "input": r["input"], "k_shot": r["k_shot"], "true": t, "predicted": p,
             "count": c} for r in rows for t, p, c in r["confusion"]]
    keys = list(CONFUSION_COLUMNS[:-1])
    confusion = (pd.DataFrame(conf).groupby(keys, as_index=False)["count"].sum()
                 if conf else pd.DataFrame(columns=list(CONFUSION_COLUMNS)))
    return {"results": pd.DataFrame(rows, columns=list(RESULT_COLUMNS)),
            "confusion": confusion, "latency": lat if lat is not None else pd.DataFrame(),
            "wall_s": time.perf_counter() - t_all, "input_s": input_s}


# --------------------------------------------------------------------------- task


def _data_sets(cfg, tc: Mapping[str, Any], progress: bool) -> tuple[list[tuple], float]:
    """(name, path) of every data set to run on, generating the missing ones."""
    from hydra.utils import to_absolute_path

    from swgsim.generate import generate, plan

    if not tc["run_on"]:
        return [(str(cfg.data.get("name") or Path(cfg.data.path).name),
                 str(cfg.data.path))], 0.0
    for name in tc["run_on"]:  # every data-set config is checked before any work
        try:
            plan(tc["datasets"][name])
        except ValueError as e:
            raise ValueError(f"transfer.datasets.{name}: {e}") from None
    try:
        root = to_absolute_path(str(tc["data_root"]))
    except ValueError:  # outside a Hydra run
        root = str(tc["data_root"])
    out, t0 = [], time.perf_counter()
    for name in tc["run_on"]:
        path = f"{root}/{name}"
        g = generate(tc["datasets"][name], path, n_jobs=int(tc["n_jobs"]), overwrite=True,
                     progress=progress)
        if g["computed"]:
            log.info("data set %s: %d shard(s) simulated in %s", name, len(g["computed"]),
                     path)
        out.append((name, path))
    return out, time.perf_counter() - t0


def print_summary(targets: pd.DataFrame, report_dir: Path, wall_s: float, device: str) -> None:
    """Print the targets (reached, observable) and where the report went."""
    if len(targets):
        print("\ntargets (worst split or recall, k labelled target windows per class):")
        for r in targets.itertuples():
            obs = "" if np.isnan(r.observable) else f", observable {100 * r.observable:.1f} %"
            print(f"  {r.dataset:<12s} {r.condition:<36s} target {100 * r.target:5.1f} %  "
                  f"reached {100 * r.reached:6.2f} % ({r.who}: {r.run}){obs}")
    print(f"report: {report_dir}/table.md (+ results.csv, confusion.csv, figures); "
          f"{wall_s / 60:.1f} min on {device}")


def _device() -> str:
    import torch

    if torch.cuda.is_available():
        return f"GPU {torch.cuda.get_device_name(0)}"
    return "CPU"


def run_transfer(cfg) -> dict:
    """Task ``transfer``: the whole comparison over the data sets, report and MLflow.

    Reads ``cfg.transfer`` (:class:`TransferConfig`, ``conf/experiment/transfer.yaml``),
    ``cfg.data`` (when ``transfer.run_on`` is empty), ``cfg.features`` (orders, floor),
    ``cfg.logger`` (None: no tracking) and ``cfg.seed`` (CV folds).

    Returns
    -------
    dict
        ``report_dir``, ``files``, ``wall_s``, ``n_runs``, ``worst_split`` (per data set,
        ood_disturbed worst-split mean accuracy per model/input/k), ``targets`` (rows of
        :func:`learn.transfer_report.target_table`), ``run_id`` (parent MLflow run).

    Raises
    ------
    ValueError
        A bad ``transfer`` key (before any work).
    """
    import torch
    from omegaconf import OmegaConf

    from learn.features import FeatureSettings
    from learn.separability import plot_separability, separations, summary_table
    from learn.transfer_report import (
        class_recall,
        log_transfer,
        plot_accuracy_vs_k,
        summarise,
        target_table,
        write_table,
    )
    from swgsim.data import load

    tc = OmegaConf.to_container(cfg.transfer, resolve=True)
    specs = check_config(tc)
    if tc.get("n_threads"):
        torch.set_num_threads(int(tc["n_threads"]))
    feature_kwargs = FeatureSettings.of(cfg.get("features")).kwargs()
    progress = bool(tc.get("progress", True))
    t_all = time.perf_counter()
    data_sets, generate_s = _data_sets(cfg, tc, progress)
    report_dir = Path(tc.get("report_dir") or Path(cfg.paths.report_dir) / "transfer")
    report_dir.mkdir(parents=True, exist_ok=True)
    results, confusion, latency, sep_tabs, files = [], [], None, {}, {}
    input_s = 0.0
    ratio = float((tc.get("residual") or {}).get("ratio", 100.0))
    for name, path in data_sets:
        ds = load(path)
        log.info("transfer: %s, %d windows from %s, %d runs", name, ds.sizes["sample"], path,
                 len(specs))
        out = run_comparison(
            ds, specs, tc["models"], dataset=name, protocols=list(tc["protocols"]),
            seeds=list(tc["seeds"]), cv_seeds=tc.get("cv_seeds"),
            k_shots=[int(k) for k in tc["k_shots"]], finetune=tc["finetune"],
            aux=list(tc["aux"]), feature_kwargs=feature_kwargs,
            residual=tc.get("residual") or None, split_seed=int(cfg.get("seed", 0)),
            n_jobs=int(tc["n_jobs"]), threads_per_job=tc.get("threads_per_job"),
            latency=bool(tc["latency"]) and latency is None,
            latency_repeats=int(tc["latency_repeats"]), progress=progress)
        results.append(out["results"])
        confusion.append(out["confusion"])
        input_s += out["input_s"]
        if len(out["latency"]):
            latency = out["latency"]
        sep_tabs[name] = {}
        for kind in ("clean", "disturbed"):
            if not (ds["disturbed"].values.astype(bool) == (kind == "disturbed")).any():
                continue
            sep = separations(ds, disturbed=kind == "disturbed", ratio=ratio)
            if "healthy" not in sep:
                continue
            sep_tabs[name][kind] = summary_table(sep)
            files[f"separability_{name}_{kind}"] = plot_separability(
                sep, report_dir / f"separability_{name}_{kind}.png",
                f"Class separability, data set {name} ({kind} windows)")
        del ds
    res = pd.concat(results, ignore_index=True)
    conf = pd.concat(confusion, ignore_index=True)
    wall = time.perf_counter() - t_all
    n_jobs = int(tc["n_jobs"])
    timings = {"wall_s": wall, "input_s": input_s, "generate_s": generate_s,
               "threads": f"{n_jobs} process(es) x {tc.get('threads_per_job') or 'default'} "
                          f"torch thread(s)" if n_jobs > 1 else
                          f"1 process x {torch.get_num_threads()} torch thread(s)",
               "cpus": os.cpu_count(), "device": _device()}
    files["results"] = report_dir / "results.csv"
    res.to_csv(files["results"], index=False)
    files["confusion"] = report_dir / "confusion.csv"
    conf.to_csv(files["confusion"], index=False)
    if latency is not None and len(latency):
        files["latency"] = report_dir / "latency.csv"
        latency.to_csv(files["latency"], index=False)
    targets = {d: t for d, t in (tc.get("targets") or {}).items()
               if d in set(res["dataset"])}
    files["table"] = write_table(res, conf, report_dir / "table.md", targets=targets,
                                 primary=tc.get("primary"), separability=sep_tabs,
                                 latency=latency, timings=timings)
    files["figure"] = plot_accuracy_vs_k(res, report_dir / "accuracy_vs_k.png",
                                         targets=targets, separability=sep_tabs)
    summ = summarise(res)
    w = summ[(summ["protocol"] == "ood_disturbed") & (summ["split"] == "worst")]
    worst = {f"{r.dataset}/{r.model}/{r.input}/k{int(r.k_shot)}": float(r.mean)
             for r in w.itertuples()}
    tt = (target_table(summ, class_recall(conf), targets, tc.get("primary"), sep_tabs)
          if len(conf) else pd.DataFrame())
    run_id = None
    if cfg.get("logger") is not None:
        run_id = log_transfer(res, files, cfg, timings, latency)
    log.info("transfer report in %s (%.1f min)", report_dir, wall / 60)
    if progress:  # the console's summary (the log holds every cell)
        print_summary(tt, report_dir, wall, timings["device"])
    return {"task": "transfer", "report_dir": str(report_dir),
            "files": {k: str(v) for k, v in files.items()}, "wall_s": wall,
            "n_runs": len(res), "worst_split": worst,
            "targets": tt.to_dict("records"), "run_id": run_id}
