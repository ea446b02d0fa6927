"""Task ``benchmark`` (``swgsim-train experiment=benchmark``): the benchmark of issue 83
(:mod:`.benchmark`) in resumable parts, its tables per family
and held-out instance (:mod:`.statistics`), and, for a declared
scored run, its row in the ledger (:mod:`learn.tracking.ledger`).

Parts, in ``report_dir/parts`` (each with the hash of what made it, so a rerun of the same
command resumes): per data set, ``design`` (the diagnosis model trained on the lot's
training instances, written to ``models/``, and the baselines' thresholds set on design
lives); then per data set, held-out instance and family, its lives. Files: ``results.csv``
(fault lives), ``false_alarms.csv`` (healthy lives), ``design.json``, ``table.md``,
``timing.json``.
"""

from __future__ import annotations

import dataclasses
import time
from dataclasses import dataclass, field
from functools import partial
from pathlib import Path

import numpy as np

from learn.tasks.config import typed_app
from learn.tasks.parts import (
    DESIGN,
    EvaluationExperiment,
    Job,
    part_key,
    run_group,
    write_csvs,
)
from learn.tracking.ledger import append_scored_run
from swgmon.assessment.model_io import MODEL_SUFFIX, load_model, save_model
from swgmon.evaluation.benchmark import (
    ABLATION,
    BenchmarkConfig,
    ablated,
    benchmark_part,
    check_memory,
    design_thresholds,
    instances,
    population_plan,
)
from swgmon.evaluation.evaluate import banks_of
from swgmon.evaluation.statistics import (
    alarm_rate,
    alarm_share,
    conditional_delay,
)
from swgmon.evaluation.training import train_model
from swgsim.base.lazy import lazy_module
from swgsim.base.markdown import md_table
from swgsim.base.typed import check_tree
from swgsim.datasets.plan import DatasetPlan
from swgsim.files import ownership
from swgsim.files.ownership import atomic_write_bytes, atomic_write_json

pd = lazy_module("pandas")

__all__ = ["FAMILY_TARGETS", "JUDGED_FAULTS", "SECOND_TARGETS", "BenchmarkExperiment",
           "benchmark_tables", "benchmark_targets", "run_benchmark", "second_targets"]

@dataclass
class BenchmarkExperiment(EvaluationExperiment):
    """``benchmark`` group of ``swgsim-train``: the shared keys
    (:class:`learn.tasks.parts.EvaluationExperiment`) and the benchmark's design.

    Attributes
    ----------
    study : BenchmarkConfig
    report_dir : str
        Default ``reports/benchmark`` [choice].
    """

    study: BenchmarkConfig = field(default_factory=BenchmarkConfig)
    report_dir: str = "reports/benchmark"


def plan_jobs(bc: BenchmarkExperiment, plans: dict[str, DatasetPlan]
              ) -> tuple[list[Job], list[Job]]:
    """The design part of each data set and the lives' parts (data set, held-out
    instance, family), each keyed by what made it."""
    study = dataclasses.asdict(bc.study)
    design, lives = [], []
    for name, p in plans.items():
        base = {"dataset": p.config_hash, "study": study}
        design.append(Job(name, 0, DESIGN, part_key({**base, "part": DESIGN})))
        for g in instances(bc.study)[1]:
            lives += [Job(name, g, f, part_key({**base, "gear": g, "family": f}))
                      for f in bc.study.families]
    return design, lives


def run_benchmark(cfg) -> dict:
    """Run the benchmark (module docstring); return its summary.

    Raises
    ------
    ValueError
        A bad ``benchmark`` key or data set, a scored seed outside a declared scored run,
        ``benchmark.group`` beyond the groups or a lives group before its data set's
        design part, lives parts that cannot fit in memory ``n_jobs`` at once
        (:func:`~.benchmark.check_memory`), an unwritable MLflow
        store or a ``report_dir`` holding a file this project cannot show it wrote;
        before any work.
    """
    app = typed_app(cfg)
    bc: BenchmarkExperiment = app.benchmark
    check_tree(bc.study, "benchmark.study")
    plans = {n: population_plan(p, bc.study) for n, p in bc.plans("benchmark").items()}
    check_memory(plans, bc.study, bc.n_jobs)
    return bc.run_stages("benchmark", plans, app.logger, *plan_jobs(bc, plans), _design,
                         _lives, partial(_report, bc))


def _design(plan: DatasetPlan, jobs: list[Job], bc: BenchmarkConfig, out: str
            ) -> list[tuple[dict, Job]]:
    """A data set's design part in a worker: its model (written to ``models/``) and the
    baselines' thresholds."""
    ownership.join(out, "benchmark")

    def one(job: Job) -> dict:
        train, _ = instances(bc)
        banks = {g: b for g, b in banks_of(plan).items() if g in train}
        models = {}
        for name, study in _monitors(bc).items():
            models[name] = train_model(plan, banks, train, study)
            save_model(models[name], _model_path(out, job.dataset, name),
                       [{"name": job.dataset, "config_hash": plan.config_hash, "gears": train,
                         "simulated": "training lives of swgmon.evaluation.training"}])
        thresholds, design = design_thresholds(plan, banks, models["monitor"], bc,
                                               job.dataset)
        return {"dataset": job.dataset, "thresholds": thresholds, "design": design}
    return run_group(out, jobs, one)


def _lives(plan: DatasetPlan, jobs: list[Job], bc: BenchmarkConfig, out: str,
           design: dict) -> list[tuple[dict, Job]]:
    """One held-out instance's families in a worker, sharing its records, by its data
    set's design part (the baselines' ``thresholds``)."""
    ownership.join(out, "benchmark")
    thresholds = design["thresholds"]
    models = {n: load_model(_model_path(out, jobs[0].dataset, n)) for n in _monitors(bc)}
    banks = {jobs[0].gear: banks_of(plan)[jobs[0].gear]}

    def one(job: Job) -> dict:
        t0 = time.perf_counter()
        part = benchmark_part(plan, banks, models, job.gear, job.detector, bc, thresholds,
                              job.dataset)
        return {**part, "dataset": job.dataset, "gear": job.gear, "family": job.detector,
                "wall_s": time.perf_counter() - t0}
    return run_group(out, jobs, one)


def _monitors(bc: BenchmarkConfig) -> dict:
    """The monitor's study and, with the ablation, its ablated one, by detector name."""
    return {"monitor": bc.study, **({ABLATION: ablated(bc.study)} if bc.ablation else {})}


def _model_path(out: str | Path, dataset: str, name: str = "monitor") -> Path:
    tail = "" if name == "monitor" else f"_{name}"
    return Path(out) / "models" / f"{dataset}_benchmark{tail}{MODEL_SUFFIX}"


def benchmark_tables(rows: pd.DataFrame, fa: pd.DataFrame, level: float) -> pd.DataFrame:
    """Per data set, family, held-out instance (and ``all`` of them) and detector: healthy
    lives with any gear-fault alarm and their Clopper-Pearson interval, false alarms
    per 1000 h pooled with the worst life's, faulty lives detected, the conditional
    average delay with its bootstrap interval, and (the monitor) named right at the alarm
    and an hour after.

    Parameters
    ----------
    rows, fa : DataFrame
        The fault lives' and the healthy lives' rows (``results.csv``,
        ``false_alarms.csv``).
    level : float
        The intervals' two-sided confidence level (``BenchmarkConfig.level``).

    Returns
    -------
    DataFrame
        One row per (dataset, family, held_out_gear, detector).
    """
    out = []
    keys = ["dataset", "family", "detector"]
    for gear in [*sorted(fa.held_out_gear.unique()), "all"]:
        f = fa if gear == "all" else fa[fa.held_out_gear == gear]
        r = rows if gear == "all" else rows[rows.held_out_gear == gear]
        for (d, fam, det), h in f.groupby(keys, sort=False):
            lives = r[(r.dataset == d) & (r.family == fam) & (r.detector == det)]
            share = alarm_share(h.gear_fault_alarms > 0, level=level)
            pooled, worst, _ = alarm_rate(h.gear_fault_alarms, h.healthy_hours)
            delay = conditional_delay(lives.time_to_detect_h.where(lives.detected),
                                      level=level)
            named = lives[lives.detected]
            out.append({"dataset": d, "family": fam, "held_out_gear": gear, "detector": det,
                        "healthy_lives": share.n, "any_alarm": share.value,
                        "any_alarm_low": share.low, "any_alarm_high": share.high,
                        "alarms_per_1000h": pooled, "worst_life_per_1000h": worst,
                        "fault_lives": len(lives), "detected": float(lives.detected.mean())
                        if len(lives) else np.nan,
                        "cadd_h": delay.value, "cadd_low_h": delay.low,
                        "cadd_high_h": delay.high,
                        **_named(named)})
    return pd.DataFrame(out)


#: The protocol's targets 1-6 for the monitor, per data set and family
#: (docs/results/protocol.md): (number, question, table column, bound, at most).
FAMILY_TARGETS = ((1, "false alarms", "alarms_per_1000h", 2.0, True),
                  (2, "no storms", "most_alarms_in_a_life", 1.0, True),
                  (3, "lives touched", "any_alarm", 0.20, True),
                  (4, "detection", "detected", 0.90, False),
                  (5, "delay [h]", "cadd_h", 40.0, True),
                  (6, "naming", "named_after_1h", 0.80, False))


def benchmark_targets(rows: pd.DataFrame, fa: pd.DataFrame, level: float) -> pd.DataFrame:
    """The protocol's eight targets (docs/results/protocol.md) met or not: 1-6 for the
    monitor per data set and family, 7 (against each baseline) and 8 (against the
    ablation) per data set, pooled over the families.

    Parameters
    ----------
    rows, fa : DataFrame
        ``results.csv`` and ``false_alarms.csv`` of a benchmark run.
    level : float
        As :func:`benchmark_tables` (the targets judge values, not intervals).

    Returns
    -------
    DataFrame
        One row per target and cell: ``dataset``, ``family`` (``pooled`` for 7 and 8),
        ``target``, ``question``, ``value``, ``bound``, ``met`` (False where the value is
        NaN: nothing to judge is not met).
    """
    tab = benchmark_tables(rows, fa, level)
    tab = tab[(tab.held_out_gear == "all") & (tab.detector == "monitor")]
    most = fa[fa.detector == "monitor"].groupby(["dataset", "family"]).gear_fault_alarms.max()
    out = []
    for r in tab.itertuples(index=False):
        vals = {**r._asdict(), "most_alarms_in_a_life": most.get((r.dataset, r.family))}
        for n, q, col, bound, at_most in FAMILY_TARGETS:
            v = float(vals[col])
            out.append({"dataset": r.dataset, "family": r.family, "target": n,
                        "question": q, "value": v, "bound": bound,
                        "met": bool(v <= bound if at_most else v >= bound)})
    for d in rows.dataset.unique():
        pooled = _pooled(rows[rows.dataset == d], fa[fa.dataset == d], level)
        m = pooled["monitor"]
        out += [{"dataset": d, "family": "pooled", "target": 7, **x}
                for x in _against_baselines(pooled, strict=False)]
        if ABLATION in pooled:
            a = pooled[ABLATION]
            out.append({"dataset": d, "family": "pooled", "target": 8,
                        "question": "against the ablation: alarms per 1000 h, detected",
                        "value": (m["per_1000h"], m["detected"]),
                        "bound": (a["per_1000h"], a["detected"]),
                        "met": bool(m["per_1000h"] <= a["per_1000h"]
                                    and m["detected"] >= a["detected"])})
    return pd.DataFrame(out)


#: The gear faults the second protocol's targets B-D judge (docs/results/protocol.md);
#: the others are reported beside them.
JUDGED_FAULTS = ("eccentric_wg", "reduced_damping", "root_tooth_crack", "tip_tooth_crack")
#: The second protocol's targets A-E: (letter, question, bound, at most).
SECOND_TARGETS = (("A", "healthy lives touched", 0.05, True),
                  ("B", "detected", 0.95, False),
                  ("C", "delay at the mildest severity [h]", 1.0, True),
                  ("D", "named right at the alarm", 0.95, False),
                  ("E", "sensor families' healthy lives with a gear-fault alarm", 0.0, True))


def second_targets(rows: pd.DataFrame, fa: pd.DataFrame, growth_h: float, level: float
                   ) -> pd.DataFrame:
    """The second protocol's targets A-F (docs/results/protocol.md, issue 84) for the
    monitor, from a benchmark run's rows alone.

    A per data set, family and held-out instance (and per family over its instances, not
    judged); B-D per data set and gear fault over every family (judged for
    :data:`JUDGED_FAULTS`); E per data set over the ``sensor_*`` families; F per data set
    against each baseline, pooled over the families (:func:`_pooled`).

    Parameters
    ----------
    rows, fa : DataFrame
        ``results.csv`` and ``false_alarms.csv`` of a benchmark run.
    growth_h : float
        Hours a fault life's fault grows to its mildest severity
        (``MonitorStudyConfig.family_growth_h``) [h]: C counts the delay from there, an
        alarm before it as 0.
    level : float
        Two-sided level of A's Clopper-Pearson interval.

    Returns
    -------
    DataFrame
        One row per target and cell: ``dataset``, ``target``, ``cell`` (family and
        instance, fault, or ``pooled``), ``question``, ``value``, ``high`` (A's upper
        bound, else NaN), ``n`` (lives behind it), ``bound``, ``judged``, ``met`` (False
        where the value is NaN).
    """
    spec = {t: (q, b, most) for t, q, b, most in SECOND_TARGETS}
    out = []

    def add(d, t, cell, value, n, judged=True, high=np.nan):
        q, b, most = spec[t]
        v = float(value)
        out.append({"dataset": d, "target": t, "cell": cell, "question": q, "value": v,
                    "high": float(high), "n": int(n), "bound": b, "judged": judged,
                    "met": bool(v <= b if most else v >= b)})
    for d in fa.dataset.unique():
        f = fa[(fa.dataset == d) & (fa.detector == "monitor")]
        r = rows[(rows.dataset == d) & (rows.detector == "monitor")]
        for keys, judged in ((["family", "held_out_gear"], True), (["family"], False)):
            for k, h in f.groupby(keys, sort=False):
                s = alarm_share(h.gear_fault_alarms > 0, level=level)
                cell = f"{k[0]}, {k[1]}" if judged else f"{k[0]}, all"
                add(d, "A", cell, s.value, s.n, judged, s.high)
        for fault, x in r.groupby("fault", sort=False):
            hit = x[x.detected.astype(bool)]
            judged = fault in JUDGED_FAULTS
            late = np.clip(hit.time_to_detect_h.to_numpy(float) - growth_h, 0.0, None)
            add(d, "B", fault, x.detected.astype(bool).mean(), len(x), judged)
            add(d, "C", fault, late.mean() if len(hit) else np.nan, len(hit), judged)
            add(d, "D", fault, (hit.fault_at_alarm == fault).mean() if len(hit) else np.nan,
                len(hit), judged)
        sensor = f[f.family.astype(str).str.startswith("sensor_")]
        add(d, "E", "pooled", (sensor.gear_fault_alarms > 0).sum(), len(sensor))
        pooled = _pooled(rows[rows.dataset == d], fa[fa.dataset == d], level)
        out += [{"dataset": d, "target": "F", "cell": x["baseline"], "high": np.nan,
                 "n": len(r), "judged": True, **x}
                for x in _against_baselines(pooled, strict=True)]
    return pd.DataFrame(out)


def _against_baselines(pooled: dict[str, dict[str, float]], strict: bool) -> list[dict]:
    """Per baseline of :func:`_pooled`'s: the monitor detected at least, and its CADD at
    most (``strict``: below), the baseline's (``baseline``, ``question``, ... ``met``)."""
    m, out = pooled["monitor"], []
    for b in [x for x in pooled if x not in ("monitor", ABLATION)]:
        cadd = m["cadd_h"] < pooled[b]["cadd_h"] if strict else \
            m["cadd_h"] <= pooled[b]["cadd_h"]
        out.append({"baseline": b, "question": f"against {b}: detected, CADD [h]",
                    "value": (m["detected"], m["cadd_h"]),
                    "bound": (pooled[b]["detected"], pooled[b]["cadd_h"]),
                    "met": bool(m["detected"] >= pooled[b]["detected"] and cadd)})
    return out


def _pooled(rows: pd.DataFrame, fa: pd.DataFrame, level: float
            ) -> dict[str, dict[str, float]]:
    """Per detector, over every family of a data set: detected, CADD and gear-fault alarms
    per 1000 h."""
    out = {}
    for det, h in fa.groupby("detector", sort=False):
        r = rows[rows.detector == det]
        out[det] = {"detected": float(r.detected.mean()) if len(r) else np.nan,
                    "cadd_h": conditional_delay(r.time_to_detect_h.where(r.detected),
                                                level=level).value,
                    "per_1000h": alarm_rate(h.gear_fault_alarms, h.healthy_hours)[0]}
    return out


def _named(named: pd.DataFrame) -> dict:
    """Shares of detected lives named right at the alarm and an hour after (NaN for the
    baselines, which name nothing)."""
    if "fault_at_alarm" not in named or named.fault_at_alarm.isna().all() or not len(named):
        return {"named_at_alarm": np.nan, "named_after_1h": np.nan}
    return {"named_at_alarm": float((named.fault_at_alarm == named.fault).mean()),
            "named_after_1h": float((named.fault_after_1h == named.fault).mean())}


def _report(bc: BenchmarkExperiment, out: Path, claim, designs: list[dict],
            parts: list[dict], wall: float, resumed: int) -> dict:
    """The benchmark's files, its console summary and, for a scored run, its ledger row."""
    rows = pd.DataFrame([r for p in parts for r in p["rows"]])
    fa = pd.DataFrame([r for p in parts for r in p["false_alarms"]])
    tab = benchmark_tables(rows, fa, bc.study.level)
    csvs = write_csvs(out, {"results.csv": rows, "false_alarms.csv": fa, "table.csv": tab})
    atomic_write_json(out / "design.json", {d["dataset"]: {"thresholds": d["thresholds"],
                                                           **d["design"]} for d in designs})
    atomic_write_json(out / "timing.json", {"wall_s": wall, "resumed": resumed, "parts": [
        {k: p.get(k) for k in ("dataset", "gear", "family", "wall_s")} for p in parts]})
    atomic_write_bytes(out / "table.md", _markdown(bc, tab, wall).encode())
    claim.record([*csvs, out / "table.md"])
    summary = {"task": "benchmark", "report_dir": str(out), "wall_s": wall,
               "parts": len(parts), "resumed": resumed}
    if bc.study.scored_run:
        summary["ledger"] = append_scored_run(bc.study.seeds,
                                             [out / "results.csv", out / "false_alarms.csv"])
    if bc.progress:
        print(f"report: {out}/table.md (+ results.csv, false_alarms.csv, table.csv); "
              f"wall time {wall / 60:.1f} min")
    return summary


def _markdown(bc: BenchmarkExperiment, tab: pd.DataFrame, wall: float) -> str:
    """``table.md``: the design, then per data set the families over every held-out
    instance, each detector a row."""
    s = bc.study
    head = (f"# Benchmark (issue 83)\n\n{s.population} gear instances per preset, the last "
            f"{s.held_out} held out; families {', '.join(s.families)}; healthy lives of "
            f"{s.healthy_hours:g} h; seeds {s.seeds} "
            f"({'scored run' if s.scored_run else 'design seeds: not a scored run'}); "
            f"wall time {wall / 60:.1f} min.\n")
    parts = [head]
    cols = ["family", "detector", "healthy_lives", "any_alarm", "any_alarm_high",
            "alarms_per_1000h", "worst_life_per_1000h", "fault_lives", "detected", "cadd_h",
            "named_at_alarm", "named_after_1h"]
    for d, t in tab[tab.held_out_gear == "all"].groupby("dataset", sort=False):
        parts.append(f"\n## {d}, every held-out instance\n\n"
                     + md_table(cols, t[cols].itertuples(index=False)) + "\n")
    return "".join(parts)
