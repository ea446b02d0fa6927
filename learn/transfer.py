"""Deep learners and transfer to the unseen gear: the whole comparison in one task.

``swgsim-train -m experiment=transfer`` -> :func:`run_transfer`. For every protocol
(:data:`learn.protocols.PROTOCOLS`), split and seed it trains each configured
(model, input) pair on the training windows and scores it; under the leave-one-gear-out
protocols it also

* fine-tunes every torch net marked ``finetune`` on k labelled windows per class of the
  held-out gear, all layers and last layer only, for each k in ``k_shots``;
* runs the unsupervised domain-adaptation baselines: AdaBN for the torch nets (batch-norm
  statistics re-estimated on unlabelled target windows) and CORAL for feature models
  (source features re-coloured with the target covariance).

The k-shot split (:func:`kshot_split`). For the held-out gear a seeded draw picks, per
class, whole fault *variants* until they hold at least ``max(k_shots)`` windows: the
*pool*. The k labelled windows of a class are the first k of a seeded permutation of
its pool windows (so the k = 1 windows are among the k = 5 ones). Every model, k = 0
included, is evaluated on the same remaining windows of the gear (other variants),
so accuracies are comparable across k; the pool's windows (labels dropped) are also the
unlabelled target data of AdaBN and CORAL. Nothing in training, early stopping, model
choice or hyper-parameters sees an evaluation window: early stopping, where enabled,
splits the *source* gears; fine-tuning has a fixed step budget.

Files in ``report_dir`` (default ``reports/transfer``): ``results.csv`` (one row per run:
protocol, split, model, input, k_shot, seed, accuracy in 0..1, train_s, n_test),
``table.md`` (per protocol and split plus the worst split, mean ± std over seeds; the
targets; a diagnosis of the main confusions; latency; training time),
``accuracy_vs_k.png``, ``confusion.csv`` (true x predicted counts per protocol, model,
input and k, summed over splits and seeds), ``latency.csv``. One MLflow run per
(protocol, model, input, k) with the per-split, per-seed accuracies, and a parent run
holding the report and the resolved config.

Cost: the (protocol, split, seed) cells run in ``n_jobs`` processes; the default grid
(``conf/experiment/transfer.yaml``, 38 cells, 12 model/input pairs) takes a few hours on
two CPU cores, most of it MiniRocket and the CNNs on the 1200-sample raw signals.
"""

from __future__ import annotations

import copy
import logging
import os
import time
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np
import pandas as pd
from sklearn.base import clone
from sklearn.pipeline import Pipeline

from learn.separability import plot_separability, separations, summary_table

log = logging.getLogger(__name__)

RESULT_COLUMNS = ("protocol", "split", "model", "input", "k_shot", "seed", "accuracy",
                  "train_s", "n_test")
OOD_PROTOCOLS = ("ood_clean", "ood_disturbed")
ALL_PROTOCOLS = ("cv_clean", "cv_disturbed", "ood_clean", "ood_disturbed")
FT_MODES = ("all", "last")
ADAPT = ("adabn", "coral")


# --------------------------------------------------------------------------- k-shot split


@dataclass(frozen=True)
class KShotSplit:
    """Labelled pool and evaluation windows of a held-out gear.

    Attributes
    ----------
    pool : ndarray of int
        Positions (rows of the input) of the windows set aside for fine-tuning.
    evaluation : ndarray of int
        Positions of the windows every model is scored on: the gear's other windows.
    order : dict of str to ndarray of int
        Per class, the pool positions in draw order.
    pool_groups : set of (str, int)
        (fault, variant) of the pool.
    """

    pool: np.ndarray
    evaluation: np.ndarray
    order: dict[str, np.ndarray]
    pool_groups: frozenset

    def shots(self, k: int) -> np.ndarray:
        """Positions of the k labelled windows per class (nested in k)."""
        if k <= 0:
            return np.array([], dtype=np.int64)
        short = [c for c, o in self.order.items() if len(o) < k]
        if short:
            raise ValueError(f"the pool holds fewer than k={k} windows of classes {short}")
        return np.sort(np.concatenate([o[:k] for o in self.order.values()]))


def kshot_split(meta: pd.DataFrame, target: np.ndarray, k_max: int, seed: int) -> KShotSplit:
    """Split the windows of a held-out gear into a labelled pool and evaluation windows.

    Parameters
    ----------
    meta : pandas.DataFrame
        Per-window metadata (columns ``fault``, ``variant``), rows = input positions.
    target : ndarray of int
        Positions of the held-out gear's windows (a leave-one-gear-out test split).
    k_max : int
        Largest k; the pool holds at least k_max windows of every class.
    seed : int
        Seed of the variant draw and of the window order.

    Returns
    -------
    KShotSplit

    Raises
    ------
    ValueError
        If a class has too few windows for ``k_max`` while leaving one variant for
        evaluation.
    """
    target = np.asarray(target, dtype=np.int64)
    sub = meta.iloc[target]
    rng = np.random.default_rng([int(seed), int(sub["gear"].iloc[0]) if "gear" in sub else 0])
    pool, order, groups = [], {}, set()
    faults = sub["fault"].astype(str).to_numpy()
    variants = sub["variant"].to_numpy()
    for c in sorted(set(faults)):
        in_c = faults == c
        vs = rng.permutation(np.unique(variants[in_c]))
        chosen, n = [], 0
        for v in vs:
            if n >= k_max:
                break
            chosen.append(v)
            n += int(np.sum(in_c & (variants == v)))
        if k_max > 0 and (n < k_max or len(chosen) == len(vs)):
            raise ValueError(
                f"class {c!r} of the held-out gear has too few windows for k={k_max} with "
                f"variants left for evaluation ({len(vs)} variants, {int(in_c.sum())} windows)")
        pos = target[in_c & np.isin(variants, chosen)]
        order[c] = rng.permutation(pos)
        pool.append(pos)
        groups.update((c, int(v)) for v in chosen)
    pool_arr = np.sort(np.concatenate(pool)) if pool else np.array([], dtype=np.int64)
    evaluation = np.setdiff1d(target, pool_arr)
    return KShotSplit(pool_arr, evaluation, order, frozenset(groups))


# --------------------------------------------------------------------------- CORAL


class CoralClassifier:
    """CORAL (Sun, Feng & Saenko, AAAI 2016) around any feature classifier.

    Features are standardised with the source statistics; the source features are
    whitened with their own covariance and re-coloured with the target's (both + ``reg``
    times the identity), their mean moved to the target's; the classifier is trained on
    them and applied to standardised target features. Target labels are never used.

    Parameters
    ----------
    estimator : classifier
        Unfitted; cloned.
    reg : float
        Ridge added to both covariances (CORAL's identity term).
    """

    def __init__(self, estimator, reg: float = 1.0):
        self.estimator = estimator
        self.reg = reg

    @staticmethod
    def _sqrtm(c: np.ndarray, inverse: bool = False) -> np.ndarray:
        w, v = np.linalg.eigh(c)
        w = np.clip(w, 1e-12, None)
        return (v * (w ** (-0.5 if inverse else 0.5))) @ v.T

    def fit(self, X, y, X_target):
        """Fit on labelled source ``(X, y)`` aligned to unlabelled ``X_target`` (2-D)."""
        X = np.asarray(X, dtype=np.float64)
        Xt = np.asarray(X_target, dtype=np.float64)
        self.mean_ = X.mean(axis=0)
        sd = X.std(axis=0)
        self.scale_ = np.where(sd > 1e-12, sd, 1.0)
        zs = (X - self.mean_) / self.scale_
        zt = (Xt - self.mean_) / self.scale_
        eye = self.reg * np.eye(X.shape[1])
        cs = np.cov(zs, rowvar=False) + eye
        ct = np.cov(zt, rowvar=False) + eye
        a = self._sqrtm(cs, inverse=True) @ self._sqrtm(ct)
        zs_aligned = (zs - zs.mean(axis=0)) @ a + zt.mean(axis=0)
        self.estimator_ = clone(self.estimator).fit(zs_aligned, y)
        self.classes_ = self.estimator_.classes_
        return self

    def predict(self, X) -> np.ndarray:
        return self.estimator_.predict((np.asarray(X, dtype=np.float64) - self.mean_)
                                       / self.scale_)


# --------------------------------------------------------------------------- runs


@dataclass(frozen=True)
class RunSpec:
    """One (model, input) pair of the comparison.

    Attributes
    ----------
    model : str
        Key into the model configs (``transfer.models``).
    input : str
        One of :data:`learn.inputs.INPUTS`.
    finetune : bool
        Fine-tune on k target windows per class (torch nets; OOD protocols).
    adapt : str or None
        ``adabn`` (torch nets) or ``coral`` (feature inputs); OOD protocols.
    params : tuple of (str, value)
        Parameters set on the model for this input (e.g. ``padding_mode``).
    """

    model: str
    input: str
    finetune: bool = False
    adapt: str | None = None
    params: tuple = ()

    @property
    def label(self) -> str:
        return f"{self.model}/{self.input}"


def _final(est):
    return est[-1] if isinstance(est, Pipeline) else est


def _pre(est, X):
    return est[:-1].transform(X) if isinstance(est, Pipeline) and len(est) > 1 else X


def make_estimator(model_cfg: Mapping[str, Any], seed: int, n_aux: int,
                   params: Mapping[str, Any] | None = None):
    """Instantiate a model config (``_target_``) and set its seed, ``n_aux`` and ``params``.

    Every parameter named ``random_state`` or ``*__random_state`` is set to ``seed``,
    every ``n_aux`` to ``n_aux`` (the scalar channels of a signal input); ``params`` are
    set on the final estimator of a pipeline.
    """
    from hydra.utils import instantiate

    est = instantiate(model_cfg, _convert_="all")
    keys = est.get_params(deep=True)
    upd = {k: seed for k in keys if k == "random_state" or k.endswith("__random_state")}
    upd.update({k: n_aux for k in keys if k == "n_aux" or k.endswith("__n_aux")})
    est.set_params(**upd)
    if params:
        _final(est).set_params(**dict(params))
    return est


def _score(est, X, y) -> tuple[float, list[tuple[str, str, int]]]:
    """Accuracy and the confusion as (true, predicted, count) triples."""
    pred = np.asarray(est.predict(X)).astype(str)
    y = np.asarray(y).astype(str)
    pairs = pd.Series(list(zip(y, pred, strict=True))).value_counts()
    return float(np.mean(pred == y)), [(t, p, int(c)) for (t, p), c in pairs.items()]


def _fit(est, X, y, groups):
    """``est.fit``, passing ``groups`` (for a source-only early-stopping split) to an
    estimator whose ``fit`` takes them."""
    import inspect

    final = _final(est)
    if "groups" not in inspect.signature(final.fit).parameters:
        return est.fit(X, y)
    if isinstance(est, Pipeline):
        return est.fit(X, y, **{f"{est.steps[-1][0]}__groups": groups})
    return est.fit(X, y, groups=groups)


def _run_cell(spec: RunSpec, est, inp, train, evaluation, kshot: KShotSplit | None,
              k_shots: Sequence[int], ft: Mapping[str, Any], seed: int):
    """Fit one (model, input) on ``train``; score it (and its adaptations) on
    ``evaluation``. Returns result rows (without protocol and split; each with a
    ``confusion`` list) and the fitted estimator."""
    X, y = inp.X, inp.y
    rows = []
    groups = (inp.meta["gear"].astype(str) + ":" + inp.meta["fault"].astype(str) + ":"
              + inp.meta["variant"].astype(str)).to_numpy()
    t0 = time.perf_counter()
    _fit(est, X[train], y[train], groups[train])
    train_s = time.perf_counter() - t0
    base = {"model": spec.model, "input": spec.input, "seed": seed, "n_test": len(evaluation)}

    def add(model, k, m, seconds):
        acc, conf = _score(m, X[evaluation], y[evaluation])
        rows.append({**base, "model": model, "k_shot": k, "accuracy": acc, "train_s": seconds,
                     "confusion": conf})

    add(spec.model, 0, est, train_s)
    if kshot is None:
        return rows, est
    net = _final(est)
    if spec.adapt == "adabn":
        if not hasattr(net, "adapt_bn"):
            raise ValueError(f"{spec.label}: AdaBN needs a torch net")
        t0 = time.perf_counter()
        m = copy.deepcopy(est)
        _final(m).adapt_bn(_pre(m, X[kshot.pool]))
        add(f"{spec.model}+adabn", 0, m, time.perf_counter() - t0)
    elif spec.adapt == "coral":
        if X.ndim != 2:
            raise ValueError(f"{spec.label}: CORAL needs a feature input")
        t0 = time.perf_counter()
        m = CoralClassifier(est, reg=float(ft.get("coral_reg", 1.0)))
        m.fit(X[train], y[train], X[kshot.pool])
        add(f"{spec.model}+coral", 0, m, time.perf_counter() - t0)
    elif spec.adapt is not None:
        raise ValueError(f"adapt must be one of {ADAPT} or null, got {spec.adapt!r}")
    if spec.finetune:
        if not hasattr(net, "fine_tune"):
            raise ValueError(f"{spec.label}: fine-tuning needs a torch net")
        replay = float(ft.get("replay", 1.0))
        for mode in ft.get("modes", FT_MODES):
            for k in k_shots:
                if k <= 0:
                    continue
                shots = kshot.shots(k)
                t0 = time.perf_counter()
                m = copy.deepcopy(est)
                lr = ft.get(f"lr_{mode}")
                _final(m).fine_tune(
                    _pre(m, X[shots]), y[shots], mode=mode, steps=int(ft.get("steps", 100)),
                    lr=None if lr is None else float(lr),
                    X_replay=_pre(m, X[train]) if replay > 0 else None,
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
        _check_no_leak(meta, split.train, kshot)
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
    protocols: Sequence[str] = ALL_PROTOCOLS,
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
    """Run every (protocol, split, seed, model, input) of the comparison.

    Parameters
    ----------
    ds : xarray.Dataset
        Schema v1 with clean and/or disturbed windows and reference windows.
    specs : sequence of RunSpec
    model_cfgs : mapping
        Model name -> config with ``_target_`` (``conf/model/*.yaml``).
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
        ``modes`` (all, last), ``steps``, ``lr_all``, ``lr_last``, ``replay``,
        ``coral_reg``.
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
        ``results`` (DataFrame, :data:`RESULT_COLUMNS`), ``confusion`` (DataFrame:
        protocol, model, input, k_shot, true, pred, count, summed over splits and seeds),
        ``latency`` (DataFrame: model, input, input_ms, model_ms), ``wall_s`` (total),
        ``input_s`` (building inputs).

    Raises
    ------
    ValueError
        For an unknown protocol, model or adaptation, or a k-shot split that would leak.
    """
    from joblib import Parallel, delayed
    from tqdm.auto import tqdm

    from learn.inputs import build_input
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
    bar = tqdm(total=n_cells, desc="transfer", unit="cell", disable=not progress)
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
                bar.set_description(f"{c[0]} {c[1].name} seed {c[2]}")
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
    wall = time.perf_counter() - t_all
    conf = [{"protocol": r["protocol"], "model": r["model"], "input": r["input"],
             "k_shot": r["k_shot"], "true": t, "pred": p, "count": c}
            for r in rows for t, p, c in r["confusion"]]
    confusion = (pd.DataFrame(conf).groupby(["protocol", "model", "input", "k_shot", "true",
                                              "pred"], as_index=False)["count"].sum()
                 if conf else pd.DataFrame(columns=["protocol", "model", "input", "k_shot",
                                                    "true", "pred", "count"]))
    results = pd.DataFrame(rows, columns=list(RESULT_COLUMNS))
    return {"results": results, "confusion": confusion,
            "latency": lat if lat is not None else pd.DataFrame(), "wall_s": wall,
            "input_s": input_s}


def _check_no_leak(meta: pd.DataFrame, train: np.ndarray, kshot: KShotSplit) -> None:
    """Raise if evaluation windows meet the training or pool windows, or a variant of
    the pool is evaluated."""
    ev = kshot.evaluation
    if np.intersect1d(ev, train).size or np.intersect1d(ev, kshot.pool).size:
        raise ValueError("k-shot split leaks: evaluation windows in training or pool")
    groups = set(zip(meta["fault"].astype(str).to_numpy()[ev],
                     meta["variant"].to_numpy()[ev].astype(int).tolist(), strict=True))
    if groups & set(kshot.pool_groups):
        raise ValueError("k-shot split leaks: a pool variant is also evaluated")
    if set(meta["gear"].to_numpy()[train]) & set(meta["gear"].to_numpy()[ev]):
        raise ValueError("leave-one-gear-out split leaks: the target gear is in training")


def measure_latency(ds, specs: Sequence[RunSpec], model_cfgs, inputs, *, aux=("eta2_rel",
                    "eta_rel"), feature_kwargs=None, residual=None, repeats: int = 100,
                    n_fit: int = 600) -> pd.DataFrame:
    """Inference latency per window, batch 1, one CPU thread, of every (model, input).

    Each model is fitted on at most ``n_fit`` windows with a budget of one epoch (the
    cost of ``predict`` does not depend on how well it was trained), then timed on
    ``repeats`` single windows (median). ``input_ms`` is the median time to build the
    input of one window from a two-window data set (the window and its reference).

    Returns
    -------
    pandas.DataFrame
        Columns model, input, input_ms, model_ms [ms].
    """
    import torch

    from learn.inputs import build_input

    threads = torch.get_num_threads()
    torch.set_num_threads(1)
    rows = []
    try:
        seen = set()
        for spec in specs:
            if (spec.model, spec.input) in seen:
                continue
            seen.add((spec.model, spec.input))
            inp = inputs[spec.input]
            rng = np.random.default_rng(0)
            idx = np.sort(rng.choice(len(inp.y), size=min(n_fit, len(inp.y)), replace=False))
            est = make_estimator(model_cfgs[spec.model], 0, inp.n_aux, dict(spec.params))
            if "max_epochs" in _final(est).get_params():
                _final(est).set_params(max_epochs=1)
            est.fit(inp.X[idx], inp.y[idx])
            from learn.features import reference_index

            s_all, r_all = reference_index(ds)
            smp = int(inp.meta["sample"].iloc[0])
            one = ds.isel(sample=[smp, int(r_all[np.searchsorted(s_all, smp)])])
            t_in = []
            for _ in range(max(3, repeats // 10)):
                t0 = time.perf_counter()
                build_input(one, spec.input, aux=tuple(aux),
                            feature_kwargs=dict(feature_kwargs or {}),
                            residual=dict(residual or {}))
                t_in.append(time.perf_counter() - t0)
            est.predict(inp.X[:1])  # warm-up
            t_m = []
            for r in range(repeats):
                x = inp.X[r % len(inp.y)][None]
                t0 = time.perf_counter()
                est.predict(x)
                t_m.append(time.perf_counter() - t0)
            rows.append({"model": spec.model, "input": spec.input,
                         "input_ms": 1e3 * float(np.median(t_in)),
                         "model_ms": 1e3 * float(np.median(t_m))})
    finally:
        torch.set_num_threads(threads)
    return pd.DataFrame(rows)


# --------------------------------------------------------------------------- report

_NAMES = {"rf": "RF", "minirocket": "MiniRocket", "mlp_torch": "MLP", "cnn": "CNN",
          "mlp": "MLP (sklearn)", "knn": "KNN", "nb": "NB", "svm": "SVM"}
_INPUTS = {"raw": "raw", "diff": "differenced", "sel1": "Selection 1", "sel3": "Selection 3"}
_SPLIT_ORDER = {"gear3": 0, "gear1": 1, "gear2": 2}


def row_label(model: str, inp: str, k: int) -> str:
    """Human-readable row name, e.g. ``CNN, raw, fine-tuned all layers, k=5``."""
    base, _, suffix = model.partition("+")
    name = f"{_NAMES.get(base, base)}, {_INPUTS.get(inp, inp)}"
    if suffix == "ft_all":
        name += f", fine-tuned all layers, k={k}"
    elif suffix == "ft_last":
        name += f", fine-tuned last layer, k={k}"
    elif suffix == "adabn":
        name += ", AdaBN (unsupervised)"
    elif suffix == "coral":
        name += ", CORAL (unsupervised)"
    return name


def summarise(results: pd.DataFrame) -> pd.DataFrame:
    """Mean and std over seeds per (protocol, model, input, k, split), plus the worst
    split (lowest mean) per (protocol, model, input, k).

    Returns
    -------
    pandas.DataFrame
        Columns protocol, model, input, k_shot, split, mean, std, n_seeds; the worst split
        appears as ``split == "worst"`` (its std is that split's std).
    """
    keys = ["protocol", "model", "input", "k_shot"]
    g = results.groupby([*keys, "split"])["accuracy"]
    per = g.agg(["mean", "std", "count"]).reset_index().rename(columns={"count": "n_seeds"})
    per["std"] = per["std"].fillna(0.0)
    worst = per.loc[per.groupby(keys)["mean"].idxmin()].copy()
    worst["worst_of"] = worst["split"]
    worst["split"] = "worst"
    return pd.concat([per, worst], ignore_index=True)


def _pct(m: float, s: float) -> str:
    return f"{100 * m:.2f} ± {100 * s:.2f}"


def write_table(results: pd.DataFrame, path: str | Path, *, timings: Mapping | None = None,
                latency: pd.DataFrame | None = None, targets: Mapping | None = None,
                confusion: pd.DataFrame | None = None, paper: bool = True,
                separability: pd.DataFrame | None = None) -> Path:
    """Write ``table.md``: per protocol, accuracy [%] per split and worst split.

    Rows: every (model, input, k) present; the paper's own numbers (RF, Table X and IX)
    beside ours where known. With ``confusion``, a diagnosis of the best model per
    leave-one-gear-out protocol: its main confusions, the class pairs it cannot tell
    apart and the accuracy ceiling if those pairs are truly indistinguishable. With
    ``separability`` (:func:`learn.separability.summary_table`), how far each class lies
    from the healthy windows in the signals themselves.
    """
    summ = summarise(results)
    lines = ["# Transfer to the unseen gear: deep learners, MiniRocket and the paper's "
             "pipeline", "",
             "Accuracy [%] on the test windows, mean ± std over seeds; `worst` = the split "
             "with the lowest mean. Leave-one-gear-out splits `gearN` hold out gear N "
             "(paper: `1,2 → 3` is `gear3`); they are scored on the held-out gear's windows "
             "outside the k-shot pool, for every k alike.", ""]
    if targets:
        lines += _targets_md(summ, targets) + [""]
    if confusion is not None and len(confusion):
        lines += _diagnosis_md(summ, confusion) + [""]
    if separability is not None and len(separability):
        lines += _separability_md(separability) + [""]
    for p in [q for q in ALL_PROTOCOLS if q in set(results["protocol"])]:
        sp = summ[summ["protocol"] == p]
        splits = sorted({s for s in sp["split"] if s != "worst"},
                        key=lambda s: (_SPLIT_ORDER.get(s, 9), s))
        lines += [f"## {p}", "", "| model | " + " | ".join(splits) + " | worst |",
                  "|---|" + "---:|" * (len(splits) + 1)]
        order = sp[sp["split"] == "worst"].sort_values(
            ["k_shot", "model", "input"], key=lambda c: c.map(_model_rank)
            if c.name == "model" else c)
        for _, w in order.iterrows():
            cells = []
            for s in splits:
                r = sp[(sp["model"] == w["model"]) & (sp["input"] == w["input"])
                       & (sp["k_shot"] == w["k_shot"]) & (sp["split"] == s)]
                cells.append(_pct(r["mean"].iloc[0], r["std"].iloc[0]) if len(r) else "")
            cells.append(f"**{100 * w['mean']:.2f}** ({w['worst_of']})")
            lines.append(f"| {row_label(w['model'], w['input'], int(w['k_shot']))} | "
                         + " | ".join(cells) + " |")
        if paper and p in ("ood_clean", "ood_disturbed"):
            lines += _paper_rows(p, splits)
        lines.append("")
    if latency is not None and len(latency):
        lines += ["## Inference latency per window (CPU, batch 1, one thread)", "",
                  "| model | input | input build [ms] | model [ms] |", "|---|---|---:|---:|"]
        for _, r in latency.iterrows():
            lines.append(f"| {_NAMES.get(r['model'], r['model'])} | {r['input']} | "
                         f"{r['input_ms']:.2f} | {r['model_ms']:.2f} |")
        lines.append("")
    if timings:
        tt = results.groupby(["model", "input"])["train_s"].sum().sort_values(ascending=False)
        lines += ["## Training time", "",
                  f"Whole comparison: {timings.get('wall_s', float('nan')) / 60:.1f} min wall "
                  f"time, {timings.get('threads', '?')} on a machine with "
                  f"{timings.get('cpus', '?')} CPU cores "
                  f"(inputs {timings.get('input_s', float('nan')):.1f} s). "
                  "Sum of fit times per model (fine-tuning: the fine-tuning alone):", "",
                  "| model | input | train [s] |", "|---|---|---:|"]
        for (m, i), v in tt.items():
            lines.append(f"| {m} | {i} | {v:.1f} |")
        lines.append("")
    path = Path(path)
    path.write_text("\n".join(lines) + "\n")
    return path


def _model_rank(m: str) -> int:
    order = ["rf", "rf+coral", "minirocket", "mlp_torch", "mlp_torch+adabn",
             "mlp_torch+ft_last", "mlp_torch+ft_all", "cnn", "cnn+adabn", "cnn+ft_last",
             "cnn+ft_all"]
    return order.index(m) if m in order else len(order)


def _paper_rows(protocol: str, splits: Sequence[str]) -> list[str]:
    try:
        from learn.paper_results import PAPER_RESULTS
    except ImportError:  # pragma: no cover
        return []
    table = {"ood_clean": "IX", "ood_disturbed": "X"}[protocol]
    out = []
    for sel in ("selection1", "selection3"):
        res = PAPER_RESULTS.get(table) or {}
        if sel not in res:
            continue
        vals = [res[sel].get(s, {}).get("rf") for s in splits]
        if any(v is None for v in vals):
            continue
        out.append(f"| paper Table {table}: RF, Selection {sel[-1]} | "
                   + " | ".join(f"{v:.2f}" for v in vals) + f" | **{min(vals):.2f}** |")
    return out


def _targets_md(summ: pd.DataFrame, targets: Mapping) -> list[str]:
    """Best worst-split accuracy on ood_disturbed without and with k target labels."""
    w = summ[(summ["protocol"] == "ood_disturbed") & (summ["split"] == "worst")]
    if w.empty:
        return []
    lines = ["## Targets (ood_disturbed, worst of the three splits)", "",
             "| condition | target | best reached | by |", "|---|---:|---:|---|"]
    for k, target in sorted(targets.items()):
        cand = w[w["k_shot"] == int(k)]
        if cand.empty:
            continue
        b = cand.loc[cand["mean"].idxmax()]
        ok = "met" if b["mean"] >= float(target) else "not met"
        lines.append(f"| k = {k} labelled windows per class | {100 * float(target):.1f} % | "
                     f"{100 * b['mean']:.2f} % ({ok}) | "
                     f"{row_label(b['model'], b['input'], int(b['k_shot']))} |")
    return lines


def confusable_pairs(conf: pd.DataFrame, threshold: float = 0.25) -> list[tuple[str, str]]:
    """Class pairs (a, b) with a -> b and b -> a each above ``threshold`` of the class.

    Parameters
    ----------
    conf : pandas.DataFrame
        Columns true, pred, count (one model).
    """
    tot = conf.groupby("true")["count"].sum()
    rate = {(t, p): c / tot[t] for t, p, c in conf[["true", "pred", "count"]].itertuples(
        index=False) if t != p}
    pairs = []
    for (a, b), r in rate.items():
        if a < b and r > threshold and rate.get((b, a), 0.0) > threshold:
            pairs.append((a, b))
    return pairs


def _diagnosis_md(summ: pd.DataFrame, confusion: pd.DataFrame) -> list[str]:
    lines = []
    for p in OOD_PROTOCOLS:
        w = summ[(summ["protocol"] == p) & (summ["split"] == "worst") & (summ["k_shot"] == 0)]
        if w.empty:
            continue
        b = w.loc[w["mean"].idxmax()]
        c = confusion[(confusion["protocol"] == p) & (confusion["model"] == b["model"])
                      & (confusion["input"] == b["input"]) & (confusion["k_shot"] == 0)]
        if c.empty:
            continue
        tot = c.groupby("true")["count"].sum()
        off = c[c["true"] != c["pred"]].copy()
        off["rate"] = off["count"] / off["true"].map(tot)
        top = off.sort_values("rate", ascending=False).head(5)
        pairs = confusable_pairs(c)
        n = tot.sum()
        ceiling = 1.0 - sum(0.5 * (tot[a] + tot[b]) for a, b in pairs) / n
        lines += [f"## Diagnosis: {p}, best model without target labels "
                  f"({row_label(b['model'], b['input'], 0)})", "",
                  "Main confusions (all splits and seeds; share of the true class):", ""]
        lines += [f"- {r.true} → {r.pred}: {100 * r.rate:.1f} %" for r in top.itertuples()]
        if pairs:
            names = ", ".join(f"{a} ↔ {b}" for a, b in pairs)
            lines += ["", f"Confused both ways (> 25 % each): {names}. If these classes "
                      "leave no trace in the data, no classifier beats chance between them: "
                      f"accuracy ceiling {100 * ceiling:.1f} %."]
        lines.append("")
    return lines


def _separability_md(tab: pd.DataFrame) -> list[str]:
    lines = ["## Class separability in the signals (independent of any classifier)", "",
             f"Each {tab.attrs.get('kind', 'clean')} window reduced to the amplitudes of the "
             "first harmonics of the wave-generator angle in the five bridges and η; its "
             "separation = the largest distance from the healthy windows of the same gear "
             "and operating point, in their spreads (`learn/separability.py`, figure "
             "`separability.png`). Healthy windows scored leave-one-out reach "
             f"{tab.attrs['p95']:.2f} (95th percentile) by chance.", "",
             "| class | windows | beyond healthy p95 | beyond healthy p99 | median |",
             "|---|---:|---:|---:|---:|"]
    for r in tab.itertuples():
        lines.append(f"| {r.fault} | {r.windows} | {100 * r.beyond_p95:.1f} % | "
                     f"{100 * r.beyond_p99:.1f} % | {r.median:.3g} |")
    return lines


def plot_accuracy_vs_k(results: pd.DataFrame, path: str | Path,
                       targets: Mapping | None = None) -> Path:
    """Figure: worst-split accuracy against k per leave-one-gear-out protocol.

    Solid / dashed lines: a net fine-tuned on all layers / the last layer (k = 0 is its
    pretrained model); dotted horizontal lines: models without target labels (including
    the unsupervised adaptations). One colour per (model, input) in every panel. Error
    bars: std over seeds. ``targets`` ({k: accuracy 0-1}) are marked on ood_disturbed.
    One legend below the panels.
    """
    from matplotlib import colormaps
    from matplotlib.figure import Figure
    from matplotlib.lines import Line2D

    summ = summarise(results)
    prots = [p for p in OOD_PROTOCOLS if p in set(results["protocol"])] or ["ood_disturbed"]
    w_all = summ[summ["split"] == "worst"]
    keys = sorted({(m.split("+")[0], i, m.partition("+")[2])
                   for m, i in zip(w_all["model"], w_all["input"], strict=True)
                   if not m.partition("+")[2].startswith("ft_")},
                  key=lambda t: (_model_rank(t[0]), t[1], t[2]))
    cmap = colormaps["tab20"]
    colour = {k: cmap(n % 20) for n, k in enumerate(keys)}
    k_max = max(1, int(results["k_shot"].max()) if len(results) else 1)
    fig = Figure(figsize=(6.0 * len(prots), 4.0 + 0.22 * len(keys)), layout="constrained")
    axes = [fig.add_subplot(1, len(prots), n + 1) for n in range(len(prots))]
    handles: dict[str, Line2D] = {}
    for ax, p in zip(axes, prots, strict=True):
        w = w_all[w_all["protocol"] == p]
        for (m, i), g in w[w["model"].str.contains(r"\+ft_")].groupby(["model", "input"]):
            base_name, _, mode = m.partition("+")
            base = w[(w["model"] == base_name) & (w["input"] == i) & (w["k_shot"] == 0)]
            g = pd.concat([base, g]).sort_values("k_shot")
            ls = "-" if mode == "ft_all" else "--"
            ax.errorbar(g["k_shot"], 100 * g["mean"], yerr=100 * g["std"], marker="o",
                        ms=4, capsize=3, ls=ls, color=colour[(base_name, i, "")])
            lab = row_label(m, i, 0).replace(", k=0", "")
            handles.setdefault(lab, Line2D([], [], color=colour[(base_name, i, "")], ls=ls,
                                           marker="o", ms=4))
        ft_pairs = {(m.partition("+")[0], i) for m, i in zip(w["model"], w["input"],
                                                             strict=True) if "+ft_" in m}
        for _, r in w[w["k_shot"] == 0].iterrows():
            base_name, _, suffix = r["model"].partition("+")
            if not suffix and (base_name, r["input"]) in ft_pairs:
                continue  # drawn as the k = 0 point of its fine-tuned lines
            c = colour[(base_name, r["input"], suffix)]
            ax.axhline(100 * r["mean"], ls=":", lw=1.4, color=c)
            lab = row_label(r["model"], r["input"], 0)
            handles.setdefault(lab, Line2D([], [], color=c, ls=":", lw=1.4))
        if targets and p == "ood_disturbed":
            tk = sorted((int(k), 100 * float(v)) for k, v in targets.items())
            ax.plot([k for k, _ in tk], [v for _, v in tk], "k*", ms=10)
            handles.setdefault("target (issue)", Line2D([], [], color="k", marker="*", ls="",
                                                        ms=10))
        ax.set_xlim(-0.5, k_max + 0.5)
        ax.set_xlabel("labelled windows per class of the held-out gear, k")
        ax.set_ylabel("accuracy, worst split [%]")
        ax.set_title(p)
        ax.grid(alpha=0.3)
    fig.legend(list(handles.values()), list(handles.keys()), loc="outside lower center",
               ncol=3, fontsize=7, frameon=False)
    path = Path(path)
    fig.savefig(path, dpi=130)
    return path


# --------------------------------------------------------------------------- task


def _specs_from_cfg(runs) -> list[RunSpec]:
    out = []
    for r in runs:
        r = dict(r)
        out.append(RunSpec(model=str(r["model"]), input=str(r["input"]),
                           finetune=bool(r.get("finetune", False)), adapt=r.get("adapt"),
                           params=tuple(sorted(dict(r.get("params") or {}).items()))))
    return out


def run_transfer(cfg) -> dict:
    """Task ``transfer``: the whole comparison, report and MLflow logging.

    Reads ``cfg.data.path``, ``cfg.transfer`` (see ``conf/experiment/transfer.yaml``),
    ``cfg.features`` (orders, floor), ``cfg.logger`` (None: no tracking), ``cfg.seed``
    (CV folds) and ``cfg.paths.report_dir``.

    Returns
    -------
    dict
        ``report_dir``, ``files``, ``wall_s``, ``n_runs``, ``worst_split`` (ood_disturbed
        worst-split mean accuracy per model/input/k), ``run_id`` (parent MLflow run).
    """
    import torch
    from omegaconf import OmegaConf

    from learn.features import FeatureSettings
    from swgsim.data import load

    tc = cfg.transfer
    threads = tc.get("n_threads")
    if threads:
        torch.set_num_threads(int(threads))
    feature_kwargs = FeatureSettings.of(cfg.get("features")).kwargs()
    models = OmegaConf.to_container(tc.models, resolve=True)
    specs = _specs_from_cfg(OmegaConf.to_container(tc.runs, resolve=True))
    ds = load(cfg.data.path)
    log.info("transfer: %d windows from %s, %d model/input pairs", ds.sizes["sample"],
             cfg.data.path, len(specs))
    out = run_comparison(
        ds, specs, models,
        protocols=list(tc.protocols), seeds=list(tc.seeds),
        cv_seeds=None if tc.get("cv_seeds") is None else list(tc.cv_seeds),
        k_shots=list(tc.k_shots),
        finetune=OmegaConf.to_container(tc.finetune, resolve=True),
        aux=list(tc.aux), feature_kwargs=feature_kwargs,
        residual=OmegaConf.to_container(tc.residual, resolve=True) if tc.get("residual")
        else None,
        split_seed=int(cfg.get("seed", 0)), n_jobs=int(tc.get("n_jobs", 1)),
        threads_per_job=tc.get("threads_per_job"),
        latency=bool(tc.get("latency", True)),
        latency_repeats=int(tc.get("latency_repeats", 100)),
        progress=bool(tc.get("progress", True)),
    )
    report_dir = Path(tc.get("report_dir") or Path(cfg.paths.report_dir) / "transfer")
    report_dir.mkdir(parents=True, exist_ok=True)
    res = out["results"]
    n_jobs = int(tc.get("n_jobs", 1))
    timings = {"wall_s": out["wall_s"], "input_s": out["input_s"],
               "threads": f"{n_jobs} process(es) x {tc.get('threads_per_job') or 'default'} "
                          f"torch thread(s)" if n_jobs > 1 else
                          f"1 process x {torch.get_num_threads()} torch thread(s)",
               "cpus": os.cpu_count()}
    files = {"results": report_dir / "results.csv"}
    res.to_csv(files["results"], index=False)
    files["confusion"] = report_dir / "confusion.csv"
    out["confusion"].to_csv(files["confusion"], index=False)
    if len(out["latency"]):
        files["latency"] = report_dir / "latency.csv"
        out["latency"].to_csv(files["latency"], index=False)
    targets = OmegaConf.to_container(tc.targets, resolve=True) if tc.get("targets") else None
    kind = "clean" if (~ds["disturbed"].values.astype(bool)).any() else "disturbed"
    sep = separations(ds, disturbed=kind == "disturbed",
                      ratio=float((tc.get("residual") or {}).get("ratio", 100.0)))
    sep_tab = None
    if "healthy" in sep:
        sep_tab = summary_table(sep)
        sep_tab.attrs["kind"] = kind
        files["separability"] = plot_separability(
            sep, report_dir / "separability.png",
            f"Class separability in the simulated signals ({kind})")
    files["table"] = write_table(res, report_dir / "table.md", timings=timings,
                                 latency=out["latency"], targets=targets,
                                 confusion=out["confusion"], separability=sep_tab)
    files["figure"] = plot_accuracy_vs_k(res, report_dir / "accuracy_vs_k.png",
                                         targets=targets)
    summ = summarise(res)
    w = summ[(summ["protocol"] == "ood_disturbed") & (summ["split"] == "worst")]
    worst = {f"{r.model}/{r.input}/k{int(r.k_shot)}": float(r["mean"]) for _, r in w.iterrows()}
    run_id = None
    if cfg.get("logger") is not None:
        run_id = log_transfer(res, files, cfg, timings, out["latency"])
    log.info("transfer report in %s (%.1f min)", report_dir, out["wall_s"] / 60)
    return {"task": "transfer", "report_dir": str(report_dir),
            "files": {k: str(v) for k, v in files.items()}, "wall_s": out["wall_s"],
            "n_runs": len(res), "worst_split": worst, "run_id": run_id}


def log_transfer(results: pd.DataFrame, files: Mapping[str, Path], cfg, timings: Mapping,
                 latency: pd.DataFrame | None = None) -> str:
    """Log the comparison to MLflow: a parent run with the report files and params, and
    one child run per (protocol, model, input, k) with ``<split>/accuracy`` per seed
    (step = seed), ``<split>/accuracy_mean``, ``mean_accuracy``, ``worst_split_accuracy``
    and ``train_s``. Returns the parent run id."""
    import mlflow
    from mlflow.entities import Metric, Param, RunTag
    from omegaconf import OmegaConf

    from learn.tracking import default_tracking_uri, flatten_config, get_experiment_id

    lcfg = cfg.logger
    client = mlflow.MlflowClient(lcfg.get("tracking_uri") or default_tracking_uri())
    exp_id = get_experiment_id(client, str(lcfg.get("experiment") or "transfer"))
    resolved = OmegaConf.to_container(cfg, resolve=True)
    parent = client.create_run(exp_id, run_name=str(lcfg.get("run_name") or "transfer"),
                               tags={"task": "transfer"})
    pid = parent.info.run_id
    status = "FAILED"
    try:
        ts = parent.info.start_time
        flat = sorted(flatten_config(resolved.get("transfer", {})).items())
        for start in range(0, len(flat), 100):
            client.log_batch(pid, params=[Param(f"transfer.{k}", v)
                                          for k, v in flat[start:start + 100]])
        client.log_batch(pid, metrics=[Metric("wall_s", float(timings["wall_s"]), ts, 0)])
        client.log_dict(pid, resolved, "config.yaml")
        for f in files.values():
            client.log_artifact(pid, str(f))
        for (p, m, i, k), g in results.groupby(["protocol", "model", "input", "k_shot"]):
            run = client.create_run(exp_id, run_name=f"{p}-{m}-{i}-k{k}",
                                    tags={"mlflow.parentRunId": pid, "task": "transfer",
                                          "protocol": p})
            mets = [Metric(f"{s}/accuracy", float(a), ts, int(sd))
                    for s, sd, a in g[["split", "seed", "accuracy"]].itertuples(index=False)]
            means = g.groupby("split")["accuracy"].mean()
            mets += [Metric(f"{s}/accuracy_mean", float(v), ts, 0) for s, v in means.items()]
            mets += [Metric("mean_accuracy", float(means.mean()), ts, 0),
                     Metric("worst_split_accuracy", float(means.min()), ts, 0),
                     Metric("train_s", float(g["train_s"].sum()), ts, 0)]
            if latency is not None and len(latency):
                lat = latency[(latency["model"] == m.split("+")[0]) & (latency["input"] == i)]
                if len(lat):
                    mets.append(Metric("latency_ms", float(lat["model_ms"].iloc[0]), ts, 0))
            client.log_batch(run.info.run_id, metrics=mets,
                             params=[Param("protocol", p), Param("model", m),
                                     Param("input", i), Param("k_shot", str(k))],
                             tags=[RunTag("splits", ";".join(sorted(means.index)))])
            client.set_terminated(run.info.run_id, status="FINISHED")
        status = "FINISHED"
    finally:
        client.set_terminated(pid, status=status)
    return pid
