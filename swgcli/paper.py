"""swgsim-paper: the main job — the paper's study under two acquisitions, end to end.

For each data set in ``run_on`` (default: the paper's acquisition, phase-locked and
noise-free windows, and a real bench's): (1) generate ``<data_root>/<name>`` (shards
already there and valid are skipped; a data set of another config there is replaced only
if every file in the folder is provably this project's, :mod:`swgsim.files.ownership`), (2) the
study of Tables VII-X (:func:`learn.paper.task.run_paper_study`), every job logged to
MLflow, with its report in ``<report_root>/<name>``; then (3) the summary side by side
with the paper and the reproduction scorecard (:func:`learn.paper.summary.write_summary`)
in ``report_root``, a folder shared with the other apps' reports, where only the summary's
own files must be this project's. One progress bar per stage; the console ends with the
scorecard, where everything went, the time of each stage and the warnings, counted once.
Config: ``conf/paper.yaml``.
"""

from __future__ import annotations

import itertools
import time
import warnings
from collections import Counter

from omegaconf import DictConfig, OmegaConf

from learn.paper.summary import SUMMARY_FILES
from swgcli.app import hydra_app
from swgcli.schema import PaperApp
from swgsim.files import ownership
from swgsim.files.inputs import absolute_path


def _check(cfg: DictConfig) -> list[str]:
    """Validate the job's own keys before any work; return the data sets to run."""
    names = [str(p) for p in cfg.run_on]
    if not names:
        raise ValueError("run_on must name at least one of "
                         f"{sorted(cfg.datasets)}, got []")
    unknown = [p for p in names if p not in cfg.datasets]
    if unknown:
        raise ValueError(f"run_on: {unknown} not among the configured data sets "
                         f"{sorted(cfg.datasets)}")
    if len(set(names)) != len(names):
        raise ValueError(f"run_on must not repeat, got {names}")
    if int(cfg.n_jobs) < 1:
        raise ValueError(f"n_jobs must be >= 1, got {cfg.n_jobs}")
    return names


def check_inputs(cfg: DictConfig) -> dict:
    """Every key, data set and report folder of the run checked once, before any work and
    before the libraries are imported (:func:`swgcli.app.hydra_app`'s ``inputs``).

    Parameters
    ----------
    cfg : DictConfig
        Composed ``conf/paper.yaml``.

    Returns
    -------
    dict
        Data-set name -> :class:`swgsim.datasets.plan.DatasetPlan`, in ``run_on`` order.

    Raises
    ------
    ValueError
        A bad key or data-set config (named), or a report folder holding a file this
        project cannot show it wrote (:func:`swgsim.files.ownership.check`): in
        ``report_root`` one of the summary's files, anything in ``<report_root>/<name>``.
    """
    plans = _plans(cfg, _check(cfg))
    root_rep = absolute_path(str(cfg.report_root))
    ownership.check(root_rep, "report_root", only=SUMMARY_FILES,
                    app="swgsim-paper")  # shared: our files only
    for n in plans:
        ownership.check(f"{root_rep}/{n}", "report_root", app="paper-study")
    return plans


def _plans(cfg: DictConfig, names: list[str]) -> dict:
    """Every data set of the run checked once, before any work: name -> DatasetPlan."""
    from swgsim.datasets.plan import plan

    plans = {}
    for n in names:
        try:
            plans[n] = plan(OmegaConf.to_object(cfg.datasets[n]))  # the typed DatasetConfig
        except ValueError as e:
            raise ValueError(f"datasets.{n}: {e}") from None
    return plans


def _generate(cfg: DictConfig, plans: dict, root_data: str, stage, stages: dict) -> dict:
    """Stage 1: each data set generated (or found valid) in ``<root_data>/<name>``."""
    from swgsim.datasets.generate import generate

    gen = {}
    for n, p in plans.items():
        t0 = time.perf_counter()
        out = f"{root_data}/{n}"
        gen[n] = g = generate(p, out, n_jobs=int(cfg.n_jobs), overwrite=True, progress=True)
        stages[f"generate {n}"] = time.perf_counter() - t0
        state = (f"{len(g['computed'])} shard(s) simulated" if g["computed"]
                 else "already there and valid")
        if g.get("replaced"):
            state += "; " + g["replaced"]
        print(f"[{stage()}] data set {n}: {g['windows']} windows in {out} ({state}), "
              f"{stages[f'generate {n}']:.1f} s", flush=True)
    return gen


def _studies(cfg: DictConfig, names: list[str], root_data: str, root_rep: str, stage,
             stages: dict, caught: Counter) -> dict:
    """Stage 2: the paper's study on each data set, its report and MLflow runs."""
    from learn.paper.task import run_paper_study

    study = {}
    for n in names:
        t0 = time.perf_counter()
        study[n] = run_paper_study(
            f"{root_data}/{n}", f"{root_rep}/{n}", OmegaConf.to_object(cfg.study),
            tracking_uri=cfg.tracking_uri, log_models=cfg.log_models, n_jobs=cfg.n_jobs,
            random_state=cfg.seed, experiment_prefix=f"paper/{n}/", name=n)
        stages[f"study {n}"] = time.perf_counter() - t0
        for w in study[n]["warnings"]:
            caught[(w["category"], w["message"])] += w["count"]
        print(f"[{stage()}] study {n}: {study[n]['n_jobs_run']} jobs, "
              f"{len(study[n]['results'])} fits, {stages[f'study {n}']:.1f} s -> "
              f"{root_rep}/{n}", flush=True)
    return study


def _print_end(cfg: DictConfig, names: list[str], summary: dict, root_data: str,
               root_rep: str, stages: dict, warn: list[dict]) -> None:
    """The console's last words: scorecard, findings, where everything went, times."""
    from learn.paper.summary import format_scorecard
    from learn.tracking.store import default_tracking_uri

    print("\nReproduction scorecard (test cells of Tables VII, IX, X against the paper):")
    print(format_scorecard(summary["scorecards"]))
    for n in names:
        f = summary["findings"][n]
        print(f"qualitative findings of Sec. IV reproduced, {n} acquisition: "
              f"{int((f['reproduced'] == True).sum())} of {int(f['reproduced'].notna().sum())}")  # noqa: E712
    print("\nwritten:")
    for n in names:
        print(f"  data set {n:<8s} {root_data}/{n}")
        print(f"  report {n:<10s} {root_rep}/{n}/ (tables_vii_x.md, results.csv, "
              "confusion.csv, figures)")
    print(f"  summary          {summary['files']['md']} (+ summary.csv, recall_rf.png)")
    uri = cfg.tracking_uri or default_tracking_uri()
    print(f"  MLflow runs      {uri}  (browse: mlflow ui --backend-store-uri {uri})")
    print("wall time per stage: " + ", ".join(f"{n} {v:.1f} s" for n, v in stages.items()))
    if warn:
        print("warnings (each counted once here, full text in the log):")
        for w in warn:
            print(f"  {w['count']:>4d} x {w['category']}: {w['message'][:110]}")


def run_paper(cfg: DictConfig) -> dict:
    """Run the main job from a composed ``paper`` config (task function).

    Returns
    -------
    dict
        ``stages_s`` (wall time of each stage [s]), ``generate`` and ``study`` (per data
        set), ``summary`` (files, scorecards, findings), ``warnings`` (category, message,
        count).

    Raises
    ------
    ValueError
        A bad key, or a folder holding a file this project cannot show it wrote, named
        (:mod:`swgsim.files.ownership`): in ``report_root`` one of the summary's files, or
        anything in ``<report_root>/<name>`` (both before any work) or in
        ``<data_root>/<name>`` (when that data set is due).
    """
    from learn.paper.summary import write_summary
    from learn.tracking.store import check_tracking

    plans = check_inputs(cfg)
    names = list(plans)
    check_tracking(cfg.tracking_uri, "tracking_uri")  # before any work
    root_data, root_rep = absolute_path(str(cfg.data_root)), absolute_path(str(cfg.report_root))
    counter, n_stages = itertools.count(1), 2 * len(names) + 1

    def stage() -> str:
        return f"{next(counter)}/{n_stages}"

    stages: dict[str, float] = {}
    caught: Counter = Counter()
    t_all = time.perf_counter()
    with warnings.catch_warnings(record=True) as parent_warnings:
        warnings.simplefilter("default")
        gen = _generate(cfg, plans, root_data, stage, stages)
        study = _studies(cfg, names, root_data, root_rep, stage, stages, caught)
        t0 = time.perf_counter()
        with ownership.claim(root_rep, "swgsim-paper", "report_root",
                             only=SUMMARY_FILES, strict=True) as claim:
            summary = write_summary(
                {n: study[n]["results"] for n in names},
                {n: study[n]["confusion"] for n in names}, root_rep,
                {n: plans[n].config for n in names}, OmegaConf.to_object(cfg.study),
                cfg.seed, spread={n: study[n]["spread"] for n in names})
            claim.record(summary["files"].values())
        stages["summary"] = time.perf_counter() - t0
        print(f"[{stage()}] summary: {summary['files']['md']}", flush=True)
    for w in parent_warnings:
        caught[(w.category.__name__, str(w.message).splitlines()[0])] += 1
    stages["total"] = time.perf_counter() - t_all
    warn = [{"category": c, "message": m, "count": n} for (c, m), n in caught.most_common()]
    _print_end(cfg, names, summary, root_data, root_rep, stages, warn)
    return {"stages_s": stages, "generate": gen, "study": study, "summary": summary,
            "warnings": warn}


#: The libraries its runs import, resolved before any work
#: (:func:`learn.tracking.preflight.check_imports`).
NEEDS = ("numpy", "scipy", "pandas", "xarray", "h5netcdf", "joblib", "sklearn", "torch", "mlflow",
         "matplotlib")


main = hydra_app("paper", PaperApp, "swgsim-paper", NEEDS, inputs=check_inputs)(run_paper)

if __name__ == "__main__":
    main()
