"""Task ``monitor`` (``swgsim-train experiment=monitor``): the condition monitor's
leave-one-gear-out evaluation over simulated gear lives (:mod:`.evaluate`),
its table and figures (:mod:`.report`) and an MLflow run.

Files in ``report_dir``: ``results.csv`` (one row per life and detector),
``false_alarms.csv``, ``table.md``, ``time_to_detect.png``, ``false_alarms_vs_ttd.png``,
``tradeoff.csv`` (false alarms and times to detect of the same rule at other design
rates), ``timing.json``, ``models/<dataset>_without_gear<g>.skops`` with its
``.card.json`` (the diagnosis models, for ``swgsim-monitor``) and ``parts/``: one finished
part per (data set, held-out gear) for the monitor and per (data set, held-out gear,
detector) for each per-window detector, each with the hash of the config that made it (a
detector's without the list of the others), so that a rerun of the same config resumes
from them and a detector added later runs alone. The parts of one (data set, held-out gear)
run in one worker, in order, and share its gears' records (simulated once, not once per
part: :func:`learn.tasks.parts.run_parts`), so a detector's ``train_s`` in
``timing.json`` holds only the records its monitor part did not already simulate.
"""

from __future__ import annotations

import dataclasses
import logging
import time
from dataclasses import dataclass, field
from pathlib import Path

from learn.learners.devices import check_device
from learn.tasks.config import typed_app
from learn.tasks.parts import (
    EvaluationExperiment,
    Job,
    group_jobs,
    part_key,
    resumed_note,
    run_group,
    run_one_group,
    run_parts,
    write_csvs,
)
from learn.tracking import log_run
from learn.tracking.ledger import append_scored_run
from swgmon.assessment.model_io import MODEL_SUFFIX, save_model
from swgmon.evaluation.detectors import DETECTORS
from swgmon.evaluation.evaluate import banks_of, run_detectors, run_held_out, to_frames
from swgmon.evaluation.report import (
    false_alarm_table,
    figures,
    summary_table,
    targets,
    write_table,
)
from swgmon.evaluation.study import MonitorStudyConfig
from swgsim.base.lazy import lazy_module
from swgsim.base.typed import check_tree, plain
from swgsim.datasets.plan import DatasetPlan
from swgsim.files import ownership
from swgsim.files.ownership import atomic_write_json

pd = lazy_module("pandas")
joblib = lazy_module("joblib")

log = logging.getLogger(__name__)


@dataclass
class MonitorExperiment(EvaluationExperiment):
    """``monitor`` group of ``swgsim-train``: the shared keys
    (:class:`learn.tasks.parts.EvaluationExperiment`: ``run_on``, ``datasets``,
    ``report_dir``, ``n_jobs``, ``progress``, ``group``) and the monitor's own.

    Attributes
    ----------
    study : MonitorStudyConfig
        The evaluation's design.
    report_dir : str
        Default ``reports/monitor`` [choice].
    device : str
        Where the torch detectors (``cnn_res``) run: ``cpu``, ``cuda``, ``cuda:N`` or
        ``auto`` (a GPU where CUDA is present, else the CPU;
        :data:`learn.learners.devices.DEVICE_CHOICES`); checked, and resolved on this
        machine, before any work. A detector's part records the device it ran on (its
        key holds it, so a part made on another device is not resumed), and the MLflow
        run and ``table.md`` say where and whether deterministically.
    """

    study: MonitorStudyConfig = field(default_factory=MonitorStudyConfig)
    report_dir: str = "reports/monitor"
    device: str = "auto"


def plan_jobs(mc: MonitorExperiment, plans: dict[str, DatasetPlan], device: str = "cpu"
              ) -> tuple[list[Job], dict[str, dict[str, str]]]:
    """The parts of an evaluation, and the detectors that cannot run on a data set;
    ``device``: where the torch detectors run (resolved), in their parts' keys.

    Returns
    -------
    jobs : list of Job
    not_run : dict
        Data set -> {detector: why it cannot run there}
        (:meth:`.detectors.DetectorSpec.cannot_run_on`), reported, not run.
    """
    study = dataclasses.asdict(mc.study)
    common = {k: v for k, v in study.items() if k not in ("detectors", "detector_hours")}
    jobs, not_run = [], {}
    for name, p in plans.items():
        why = {d: DETECTORS[d].cannot_run_on(p) for d in mc.study.detectors}
        not_run[name] = {d: w for d, w in why.items() if w}
        for g in mc.study.gears or [int(x.id) for x in p.config.gears]:
            base = {"dataset": p.config_hash, "gear": g}
            jobs.append(Job(name, g, None, part_key({**base, "study": common})))
            jobs += [Job(name, g, d, part_key({**base, "study": common, "detector": d,
                                             "detector_hours": mc.study.detector_hours,
                                             **({"device": device}
                                                if DETECTORS[d].uses_device else {})}))
                     for d in mc.study.detectors if not why[d]]
    return jobs, not_run


def run_monitor_evaluation(cfg) -> dict:
    """Run the evaluation (module docstring); return the figures' summary.

    Raises
    ------
    ValueError
        A bad ``monitor`` key or data set (``monitor.device`` outside its choices, or a
        CUDA device on a machine without one), an unwritable MLflow store, or a
        ``report_dir`` holding a file this project cannot show it wrote (named); before
        any work.
    """
    app = typed_app(cfg)
    mc: MonitorExperiment = app.monitor
    check_tree(mc.study, "monitor.study")  # its ranges, its rule, ... then its own rules
    plans = mc.plans("monitor")  # every data set's config checked before any work
    nets = _nets(mc)  # a CUDA device on a machine without one: refused before any work
    jobs, not_run = plan_jobs(mc, plans, nets.get("torch_device", "cpu"))
    jobs = group_jobs(jobs, mc.group)
    with mc.claimed_report("monitor", plans, app.logger) as (out, claim):
        (out / "models").mkdir(parents=True, exist_ok=True)

        def delayed(js: list[Job]):
            return joblib.delayed(_job)(plans[js[0].dataset], js, mc.study, str(out),
                                        nets.get("torch_device", "cpu"))
        if mc.group is not None:  # one (data set, held-out gear)'s parts, no report
            return {"task": "monitor", **run_one_group(
                out, jobs, delayed, "monitor evaluation", mc.progress, mc.n_jobs,
                "monitor.group", mc.group)}
        return _evaluate(app, mc, plans, out, claim, nets, jobs, not_run, delayed)


def _nets(mc: MonitorExperiment) -> dict:
    """``monitor.device`` checked and, where a torch detector is evaluated, resolved on
    this machine: :func:`learn.learners.devices.device_record` plus ``torch_device`` (the
    resolved device's string); empty without a torch detector (torch not imported)."""
    check_device(mc.device, "monitor.device")
    if not any(DETECTORS[d].uses_device for d in mc.study.detectors):
        return {}
    from learn.learners.devices import device_record, resolve_device

    dev = resolve_device(mc.device, "monitor.device")
    return {**device_record(dev), "torch_device": str(dev)}


def _evaluate(app, mc: MonitorExperiment, plans: dict, out: Path, claim, nets: dict,
              jobs: list[Job], not_run: dict, delayed) -> dict:
    """The evaluation into the claimed ``out`` (every file it writes recorded); its parts
    by ``delayed`` (:func:`learn.tasks.parts.run_parts`)."""
    (out / "parts").mkdir(exist_ok=True)
    for name, why in not_run.items():
        for d, w in why.items():
            log.warning("detector %s not run on %s: %s", d, name, w)
    t0 = time.perf_counter()
    parts, resumed = run_parts(out, jobs, delayed, "monitor evaluation", mc.progress,
                               mc.n_jobs)
    wall = time.perf_counter() - t0
    res, fa, curve = to_frames(parts)
    csvs = write_csvs(out, {"results.csv": res, "false_alarms.csv": fa, "tradeoff.csv": curve})
    keys = ("dataset", "held_out_gear", "detector", "train_s", "evaluate_s")
    timing = {"wall_s": wall, "resumed": resumed,
              "parts": [{k: p.get(k) for k in keys} for p in parts]}
    atomic_write_json(out / "timing.json", timing)
    header = (f"# Condition monitor: leave-one-gear-out over simulated lives\n\n"
              f"Data sets {', '.join(mc.run_on)}; seeds {mc.study.seeds}; "
              f"{mc.study.healthy_hours:g} h per healthy life; design: one false alarm per "
              f"{mc.study.rule.design_hours:g} h. Wall time {wall / 60:.1f} min"
              f"{resumed_note(resumed, len(jobs))}.\n"
              + "".join(f"\nDetector {d} not run on {n}: {w}.\n"
                        for n, why in not_run.items() for d, w in why.items())
              + (f"\nTorch detectors on {nets['device']} ("
                 f"{'' if nets['deterministic'] else 'not '}deterministic).\n" if nets else ""))
    write_table(res, fa, out / "table.md", header)
    figs = figures(res, fa, out, curve)
    claim.record([*csvs, out / "table.md", *figs])
    if mc.study.scored_run:  # on record, whatever its figures (learn.tracking.ledger)
        append_scored_run([*mc.study.seeds, *mc.study.family_seeds],
                         [out / f for f in ("results.csv", "false_alarms.csv")])
    if mc.progress:  # the console's summary
        print(f"\ntargets (monitor; held-out gears, {len(mc.study.seeds)} seed(s)):")
        for r in targets(res, fa).itertuples(index=False):
            print(f"  {r.dataset:<12s} {r.what:<66s} target {r.target:>7s}  {r.measured}")
        for n, why in not_run.items():
            for d, w in why.items():
                print(f"detector {d} not run on {n}: {w}")
        print(f"report: {out}/table.md (+ results.csv, false_alarms.csv, tradeoff.csv, "
              f"figures); wall time {wall / 60:.1f} min{resumed_note(resumed, len(jobs))}")
    if app.logger is not None:
        _log(app, res, fa, out, wall, plans, nets)
    det = res[(res.detector == "monitor")]
    return {"task": "monitor", "report_dir": str(out), "wall_s": wall,
            "lives": int(len(det)), "detected": float(det.detected.mean()),
            "false_alarms": int(fa[fa.detector == "monitor"].false_alarms.sum())}


def _job(plan: DatasetPlan, jobs: list[Job], study: MonitorStudyConfig, out: str,
         device: str) -> list[tuple[dict, Job]]:
    """The parts of one held-out gear in a worker, sharing its gears' records: the
    monitor's (and its diagnosis model, written to ``models/``) and each detector's."""
    ownership.join(out, "monitor")  # what this worker writes is recorded
    banks = banks_of(plan)

    def one(job: Job) -> dict:
        if job.detector is None:
            part = run_held_out(plan, job.dataset, job.gear, study, banks=banks)
            train = [int(x.id) for x in plan.config.gears if int(x.id) != job.gear]
            save_model(part.pop("model"), Path(out) / "models" /
                       f"{job.dataset}_without_gear{job.gear}{MODEL_SUFFIX}",
                       [{"name": job.dataset, "config_hash": plan.config_hash,
                         "gears": train, "simulated": "training lives of "
                         "swgmon.evaluation.training"}])
        else:
            (part,) = run_detectors(plan, job.dataset, job.gear, study, [job.detector],
                                    device=device, banks=banks)
        for k in ("rows", "curve"):
            part[k] = pd.DataFrame(part[k]).to_dict("records")
        return part
    return run_group(out, jobs, one)


def _log(app, res: pd.DataFrame, fa: pd.DataFrame, out: Path, wall: float,
         plans: dict[str, DatasetPlan], nets: dict) -> None:
    """The evaluation's MLflow run (:func:`learn.tracking.log_run`: commit, library
    versions, the resolved config)."""
    lcfg = app.logger
    mc: MonitorExperiment = app.monitor
    tab, fat = summary_table(res), false_alarm_table(fa)
    mon = tab[(tab.detector == "monitor") & (tab.nuisance == "none")]
    fat_mon = fat[fat.detector == "monitor"]
    params = {"run_on": ",".join(mc.run_on), "seeds": str(mc.study.seeds),
              "healthy_hours": mc.study.healthy_hours,
              "design_hours": mc.study.rule.design_hours,
              "windows_at_once": mc.study.windows_at_once,
              "naming": dataclasses.asdict(mc.study.naming),
              "normal": dataclasses.asdict(mc.study.normal),
              **{f"config_hash.{n}": p.config_hash for n, p in plans.items()},
              **{k: v for k, v in nets.items() if k != "torch_device"}}
    with log_run("monitor", "monitor", tracking_uri=lcfg.tracking_uri, params=params,
                 config=plain(app)) as run:
        run.log_metrics({"detection_rate": float(mon.detection_rate.mean()),
                         "worst_false_alarms_per_1000h": float(
                             fat_mon[fat_mon.nuisance == "none"].per_1000_h.max()),
                         "worst_gear_fault_alarms_per_1000h_real_day": float(
                             fat_mon.gear_fault_per_1000_h.max()),
                         "wall_s": wall})
        for f in ("results.csv", "false_alarms.csv", "table.md", "time_to_detect.png",
                  "false_alarms_vs_ttd.png"):
            if (out / f).is_file():
                run.log_artifact(out / f)


__all__ = ["MonitorExperiment", "plan_jobs", "run_monitor_evaluation"]
