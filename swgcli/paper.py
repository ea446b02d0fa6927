"""swgsim-paper: the main job — the paper's study under two data-set protocols, end to end.

For each protocol in ``protocols`` (default: the paper's phase-locked, noise-free windows
and a real bench's): (1) generate ``<data_root>/<protocol>`` (shards already there and
valid are skipped; a data set of another config there is replaced only if the folder
holds nothing else), (2) the study of Tables VII-X
(:func:`learn.tasks.paper.run_paper_study`), every job logged to MLflow, with its report
in ``<report_root>/<protocol>``; then (3) the summary side by side with the paper and the
reproduction scorecard (:func:`learn.reports.summary.write_summary`). One progress bar per
stage; the console ends with the scorecard, where everything went, the time of each stage
and the warnings, counted once. Config: ``conf/paper.yaml``.
"""

from __future__ import annotations

import logging
import time
import warnings
from collections import Counter

from omegaconf import DictConfig, OmegaConf

from swgcli.app import absolute_path, hydra_app
from swgcli.schema import PaperApp

log = logging.getLogger(__name__)


def _check(cfg: DictConfig) -> list[str]:
    """Validate the job's own keys before any work; return the protocols to run."""
    protocols = [str(p) for p in cfg.protocols]
    if not protocols:
        raise ValueError("protocols must name at least one of "
                         f"{sorted(cfg.datasets)}, got []")
    unknown = [p for p in protocols if p not in cfg.datasets]
    if unknown:
        raise ValueError(f"protocols: {unknown} not among the configured data sets "
                         f"{sorted(cfg.datasets)}")
    if len(set(protocols)) != len(protocols):
        raise ValueError(f"protocols must not repeat, got {protocols}")
    if int(cfg.n_jobs) < 1:
        raise ValueError(f"n_jobs must be >= 1, got {cfg.n_jobs}")
    return protocols


def run_paper(cfg: DictConfig) -> dict:
    """Run the main job from a composed ``paper`` config (task function).

    Returns
    -------
    dict
        ``stages_s`` (wall time of each stage [s]), ``generate`` and ``study`` (per
        protocol), ``summary`` (files, scorecards, findings), ``warnings`` (category,
        message, count).
    """
    from learn.reports.summary import format_scorecard, write_summary
    from learn.tasks.paper import run_paper_study
    from learn.tracking import default_tracking_uri
    from swgsim.generate import generate
    from swgsim.plan import plan

    protocols = _check(cfg)
    datasets = {p: OmegaConf.to_object(cfg.datasets[p]) for p in protocols}  # typed
    plans = {}
    for p in protocols:  # every data-set config is checked once, before any work
        try:
            plans[p] = plan(datasets[p])
        except ValueError as e:
            raise ValueError(f"datasets.{p}: {e}") from None
    from learn.tracking import check_tracking

    check_tracking(cfg.tracking_uri, "tracking_uri")  # before any work
    root_data, root_rep = absolute_path(str(cfg.data_root)), absolute_path(str(cfg.report_root))
    s = cfg.study
    n_stages = 2 * len(protocols) + 1
    stages: dict[str, float] = {}
    caught: Counter = Counter()
    gen, study = {}, {}
    t_all = time.perf_counter()
    k = 0
    with warnings.catch_warnings(record=True) as parent_warnings:
        warnings.simplefilter("default")
        for p in protocols:
            k += 1
            t0 = time.perf_counter()
            out = f"{root_data}/{p}"
            gen[p] = generate(plans[p], out, n_jobs=int(cfg.n_jobs), overwrite=True,
                              progress=True)
            stages[f"generate {p}"] = time.perf_counter() - t0
            state = (f"{len(gen[p]['computed'])} shard(s) simulated" if gen[p]["computed"]
                     else "already there and valid")
            if gen[p].get("replaced"):
                state += "; " + gen[p]["replaced"]
            print(f"[{k}/{n_stages}] data set {p}: {gen[p]['windows']} windows in {out} "
                  f"({state}), {stages[f'generate {p}']:.1f} s", flush=True)
        for p in protocols:
            k += 1
            t0 = time.perf_counter()
            study[p] = run_paper_study(
                f"{root_data}/{p}", f"{root_rep}/{p}", OmegaConf.to_object(s),
                tracking_uri=cfg.tracking_uri, log_models=cfg.log_models, n_jobs=cfg.n_jobs,
                random_state=cfg.seed, experiment_prefix=f"paper_study/{p}/", name=p)
            stages[f"study {p}"] = time.perf_counter() - t0
            for w in study[p]["warnings"]:
                caught[(w["category"], w["message"])] += w["count"]
            print(f"[{k}/{n_stages}] study {p}: {study[p]['n_jobs_run']} jobs, "
                  f"{len(study[p]['results'])} fits, {stages[f'study {p}']:.1f} s -> "
                  f"{root_rep}/{p}", flush=True)
        k += 1
        t0 = time.perf_counter()
        summary = write_summary(
            {p: study[p]["results"] for p in protocols},
            {p: study[p]["confusion"] for p in protocols}, root_rep, datasets,
            OmegaConf.to_object(s), cfg.seed, spread={p: study[p]["spread"] for p in protocols})
        stages["summary"] = time.perf_counter() - t0
        print(f"[{k}/{n_stages}] summary: {summary['files']['md']}", flush=True)
    for w in parent_warnings:
        caught[(w.category.__name__, str(w.message).splitlines()[0])] += 1
    stages["total"] = time.perf_counter() - t_all

    print("\nReproduction scorecard (test cells of Tables VII, IX, X against the paper):")
    print("\n".join(format_scorecard(summary["scorecards"])))
    for p in protocols:
        f = summary["findings"][p]
        print(f"qualitative findings of Sec. IV reproduced, {p} protocol: "
              f"{int((f['reproduced'] == True).sum())} of {int(f['reproduced'].notna().sum())}")  # noqa: E712
    print("\nwritten:")
    for p in protocols:
        print(f"  data set {p:<8s} {root_data}/{p}")
        print(f"  report {p:<10s} {root_rep}/{p}/ (tables_vii_x.md, results.csv, "
              "confusion.csv, figures)")
    print(f"  summary          {summary['files']['md']} (+ summary.csv, recall_rf.png)")
    print(f"  MLflow runs      {cfg.tracking_uri or default_tracking_uri()}  (browse: mlflow "
          "ui --backend-store-uri sqlite:///mlflow.db)")
    print("wall time per stage: " + ", ".join(f"{n} {v:.1f} s" for n, v in stages.items()))
    warn = [{"category": c, "message": m, "count": n} for (c, m), n in caught.most_common()]
    if warn:
        print("warnings (each counted once here, full text in the log):")
        for w in warn:
            print(f"  {w['count']:>4d} x {w['category']}: {w['message'][:110]}")
    return {"stages_s": stages, "generate": gen, "study": study, "summary": summary,
            "warnings": warn}


main = hydra_app("paper", PaperApp, "swgsim-paper")(run_paper)

if __name__ == "__main__":
    main()
