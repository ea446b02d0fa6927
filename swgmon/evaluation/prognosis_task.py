"""Task ``prognosis`` (``swgsim-train experiment=prognosis``): the prognosis's
leave-one-gear-out evaluation on lives that run to failure
(:mod:`.prognosis_evaluation`), its tables, targets and figure
(:mod:`.prognosis_report`) and an MLflow run.

Files in ``report_dir``: ``results.csv`` (one row per prognosis and method), ``lives.csv``
(one row per life), ``calibration.csv`` (the lower and upper conformal scales per data
set, method, fault (and pooled) and quarter of the true remaining share),
``scores.csv`` (each life's scores per method), ``changes.csv`` (each life with a payload
change against its twin without it, per method), ``table.md``, ``prognosis.png``,
``timing.json``, ``models/<dataset>_prognosis.skops`` with its ``.card.json`` (each data
set's diagnosis model) and ``parts/``: per data set its design part (the model trained
and the intervals calibrated), then one part per held-out instance (its lives), each with
the hash of the config that made it (:func:`learn.tasks.parts.part_key`), so that a rerun
of the same config resumes from them and a stopped run loses at most one part per worker
(the staged parts of :mod:`learn.tasks.parts`, as the benchmark's).
"""

from __future__ import annotations

import dataclasses
import logging
from dataclasses import dataclass, field
from functools import partial
from pathlib import Path

from learn.tasks.config import typed_app
from learn.tasks.parts import (
    DESIGN,
    EvaluationExperiment,
    Job,
    part_key,
    resumed_note,
    run_group,
    write_csvs,
)
from learn.tracking import log_run
from learn.tracking.ledger import append_scored_run
from swgmon.assessment.model_io import MODEL_SUFFIX, load_model, save_model
from swgmon.evaluation.benchmark import instances
from swgmon.evaluation.prognosis_evaluation import (
    PrognosisStudyConfig,
    prognosis_design,
    prognosis_lives,
)
from swgmon.evaluation.prognosis_report import (
    CHANGE_COLUMNS,
    bucket_table,
    change_table,
    figure,
    life_scores,
    summary_table,
    targets,
    write_table,
)
from swgsim.base.lazy import lazy_module
from swgsim.base.typed import check_tree, plain
from swgsim.datasets.plan import DatasetPlan
from swgsim.files import ownership
from swgsim.files.ownership import atomic_write_json

pd = lazy_module("pandas")

log = logging.getLogger(__name__)


@dataclass
class PrognosisExperiment(EvaluationExperiment):
    """``prognosis`` group of ``swgsim-train``: the shared keys
    (:class:`learn.tasks.parts.EvaluationExperiment`: ``run_on``, ``datasets`` - their
    own ``life`` is not used, the study makes the lives -, ``report_dir``, ``n_jobs``,
    ``progress``, ``group``) and the prognosis's study.

    Attributes
    ----------
    study : PrognosisStudyConfig
        The evaluation's design.
    report_dir : str
        Default ``reports/prognosis`` [choice].
    """

    study: PrognosisStudyConfig = field(default_factory=PrognosisStudyConfig)
    report_dir: str = "reports/prognosis"


def plan_parts(pc: PrognosisExperiment, plans: dict[str, DatasetPlan]
               ) -> tuple[list[Job], list[Job]]:
    """Each data set's design part and its lives' parts (one per held-out instance), each
    keyed by the hash of the data set's config, the study and the part."""
    study = dataclasses.asdict(pc.study)
    design, lives = [], []
    for name, p in plans.items():
        base = {"dataset": p.config_hash, "study": study, "task": "prognosis"}
        design.append(Job(name, 0, DESIGN, part_key({**base, "part": DESIGN})))
        lives += [Job(name, g, None, part_key({**base, "gear": g}))
                  for g in instances(pc.study)[1]]
    return design, lives


def run_prognosis_evaluation(cfg) -> dict:
    """Run the evaluation (module docstring); return its summary.

    Raises
    ------
    ValueError
        A bad ``prognosis`` key or data set, a lot without two training instances,
        ``prognosis.group`` beyond the groups or a lives group before its data set's
        design part, an unwritable MLflow store, or a ``report_dir`` holding a file this
        project cannot show it wrote (named); before any work.
    """
    app = typed_app(cfg)
    pc: PrognosisExperiment = app.prognosis
    check_tree(pc.study, "prognosis.study")  # its training design, ..., then its rules
    plans = pc.plans("prognosis")  # every data set's config checked before any work
    return pc.run_stages("prognosis", plans, app.logger, *plan_parts(pc, plans), _design,
                         _lives, partial(_evaluate, app, pc, plans))


def _model_path(out: str | Path, dataset: str) -> Path:
    return Path(out) / "models" / f"{dataset}_prognosis{MODEL_SUFFIX}"


def _design(plan_: DatasetPlan, jobs: list[Job], study: PrognosisStudyConfig, out: str
            ) -> list[tuple[dict, Job]]:
    """A data set's design part in a worker: its model, written to ``models/``, and
    its calibration (:func:`~.prognosis_evaluation.prognosis_design`)."""
    ownership.join(out, "prognosis")

    def one(job: Job) -> dict:
        model, part = prognosis_design(plan_, job.dataset, study)
        save_model(model, _model_path(out, job.dataset),
                   [{"name": job.dataset, "config_hash": plan_.config_hash,
                     "gears": instances(study)[0],
                     "simulated": "training lives of swgmon.evaluation.training"}],
                   without=study.cross_validation)
        return part
    return run_group(out, jobs, one)


def _lives(plan_: DatasetPlan, jobs: list[Job], study: PrognosisStudyConfig, out: str,
           design: dict) -> list[tuple[dict, Job]]:
    """One held-out instance's lives in a worker, by its data set's model and design
    (:func:`~.prognosis_evaluation.prognosis_lives`)."""
    ownership.join(out, "prognosis")
    model = load_model(_model_path(out, jobs[0].dataset))
    return run_group(out, jobs, lambda j: prognosis_lives(plan_, j.dataset, study, model,
                                                          design, j.gear))


def _frames(designs: list[dict], parts: list[dict]) -> tuple[pd.DataFrame, ...]:
    """Results, lives, payload changes and calibration tables of the parts."""
    rows = pd.DataFrame([r for p in parts for r in p["rows"]])
    lives = pd.DataFrame([r for p in parts for r in p["lives"]])
    changes = pd.DataFrame([r for p in parts for r in p.get("changes", [])],
                           columns=CHANGE_COLUMNS)
    cal = pd.DataFrame([{"dataset": d["dataset"], **c} for d in designs
                        for c in d["calibration"]])
    return rows, lives, changes, cal


def _evaluate(app, pc: PrognosisExperiment, plans: dict, out: Path, claim,
              designs: list[dict], parts: list[dict], wall: float, resumed: int) -> dict:
    """The report of the parts into the claimed ``out`` (every file it writes
    recorded)."""
    rows, lives, changes, cal = _frames(designs, parts)
    if rows.empty:
        raise ValueError("prognosis: no life was followed to a prognosis (no alarm named "
                         "a growing fault); nothing to score")
    rows["valid"] = rows["valid"].astype(bool)
    goal, nominal = pc.study.targets, pc.study.coverage
    scores = life_scores(rows, lives, goal)
    buckets, summary = bucket_table(rows, goal), summary_table(scores)
    moved = change_table(changes, goal)
    tgt = targets(buckets, summary, moved, goal, nominal)
    csvs = write_csvs(out, {"results.csv": rows, "lives.csv": lives, "calibration.csv": cal,
                            "scores.csv": scores, "changes.csv": changes})
    not_run = {f"{d['dataset']}: {f}": w for d in designs for f, w in d["not_run"].items()}
    atomic_write_json(out / "timing.json", {"wall_s": wall, "resumed": resumed, "parts": [
        {k: p.get(k) for k in ("dataset", "held_out_gear", "train_s", "calibrate_s",
                               "evaluate_s")} for p in designs + parts]})
    sc = pc.study
    train_ids, held = instances(sc)
    header = (f"# Prognosis: lives to failure by laws it does not assume, on gear instances "
              f"it never saw\n\n"
              f"Data sets {', '.join(pc.run_on)}; a lot of {sc.population} instances (seed "
              f"{sc.population_seed}), trained on {len(train_ids)}, scored on {held}; seeds "
              f"{sc.seeds}; calibration seeds {sc.calibration_seeds} on the training "
              f"instances, each read without its own; the lives' day and law drawn per seed "
              f"(`prognosis.study.day`, `prognosis.study.growth`); a prognosis every "
              f"{sc.prognosis.every_h:g} h after the alarm; "
              f"{'a scored run' if sc.scored_run else 'design seeds: not a scored run'}. "
              f"Wall time {wall / 60:.1f} min"
              f"{resumed_note(resumed, len(designs) + len(parts))}.\n"
              + "".join(f"\nNot evaluated: {k}: {w}.\n" for k, w in sorted(not_run.items())))
    write_table(out / "table.md", header, tgt, summary, buckets, lives, cal, moved)
    fig = figure(buckets, rows, out / "prognosis.png", goal, nominal)
    claim.record([*csvs, out / "table.md", fig])
    ledger = None
    if sc.scored_run:
        ledger = append_scored_run(sc.seeds, [out / "results.csv", out / "lives.csv"])
    if pc.progress:
        print("\ntargets (prognosis, the growth law; held-out instances):")
        for r in tgt.itertuples(index=False):
            print(f"  {r.dataset:<12s} {r.fault:<17s} {r.what:<62s} {r.target:>9s} "
                  f"{r.measured:>7s} {r.result}")
        print(f"report: {out}/table.md; wall time {wall / 60:.1f} min")
    if app.logger is not None:
        _log(app, summary, tgt, out, wall, plans)
    return {"task": "prognosis", "report_dir": str(out), "wall_s": wall,
            "lives": int(len(lives)), "prognoses": int(rows.valid.sum()) if len(rows) else 0,
            "targets_passed": int((tgt.result == "pass").sum()),
            "targets_judged": int(tgt.result.isin(["pass", "fail"]).sum()),
            **({} if ledger is None else {"ledger": ledger})}


def _log(app, summary: pd.DataFrame, tgt: pd.DataFrame, out: Path, wall: float,
         plans: dict[str, DatasetPlan]) -> None:
    """The evaluation's MLflow run (:func:`learn.tracking.log_run`)."""
    pc: PrognosisExperiment = app.prognosis
    gr = summary[summary.method == "growth"]
    params = {"run_on": ",".join(pc.run_on), "seeds": str(pc.study.seeds),
              "calibration_seeds": str(pc.study.calibration_seeds),
              "naming": dataclasses.asdict(pc.study.train.naming),
              "normal": dataclasses.asdict(pc.study.train.normal),
              "targets": dataclasses.asdict(pc.study.targets),
              "max_scale": pc.study.max_scale, "failure_history": pc.study.failure_history,
              **{f"config_hash.{n}": p.config_hash for n, p in plans.items()}}
    with log_run(app.logger.experiment, app.logger.run_name,
                 tracking_uri=app.logger.tracking_uri, params=params,
                 config=plain(app)) as run:
        run.log_metrics({"ra_half_life_median": float(gr.ra_median.median()),
                         "alpha_lambda_share": float(gr.alpha_lambda_share.mean()),
                         "targets_passed": float((tgt.result == "pass").sum()),
                         "wall_s": wall})
        for f in ("results.csv", "lives.csv", "scores.csv", "changes.csv", "table.md",
                  "prognosis.png"):
            if (out / f).is_file():
                run.log_artifact(out / f)


__all__ = ["PrognosisExperiment", "plan_parts", "run_prognosis_evaluation"]
