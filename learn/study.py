"""The paper's fault-classification study (Sec. IV, Tables VII-X) and the train task.

Two entry points:

* :func:`run_train` - the task function behind ``swgsim-train`` (Hydra). It dispatches on
  ``cfg.task`` through :data:`TASKS`, a dict of task name to importable function path:
  ``study`` runs one job (one protocol, one feature selection, one model, all splits),
  ``paper_study`` the whole study, ``transfer`` :func:`learn.transfer.run_transfer`.
* :func:`run_paper_study` - every job of Tables VII-X on one data set, features of each
  selection computed once, one MLflow run per job, a report in ``report_dir``.
"""

from __future__ import annotations

import logging
import time
from collections.abc import Mapping, Sequence
from pathlib import Path
from typing import Any

import numpy as np
import pandas as pd

from learn.baselines import MODEL_LABELS, make_model
from learn.features import Features, FeatureSettings, extract_features
from learn.paper_results import PAPER_TABLES
from learn.protocols import (
    PROTOCOLS,
    ProtocolResult,
    class_labels,
    evaluate,
    make_splits,
)

log = logging.getLogger(__name__)

#: Task name -> function ``f(cfg) -> dict`` (dotted path, imported on use).
TASKS: dict[str, str] = {
    "study": "learn.study.run_study_job",
    "paper_study": "learn.study.run_paper_study_task",
    "transfer": "learn.transfer.run_transfer",
}

def run_train(cfg) -> dict:
    """Run the task named by ``cfg.task`` (default ``"study"``).

    Parameters
    ----------
    cfg : omegaconf.DictConfig
        Composed ``conf/train.yaml``.

    Returns
    -------
    dict
        Whatever the task returns (metrics, run ids, paths).

    Raises
    ------
    ValueError
        For a task not in :data:`TASKS`.
    """
    from hydra.utils import get_method

    task = cfg.get("task", "study")
    if task not in TASKS:
        raise ValueError(f"task must be one of {sorted(TASKS)}, got {task!r}")
    if cfg.get("logger") is not None:
        from learn.tracking import check_tracking

        check_tracking(cfg.logger.get("tracking_uri"), "logger.tracking_uri")
    log.info("task %s -> %s", task, TASKS[task])
    return get_method(TASKS[task])(cfg)


def _features_from_cfg(ds, fcfg) -> Features:
    settings = FeatureSettings.of(fcfg)
    return extract_features(ds, settings.selection, **settings.kwargs())


def run_study_job(cfg) -> dict:
    """One job: a model under a protocol on one feature selection, all splits.

    Reads ``cfg.data.path``, ``cfg.features`` (selection, max_order, order_step,
    floor_rel), ``cfg.model`` (instantiated with Hydra), ``cfg.protocol`` (keyword
    arguments of :func:`learn.protocols.make_splits` plus ``name``), ``cfg.logger``
    (None: no tracking) and ``cfg.n_jobs``.

    Parameters
    ----------
    cfg : omegaconf.DictConfig

    Returns
    -------
    dict
        ``protocol``, ``selection``, ``model``, ``splits`` (labels), ``train_accuracy``
        and ``test_accuracy`` (lists, per split), ``mean_train_accuracy``,
        ``mean_test_accuracy``, ``n_samples``, ``run_id`` (None without logger).
    """
    from hydra.utils import instantiate
    from omegaconf import OmegaConf

    from swgsim.data import load

    ds = load(cfg.data.path)
    feats = _features_from_cfg(ds, cfg.features)
    y = feats.meta["fault"].to_numpy()
    pcfg = OmegaConf.to_container(cfg.protocol, resolve=True)
    pname = pcfg.pop("name")
    splits = make_splits(feats.meta, **pcfg)
    estimator = instantiate(cfg.model, _convert_="all")
    result = evaluate(estimator, feats.X, y, splits, labels=class_labels(y),
                      n_jobs=cfg.get("n_jobs", 1))
    log.info("%s / %s / %s: test accuracy %s, mean %.4f", pname, cfg.features.name,
             cfg.model.name, np.round(result.test_accuracy, 4), result.mean_test_accuracy)
    run_id = None
    if cfg.get("logger") is not None:
        from learn.tracking import hydra_sweep

        resolved = OmegaConf.to_container(cfg, resolve=True)
        model = (_last_split_model(estimator, feats.X, y, splits[-1])
                 if cfg.logger.get("log_models", True) else None)
        run_id = _log(result, cfg.logger, params=resolved, config=resolved,
                      tags={"task": "study", "protocol": pname}, dataset=str(cfg.data.path),
                      model=model, model_tags={"split": splits[-1].label},
                      X_sample=feats.X[splits[-1].test[:5]], group=hydra_sweep())
    return {
        "task": "study",
        "protocol": pname,
        "selection": cfg.features.name,
        "model": cfg.model.name,
        "splits": [s.label for s in splits],
        "train_accuracy": result.train_accuracy.tolist(),
        "test_accuracy": result.test_accuracy.tolist(),
        "mean_train_accuracy": result.mean_train_accuracy,
        "mean_test_accuracy": result.mean_test_accuracy,
        "n_samples": int(sum(len(s.test) for s in splits)),
        "run_id": run_id,
    }


def _log(result: ProtocolResult, lcfg, **kw) -> str:
    from learn.tracking import log_job

    return log_job(result, experiment=str(lcfg.experiment), run_name=str(lcfg.run_name),
                   tracking_uri=lcfg.get("tracking_uri"),
                   confusion_plot=bool(lcfg.get("confusion_plot", True)), **kw)


def _last_split_model(estimator, X: np.ndarray, y: np.ndarray, split):
    """A clone of ``estimator`` fitted on the last split's training rows (to be logged).

    The protocol's fits run in worker processes and return scores only; this refit (one
    more fit per job) is what ``logger.log_models`` costs. Its warnings were already
    reported by the protocol's identical fit.
    """
    import warnings

    from sklearn.base import clone

    est = clone(estimator)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        est.fit(X[split.train], np.asarray(y).astype(str)[split.train])
    return est


def run_paper_study_task(cfg) -> dict:
    """Task ``paper_study``: :func:`run_paper_study` from a composed config.

    Uses ``cfg.data.path``, ``cfg.paths.report_dir``/paper, ``cfg.logger.tracking_uri``
    (no tracking if ``cfg.logger`` is None), ``cfg.n_jobs``, ``cfg.seed``,
    ``cfg.features`` (orders and floor; the selections are those of the tables) and
    ``cfg.study`` (tables, models, scale, figures; see ``conf/experiment/paper.yaml``).

    Returns
    -------
    dict
        ``timings_s``, ``files`` (report paths as str), ``n_jobs_run`` and
        ``mean_test_accuracy`` keyed by ``"table/selection/model"``.
    """
    fcfg = cfg.features
    scfg = cfg.get("study") or {}
    tables, models = scfg.get("tables"), scfg.get("models")
    out = run_paper_study(
        cfg.data.path,
        Path(cfg.paths.report_dir) / "paper",
        tracking_uri=cfg.logger.get("tracking_uri") if cfg.get("logger") is not None else None,
        track=cfg.get("logger") is not None,
        log_models=bool(cfg.logger.get("log_models", True))
        if cfg.get("logger") is not None else False,
        n_jobs=int(cfg.get("n_jobs", 1)),
        random_state=int(cfg.seed),
        tables=None if tables is None else [str(t) for t in tables],
        models=None if models is None else [str(m) for m in models],
        scale=bool(scfg.get("scale", True)),
        figures=bool(scfg.get("figures", True)),
        feature_kwargs=FeatureSettings.of(fcfg).kwargs(),
    )
    res = out.pop("results")
    means = res.groupby(["table", "selection", "model"])["test_accuracy"].mean()
    out["mean_test_accuracy"] = {"/".join(k): float(v) for k, v in means.items()}
    out["files"] = {k: str(v) for k, v in out["files"].items()}
    return out


def run_paper_study(
    dataset_path: str | Path,
    report_dir: str | Path,
    tracking_uri: str | None = None,
    n_jobs: int = 1,
    progress: bool = True,
    *,
    random_state: int = 0,
    tables: Sequence[str] | None = None,
    models: Sequence[str] | None = None,
    scale: bool = False,
    track: bool = True,
    experiment_prefix: str = "paper_study/",
    feature_kwargs: Mapping[str, Any] | None = None,
    figures: bool = True,
    name: str = "",
    protocol_kwargs: Mapping[str, Mapping[str, Any]] | None = None,
    log_models: bool = False,
) -> dict:
    """Run the paper's study, Tables VII-X, and write its report.

    ============  =============  ==============  =======================  ===========
    table         protocol       selections      models                   splits
    ============  =============  ==============  =======================  ===========
    VII           cv_clean       1, 2, 3         MLP, SVM, RF, KNN, NB    4 folds
    VIII          cv_disturbed   1, 2, 3         MLP, SVM, RF, KNN, NB    4 folds
    IX            ood_clean      1, 2, 3         MLP, SVM, RF, KNN, NB    3 gears
    X             ood_disturbed  1, 3            MLP, RF, KNN, NB         3 gears
    ============  =============  ==============  =======================  ===========

    Parameters
    ----------
    dataset_path : path-like
        Schema-v1 data set with clean and disturbed windows and reference windows.
    report_dir : path-like
        Folder of the report (:func:`learn.report.write_report`), e.g. ``reports/paper``.
    tracking_uri : str, optional
        MLflow tracking URI; default :func:`learn.tracking.default_tracking_uri`.
    n_jobs : int, default 1
        Fits run in parallel (joblib processes), over every (job, split) of every table.
    progress : bool, default True
        Show one tqdm progress bar for the stage (loading, features, fits).
    random_state : int, default 0
        Seed of the CV folds and of MLP, SVM and RF.
    tables : sequence of {"VII", "VIII", "IX", "X"}, optional
        Subset of tables; default all.
    models : sequence of str, optional
        Restrict every table to these models (e.g. for a quick run); default the paper's.
    scale : bool, default False
        Standardise features in every pipeline (see :mod:`learn.baselines`); the paper
        names scikit-learn's standard settings and no scaling.
    track : bool, default True
        Log one MLflow run per job, in experiment ``experiment_prefix + protocol``, each
        with the git commit, the data set (path and content hash) and its params; the jobs
        of one call are children of one parent run per experiment (group
        ``"study <name> <start time>"``).
    experiment_prefix : str, default "paper_study/"
    feature_kwargs : mapping, optional
        ``orders`` and ``floor_rel`` of :func:`learn.features.extract_features`.
    figures : bool, default True
        Also draw the paper's Fig. 6-8 from the data set.
    name : str, optional
        Name of the data set (protocol) for the progress bar.
    protocol_kwargs : mapping, optional
        Per protocol name, keyword arguments of :func:`learn.protocols.make_splits` that
        replace the paper's (:data:`learn.protocols.PROTOCOLS`), e.g.
        ``{"cv_clean": {"scheme": "kfold"}}`` (sensitivity studies).
    log_models : bool, default False
        With ``track``, also log each job's model fitted on its last split
        (:meth:`learn.tracking.TrackedRun.log_model`): the protocol's own fit, returned by
        the worker (no refit), plus the model's storage (``logger.log_models`` in
        :class:`swgcli.schema.LoggerConfig`, for the measured cost).

    Returns
    -------
    dict
        ``results`` (pandas.DataFrame, one row per job and split: table, protocol,
        selection, model, split, split_label, train_accuracy, test_accuracy, fit_time_s,
        n_train, n_test, run_id), ``confusion`` (pandas.DataFrame: table, protocol,
        selection, model, true, predicted, count; summed over splits), ``spread``
        (:func:`learn.features.feature_spread` of Selections 1 and 3 where computed),
        ``warnings`` (list of dicts category, message, count: what the fits raised),
        ``timings_s`` (features and each table [s]), ``files`` (report files by kind),
        ``n_jobs_run`` (number of jobs).

    Raises
    ------
    ValueError
        For an unknown table or model.
    """
    from collections import Counter

    from joblib import Parallel, delayed
    from tqdm.auto import tqdm

    from learn.features import feature_spread
    from learn.protocols import fit_split_quiet
    from learn.report import write_report
    from swgsim.data import load

    group = f"study {name or Path(dataset_path).name} {time.strftime('%Y-%m-%d %H:%M:%S')}"
    tables = list(PAPER_TABLES) if tables is None else list(tables)
    unknown = set(tables) - set(PAPER_TABLES)
    if unknown:
        raise ValueError(f"tables must be among {list(PAPER_TABLES)}, got {sorted(unknown)}")
    if models is not None:
        bad = set(models) - set(MODEL_LABELS)
        if bad:
            raise ValueError(f"models must be among {list(MODEL_LABELS)}, got {sorted(bad)}")
    timings: dict[str, float] = {}

    t0 = time.perf_counter()
    jobs = []  # (table, protocol, selection, model)
    for t in tables:
        spec = PAPER_TABLES[t]
        for s in spec["selections"]:
            for m in spec["models"]:
                if models is None or m in models:
                    jobs.append((t, spec["protocol"], s, m))
    selections = sorted({s for t in tables for s in PAPER_TABLES[t]["selections"]})
    n_fits = sum(len(PROTOCOLS[p]["test_gears"]) if "test_gears" in PROTOCOLS[p]
                 else PROTOCOLS[p]["n_splits"] for _, p, _, _ in jobs)
    # one bar for the stage: loading, each selection's features, then every fit
    bar = tqdm(total=1 + len(selections) + n_fits, desc=f"study {name}".strip(),
               unit="step", disable=not progress)
    ds = load(dataset_path)
    bar.update()
    feats = {}
    for s in selections:
        feats[s] = extract_features(ds, s, **dict(feature_kwargs or {}))
        bar.update()
    timings["features"] = time.perf_counter() - t0
    log.info("features of selections %s in %.1f s", selections, timings["features"])

    splits_of: dict[tuple[str, int], list] = {}
    for _, p, s, _ in jobs:
        if (p, s) not in splits_of:
            kw = {**PROTOCOLS[p], **dict((protocol_kwargs or {}).get(p, {}))}
            splits_of[(p, s)] = make_splits(feats[s].meta, random_state=random_state, **kw)
    tasks = []  # one fit per (job, split), all tables in one stream
    for _, p, s, m in jobs:
        y = feats[s].meta["fault"].to_numpy()
        est = make_model(m, random_state=random_state, scale=scale)
        sps = splits_of[(p, s)]
        for sp in sps:  # the last split's model comes back to be logged
            tasks.append(delayed(fit_split_quiet)(est, feats[s].X, y, sp, class_labels(y),
                                                  return_model=track and log_models
                                                  and sp is sps[-1]))

    rows, confusion = [], []
    caught: Counter = Counter()
    bar.total = 1 + len(selections) + len(tasks)  # the protocols may change split counts
    bar.refresh()
    t_table = time.perf_counter()
    outs = Parallel(n_jobs=n_jobs, return_as="generator")(tasks)
    for t, p, s, m in jobs:  # results arrive in order; log each job while fits go on
        splits = splits_of[(p, s)]
        part = [next(outs) for _ in splits]
        bar.update(len(part))
        for o in part:
            caught.update(o[4])
        y = feats[s].meta["fault"].to_numpy()
        labels = class_labels(y)
        result = ProtocolResult(
            splits=splits,
            train_accuracy=np.array([o[0] for o in part]),
            test_accuracy=np.array([o[1] for o in part]),
            confusion=np.sum([o[2] for o in part], axis=0),
            labels=labels,
            fit_time_s=np.array([o[3] for o in part]),
        )
        run_id = None
        if track:
            model = part[-1][5] if log_models else None
            run_id = _log_study_job(result, t, p, s, m, dataset_path, random_state,
                                    scale, tracking_uri, experiment_prefix, group=group,
                                    model_fit=model, X_sample=feats[s].X[splits[-1].test[:5]])
        for i, sp in enumerate(splits):
            rows.append({
                "table": t, "protocol": p, "selection": f"selection{s}", "model": m,
                "split": sp.name, "split_label": sp.label,
                "train_accuracy": result.train_accuracy[i],
                "test_accuracy": result.test_accuracy[i],
                "fit_time_s": result.fit_time_s[i],
                "n_train": len(sp.train), "n_test": len(sp.test), "run_id": run_id,
            })
        for a, true in enumerate(labels):
            for b, pred in enumerate(labels):
                confusion.append((t, p, f"selection{s}", m, true, pred,
                                  int(result.confusion[a, b])))
        if (t, p, s, m) == [j for j in jobs if j[0] == t][-1]:
            timings[t] = time.perf_counter() - t_table
            t_table = time.perf_counter()
            log.info("Table %s done in %.1f s", t, timings[t])
    bar.close()
    results = pd.DataFrame(rows)
    confusion_df = pd.DataFrame(confusion, columns=["table", "protocol", "selection", "model",
                                                    "true", "predicted", "count"])
    spread = pd.concat([feature_spread(feats[s]).assign(selection=f"selection{s}")
                        for s in (1, 3) if s in feats], ignore_index=True) \
        if any(s in feats for s in (1, 3)) else pd.DataFrame()
    warn = [{"category": c, "message": msg, "count": n} for (c, msg), n in caught.items()]
    files = write_report(results, report_dir, ds=ds if figures else None, timings_s=timings,
                         dataset_path=str(dataset_path), confusion=confusion_df)
    return {"results": results, "confusion": confusion_df, "spread": spread,
            "warnings": warn, "timings_s": timings, "files": files, "n_jobs_run": len(jobs)}


def _log_study_job(result, table, protocol, selection, model, dataset_path, random_state,
                   scale, tracking_uri, experiment_prefix, group=None, model_fit=None,
                   X_sample=None) -> str:
    from learn.tracking import log_job

    est = make_model(model, random_state=random_state, scale=scale)
    params: dict[str, Any] = {
        "table": table, "protocol": protocol, "selection": f"selection{selection}",
        "model": model, "dataset": str(dataset_path), "random_state": random_state,
        "scale": scale, "protocol_spec": PROTOCOLS[protocol],
        "estimator": {k: v if isinstance(v, (bool, int, float, str, type(None))) else str(v)
                      for k, v in est.get_params(deep=True).items() if "__" in k},
    }
    params["protocol_spec"] = {k: list(v) if isinstance(v, tuple) else v
                               for k, v in PROTOCOLS[protocol].items()}
    return log_job(result, experiment=f"{experiment_prefix}{protocol}",
                   run_name=f"selection{selection}-{model}", params=params, config=params,
                   tracking_uri=tracking_uri, tags={"task": "paper_study", "table": table},
                   dataset=str(dataset_path), group=group, model=model_fit,
                   model_tags={"split": result.splits[-1].label}, X_sample=X_sample)
