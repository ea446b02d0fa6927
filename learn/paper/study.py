"""The paper's fault-classification study (Sec. IV, Tables VII-X), computed.

:func:`paper_study` runs every job (table, protocol, feature selection, model) of the
tables chosen by :class:`learn.paper.tables.StudyOptions` on one data set: the
features of each selection once, the splits of each protocol once, every (job, split) fit
in one stream of joblib processes, one MLflow run per job (one confusion figure redrawn
for all). It writes no report; :func:`learn.paper.task.run_paper_study` adds it. The
steps, in order: :func:`plan_jobs`, :func:`compute_features`, :func:`plan_splits`,
:func:`fit_tasks`, :func:`collect_job` per job, :func:`feature_spreads`.
"""

from __future__ import annotations

import dataclasses
import logging
import time
from collections import Counter
from collections.abc import Iterator, Mapping
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from learn.inputs.features import Features, FeatureSettings, iter_features, selection_name
from learn.learners.models import make_model
from learn.paper.tables import StudyOptions
from learn.studies.protocols import (
    PROTOCOLS,
    ProtocolConfig,
    ProtocolResult,
    Split,
    class_labels,
    fit_split_quiet,
)
from learn.tracking.config import LoggerConfig
from learn.tracking.mlflow_runs import ConfusionFigure
from swgsim.base.lazy import lazy_module
from swgsim.base.registry import travelling

pd = lazy_module("pandas")

log = logging.getLogger(__name__)

CONFUSION_COLUMNS = ("table", "protocol", "selection", "model", "true", "predicted", "count")


@dataclass(frozen=True)
class StudyJob:
    """One job of the study: a model under a table's protocol on one feature selection."""

    table: str
    protocol: str
    selection: int
    model: str

    @property
    def selection_name(self) -> str:
        """``selection1`` .. (:data:`learn.inputs.features.SELECTIONS`)."""
        return selection_name(self.selection)


@dataclass(frozen=True)
class StudyTracking:
    """Where and how the study's jobs are logged to MLflow.

    Attributes
    ----------
    tracking_uri : str or None
        None: :func:`learn.tracking.store.default_tracking_uri`.
    experiment_prefix : str
        Experiment of a job: prefix + protocol.
    log_models : bool
        Also log each job's model fitted on its last split (the protocol's own fit,
        returned by the worker: no refit).
    group : str
        Parent run that holds the jobs of one call (one per experiment).
    """

    tracking_uri: str | None = None
    experiment_prefix: str = "paper/"
    log_models: bool = LoggerConfig.log_models
    group: str = ""


@dataclass
class PaperStudyResult:
    """What :func:`paper_study` computed.

    Attributes
    ----------
    results : pandas.DataFrame
        One row per job and split: table, protocol, selection, model, split, split_label,
        train_accuracy, test_accuracy, fit_time_s, n_train, n_test, run_id.
    confusion : pandas.DataFrame
        :data:`CONFUSION_COLUMNS`, summed over splits.
    spread : pandas.DataFrame
        :func:`learn.inputs.features.feature_spread` of Selections 1 and 3 where computed.
    warnings : list of dict
        ``category``, ``message``, ``count``: what the fits raised.
    timings_s : dict of str to float
        Features and each table [s].
    n_jobs_run : int
    ds : xarray.Dataset or None
        The data set (for the figures of the report).
    """

    results: pd.DataFrame
    confusion: pd.DataFrame
    spread: pd.DataFrame
    warnings: list[dict]
    timings_s: dict[str, float]
    n_jobs_run: int
    ds: Any = field(default=None, repr=False)


def plan_jobs(options: StudyOptions) -> list[StudyJob]:
    """Every job of the chosen tables, in the order of the tables, selections and models.

    Raises
    ------
    ValueError
        An unknown table or model (:meth:`StudyOptions.check`).
    """
    options.check()
    return [StudyJob(t.name, t.protocol, s, m) for t in options.selected_tables()
            for s in t.selections for m in options.table_models(t)]


def compute_features(ds, selections: list[int], settings: FeatureSettings,
                     bar=None) -> dict[int, Features]:
    """Features of each selection, computed once for every table that uses it (what the
    selections share read once, :func:`learn.inputs.features.iter_features`)."""
    out = {}
    for s, feats in zip(selections, iter_features(ds, selections, **settings.kwargs()),
                        strict=True):
        out[s] = feats
        if bar is not None:
            bar.update()
    return out


def plan_splits(jobs: list[StudyJob], feats: Mapping[int, Features],
                protocols: Mapping[str, ProtocolConfig],
                random_state: int) -> dict[tuple[str, int], list[Split]]:
    """Splits of each (protocol, selection), the CV shuffled by ``random_state``; made
    once per protocol for selections of the same windows (equal ``meta``: those of one
    data set)."""
    out: dict[tuple[str, int], list[Split]] = {}
    for j in jobs:
        if (j.protocol, j.selection) in out:
            continue
        meta = feats[j.selection].meta
        made = next((sps for (p, s), sps in out.items()
                     if p == j.protocol and feats[s].meta.equals(meta)), None)
        if made is None:
            p = dataclasses.replace(protocols[j.protocol], random_state=random_state)
            made = p.splits(meta)
        out[(j.protocol, j.selection)] = made
    return out


def fit_tasks(jobs: list[StudyJob], feats: Mapping[int, Features],
              splits_of: Mapping[tuple[str, int], list[Split]], scale: bool,
              random_state: int, return_models: bool) -> list:
    """One delayed :func:`learn.studies.protocols.fit_split_quiet` per (job, split), in job
    order; the last split of a job returns its model if ``return_models``."""
    from joblib import delayed

    tasks, fit = [], travelling(fit_split_quiet)  # a user's learners travel with the fits
    y_of = {s: f.meta["fault"].to_numpy() for s, f in feats.items()}
    labels_of = {s: class_labels(y) for s, y in y_of.items()}  # once per selection
    for j in jobs:
        y, labels = y_of[j.selection], labels_of[j.selection]
        est = make_model(j.model, random_state=random_state, scale=scale)
        sps = splits_of[(j.protocol, j.selection)]
        for sp in sps:
            tasks.append(delayed(fit)(est, feats[j.selection].X, y, sp, labels,
                                      return_model=return_models and sp is sps[-1]))
    return tasks


def collect_job(outs: Iterator, splits: list[Split], labels: list[str]
                ) -> tuple[ProtocolResult, Counter, Any]:
    """The next ``len(splits)`` fit outputs as one job's result, its warnings and the
    last split's model (None unless returned)."""
    part = [next(outs) for _ in splits]
    caught: Counter = Counter()
    for o in part:
        caught.update(o[4])
    return (ProtocolResult.from_fits(splits, part, labels), caught,
            part[-1][5] if len(part[-1]) > 5 else None)


def job_rows(job: StudyJob, result: ProtocolResult, run_id: str | None
             ) -> tuple[list[dict], list[tuple]]:
    """Rows of ``results`` (one per split) and of ``confusion`` of one job."""
    rows = [{"table": job.table, "protocol": job.protocol, "selection": job.selection_name,
             "model": job.model, "split": sp.name, "split_label": sp.label,
             "train_accuracy": result.train_accuracy[i],
             "test_accuracy": result.test_accuracy[i], "fit_time_s": result.fit_time_s[i],
             "n_train": len(sp.train), "n_test": len(sp.test), "run_id": run_id}
            for i, sp in enumerate(result.splits)]
    conf = [(job.table, job.protocol, job.selection_name, job.model, true, pred,
             int(result.confusion[a, b]))
            for a, true in enumerate(result.labels) for b, pred in enumerate(result.labels)]
    return rows, conf


def feature_spreads(feats: Mapping[int, Features]) -> pd.DataFrame:
    """:func:`learn.inputs.features.feature_spread` of Selections 1 and 3 where computed."""
    from learn.inputs.features import feature_spread

    parts = [feature_spread(feats[s]).assign(selection=selection_name(s))
             for s in (1, 3) if s in feats]
    return pd.concat(parts, ignore_index=True) if parts else pd.DataFrame()


def paper_study(
    dataset_path: str | Path,
    options: StudyOptions | None = None,
    *,
    tracking: StudyTracking | None = None,
    n_jobs: int = 1,
    progress: bool = True,
    random_state: int = 0,
    features: FeatureSettings | None = None,
    protocols: Mapping[str, ProtocolConfig] | None = None,
    name: str = "",
) -> PaperStudyResult:
    """Run the paper's study (Tables VII-X) on one data set; see the module docstring.

    Parameters
    ----------
    dataset_path : path-like
        Schema-v1 data set with clean and disturbed windows and reference windows.
    options : StudyOptions, optional
        Tables, models and scaling; default the paper's study.
    tracking : StudyTracking, optional
        One MLflow run per job (with the git commit, the data set and its params); None:
        no tracking.
    n_jobs : int, default 1
        Fits run in parallel (joblib processes), over every (job, split) of every table.
    progress : bool, default True
        One tqdm progress bar for the stage (loading, features, fits).
    random_state : int, default 0
        Seed of the CV folds and of MLP, SVM and RF.
    features : FeatureSettings, optional
        DFT orders and floor of the features (the selections are the tables').
    protocols : mapping of str to ProtocolConfig, optional
        Protocols that replace the paper's of the same name (:data:`PROTOCOLS`), e.g.
        ``{"cv_clean": ProtocolConfig.paper("cv_clean", scheme="kfold")}`` (sensitivity
        studies); their ``random_state`` is replaced by ``random_state``.
    name : str, optional
        Name of the data set (protocol) for the progress bar.

    Returns
    -------
    PaperStudyResult

    Raises
    ------
    ValueError
        For an unknown table or model.
    """
    from joblib import Parallel
    from tqdm.auto import tqdm

    from swgsim.datasets.schema import load

    options = options or StudyOptions()
    protocols = {**PROTOCOLS, **dict(protocols or {})}
    jobs = plan_jobs(options)
    timings: dict[str, float] = {}
    t0 = time.perf_counter()
    selections = sorted({s for t in options.selected_tables() for s in t.selections})
    n_fits = sum(protocols[j.protocol].n_planned for j in jobs)
    # one bar for the stage: loading, each selection's features, then every fit
    bar = tqdm(total=1 + len(selections) + n_fits, desc=f"study {name}".strip(),
               unit="step", disable=not progress)
    ds = load(dataset_path)
    bar.update()
    feats = compute_features(ds, selections, features or FeatureSettings(), bar)
    timings["features"] = time.perf_counter() - t0
    log.info("features of selections %s in %.1f s", selections, timings["features"])
    splits_of = plan_splits(jobs, feats, protocols, random_state)
    log_models = tracking is not None and tracking.log_models
    tasks = fit_tasks(jobs, feats, splits_of, options.scale, random_state, log_models)
    bar.total = 1 + len(selections) + len(tasks)  # the protocols may change split counts
    bar.refresh()
    run = _JobLogging(str(dataset_path), random_state, options.scale, protocols, tracking)
    outs = Parallel(n_jobs=n_jobs, return_as="generator")(tasks)
    rows, confusion, caught = _collect_jobs(jobs, outs, splits_of, feats, run, bar, timings)
    bar.close()
    return PaperStudyResult(
        results=pd.DataFrame(rows),
        confusion=pd.DataFrame(confusion, columns=list(CONFUSION_COLUMNS)),
        spread=feature_spreads(feats),
        warnings=[{"category": c, "message": m, "count": n} for (c, m), n in caught.items()],
        timings_s=timings, n_jobs_run=len(jobs), ds=ds)


@dataclass
class _JobLogging:
    """What logging a job of one study call needs (:func:`log_study_job`), and the
    confusion figure its jobs are drawn on."""

    dataset_path: str
    random_state: int
    scale: bool
    protocols: Mapping[str, ProtocolConfig]
    tracking: StudyTracking | None
    figure: ConfusionFigure = field(default_factory=ConfusionFigure)

    def log(self, job: StudyJob, result: ProtocolResult, model, X_sample) -> str | None:
        if self.tracking is None:
            return None
        return log_study_job(result, job, self.dataset_path, self.random_state, self.scale,
                             self.protocols[job.protocol], self.tracking, model=model,
                             X_sample=X_sample, figure=self.figure)


def _collect_jobs(jobs: list[StudyJob], outs, splits_of: Mapping, feats: Mapping,
                  run: _JobLogging, bar, timings: dict[str, float]
                  ) -> tuple[list[dict], list[tuple], Counter]:
    """Each job's result from the fits' outputs (in order), logged while fits go on: the
    result rows, the confusion rows and the warnings caught; ``timings`` gets each
    table's time [s]."""
    rows, confusion, caught = [], [], Counter()
    last_of_table = {j.table: j for j in jobs}
    labels_of = {s: class_labels(f.meta["fault"].to_numpy()) for s, f in feats.items()}
    t_table = time.perf_counter()
    for j in jobs:  # results arrive in order; log each job while fits go on
        splits = splits_of[(j.protocol, j.selection)]
        f = feats[j.selection]
        result, c, model = collect_job(outs, splits, labels_of[j.selection])
        bar.update(len(splits))
        caught.update(c)
        run_id = run.log(j, result, model, f.X[splits[-1].test[:5]])
        r, c = job_rows(j, result, run_id)
        rows += r
        confusion += c
        if j is last_of_table[j.table]:
            timings[j.table] = time.perf_counter() - t_table
            t_table = time.perf_counter()
            log.info("Table %s done in %.1f s", j.table, timings[j.table])
    return rows, confusion, caught


def log_study_job(result: ProtocolResult, job: StudyJob, dataset_path: str,
                  random_state: int, scale: bool, protocol: ProtocolConfig,
                  tracking: StudyTracking, model=None, X_sample=None,
                  figure: ConfusionFigure | None = None) -> str:
    """Log one job of the study (:func:`learn.tracking.log_job`); return its run id.

    Parameters
    ----------
    result : ProtocolResult
    job : StudyJob
    dataset_path : str
    random_state : int
    scale : bool
    protocol : ProtocolConfig
        The protocol that ran (its :meth:`ProtocolConfig.spec` is logged).
    tracking : StudyTracking
    model : estimator, optional
        Fitted on the last split, to be logged.
    X_sample : ndarray, optional
        A few rows of the features (the model's input example).
    figure : ConfusionFigure, optional
        Where the confusion matrix is drawn (one for all jobs of a study).

    Returns
    -------
    str
        MLflow run id.
    """
    from learn.learners.devices import net_record
    from learn.tracking import log_job

    est = make_model(job.model, random_state=random_state, scale=scale)
    params: dict[str, Any] = {
        "table": job.table, "protocol": job.protocol, "selection": job.selection_name,
        "model": job.model, "dataset": dataset_path, "random_state": random_state,
        "scale": scale, "protocol_spec": protocol.spec(),
        "estimator": {k: v if isinstance(v, (bool, int, float, str, type(None))) else str(v)
                      for k, v in est.get_params(deep=True).items() if "__" in k},
        **net_record(model if model is not None else est),  # where a torch net ran
    }
    return log_job(result, experiment=f"{tracking.experiment_prefix}{job.protocol}",
                   run_name=f"{job.selection_name}-{job.model}", params=params, config=params,
                   tracking_uri=tracking.tracking_uri,
                   tags={"task": "paper_study", "table": job.table}, dataset=dataset_path,
                   group=tracking.group or None, model=model, figure=figure,
                   model_tags={"split": result.splits[-1].label}, X_sample=X_sample)

