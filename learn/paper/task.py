"""The paper's study with its report: :func:`run_paper_study` (the public entry point, also
behind ``swgsim-paper``) and :func:`run_paper_study_task` (``swgsim-train
experiment=paper``)."""

from __future__ import annotations

import time
from pathlib import Path

from learn.inputs.features import FeatureSettings
from learn.paper.study import StudyTracking, paper_study
from learn.paper.tables import StudyOptions
from learn.studies.protocols import ProtocolConfig
from learn.tasks.config import typed_app


def run_paper_study(
    dataset_path: str | Path,
    report_dir: str | Path,
    options: StudyOptions | None = None,
    *,
    tracking_uri: str | None = None,
    track: bool = True,
    log_models: bool = StudyTracking.log_models,
    experiment_prefix: str = StudyTracking.experiment_prefix,
    n_jobs: int = 1,
    progress: bool = True,
    random_state: int = 0,
    features: FeatureSettings | None = None,
    protocols: dict[str, ProtocolConfig] | None = None,
    name: str = "",
) -> dict:
    """Run the paper's study, Tables VII-X (:func:`learn.paper.study.paper_study`),
    and write its report (:func:`learn.paper.report.write_report`).

    Parameters
    ----------
    dataset_path : path-like
        Schema-v1 data set with clean and disturbed windows and reference windows.
    report_dir : path-like
        Folder of the report, e.g. ``reports/paper``.
    options : StudyOptions, optional
        Tables, models, scaling and figures; default the paper's study.
    tracking_uri : str, optional
        MLflow tracking URI; default :func:`learn.tracking.store.default_tracking_uri`.
    track : bool, default True
        Log one MLflow run per job, in experiment ``experiment_prefix + protocol``; the
        jobs of one call are children of one parent run per experiment (group
        ``"study <name> <start time>"``).
    log_models : bool, default True
        With ``track``, also log each job's model fitted on its last split (no refit).
    experiment_prefix : str, default "paper/"
        The naming scheme (docs/apps.md, "MLflow experiments and runs"): ``paper/<data
        set>/`` for the main job and ``swgsim-train experiment=paper``.
    n_jobs, progress, random_state, features, protocols, name
        See :func:`learn.paper.study.paper_study`.

    Returns
    -------
    dict
        ``results``, ``confusion``, ``spread``, ``warnings``, ``timings_s``, ``n_jobs_run``
        (:class:`learn.paper.study.PaperStudyResult`) and ``files`` (report files
        by kind).

    Raises
    ------
    ValueError
        For an unknown table or model, or a ``report_dir`` holding a file this project
        cannot show it wrote (named; before any work, :func:`swgsim.files.ownership.check`).
    """
    from learn.paper.report import write_report
    from swgsim.files import ownership

    ownership.check(report_dir, "report_dir", app="paper-study")  # before any work
    options = options or StudyOptions()
    tracking = None
    if track:
        group = f"study {name or Path(dataset_path).name} {time.strftime('%Y-%m-%d %H:%M:%S')}"
        tracking = StudyTracking(tracking_uri, experiment_prefix, log_models, group)
    study = paper_study(dataset_path, options, tracking=tracking, n_jobs=n_jobs,
                        progress=progress, random_state=random_state, features=features,
                        protocols=protocols, name=name)
    with ownership.claim(report_dir, "paper-study", "report_dir", strict=True,
                         fresh=True) as claim:  # figures=false leaves no earlier figure
        files = write_report(study.results, report_dir,
                             ds=study.ds if options.figures else None,
                             timings_s=study.timings_s, dataset_path=str(dataset_path),
                             confusion=study.confusion)
        claim.record(files.values())
    return {"results": study.results, "confusion": study.confusion, "spread": study.spread,
            "warnings": study.warnings, "timings_s": study.timings_s, "files": files,
            "n_jobs_run": study.n_jobs_run}


def run_paper_study_task(cfg) -> dict:
    """Task ``paper_study``: :func:`run_paper_study` from ``swgsim-train``'s typed config.

    Uses ``data.path``, ``paths.report_dir``/paper, ``logger``
    (:class:`learn.tracking.config.LoggerConfig`; None: no tracking; its ``tracking_uri``
    and ``log_models``), ``n_jobs``, ``seed``, ``features`` (orders and floor; the
    selections are those of the tables) and ``study``
    (:class:`learn.paper.tables.StudyOptions`).

    Parameters
    ----------
    cfg : swgcli.schema.TrainApp or omegaconf.DictConfig
        The typed app config (:func:`learn.tasks.config.typed_app`).

    Returns
    -------
    dict
        ``timings_s``, ``files`` (report paths as str), ``n_jobs_run`` and
        ``mean_test_accuracy`` keyed by ``"table/selection/model"``.
    """
    app = typed_app(cfg)
    logger = app.logger
    out = run_paper_study(
        app.stored.path, Path(app.paths.report_dir) / "paper", app.study,
        tracking_uri=None if logger is None else logger.tracking_uri,
        track=logger is not None, log_models=logger is not None and logger.log_models,
        n_jobs=app.n_jobs, random_state=app.seed, features=app.features,
        experiment_prefix=f"paper/{app.stored.name}/")
    res = out.pop("results")
    means = res.groupby(["table", "selection", "model"])["test_accuracy"].mean()
    out["mean_test_accuracy"] = {"/".join(k): float(v) for k, v in means.items()}
    out["files"] = {k: str(v) for k, v in out["files"].items()}
    return out
