"""Task ``monitor`` (``swgsim-train experiment=monitor``): the condition monitor's
leave-one-gear-out evaluation over simulated gear lives (:mod:`learn.monitor.evaluate`),
its table and figures (:mod:`learn.reports.monitor_report`) and an MLflow run.

Files in ``report_dir``: ``results.csv`` (one row per life and detector),
``false_alarms.csv``, ``table.md``, ``time_to_detect.png``, ``false_alarms_vs_ttd.png``,
``tradeoff.csv`` (false alarms and times to detect of the same rule at other design
rates), ``timing.json``, ``models/<dataset>_without_gear<g>.joblib`` (the diagnosis models, for
``swgsim-monitor``) and ``parts/`` (one finished (data set, held-out gear) each, with the
hash of the config that made it: a rerun of the same config resumes from them).
"""

from __future__ import annotations

import dataclasses
import hashlib
import json
import logging
import time
from dataclasses import dataclass, field
from pathlib import Path

import pandas as pd

from learn.monitor.baselines import BASELINES
from learn.monitor.evaluate import MonitorStudyConfig, run_held_out, to_frames
from learn.tasks.config import typed_app
from swgsim.base.typed import allowed
from swgsim.datasets.config import DatasetConfig

log = logging.getLogger(__name__)


@dataclass
class MonitorExperiment:
    """``monitor`` group of ``swgsim-train``.

    Attributes
    ----------
    run_on : list of str
        Keys of ``datasets`` to evaluate, in order.
    datasets : dict of str to DatasetConfig
        Data-set presets whose gears live (their chain, recording, gears, Table V grid).
    study : MonitorStudyConfig
        The evaluation's design.
    report_dir : str
    n_jobs : int
        Worker processes, one (data set, held-out gear) each.
    progress : bool
    """

    run_on: list[str] = field(default_factory=lambda: ["bench", "robot_joint"])
    datasets: dict[str, DatasetConfig] = field(default_factory=dict)
    study: MonitorStudyConfig = field(default_factory=MonitorStudyConfig)
    report_dir: str = "reports/monitor"
    n_jobs: int = field(default=2, metadata=allowed(1, None, "worker processes"))
    progress: bool = True


def check_study(sc: MonitorStudyConfig) -> None:
    """Refuse a study design outside its ranges, naming the key.

    Raises
    ------
    ValueError
    """
    def req(cond, msg):
        if not cond:
            raise ValueError(msg)
    req(len(sc.seeds) >= 1, "monitor.study.seeds must list at least one seed")
    req(0 < sc.commissioning_h < sc.healthy_hours, "monitor.study.commissioning_h must lie in "
        f"(0, healthy_hours={sc.healthy_hours:g}) h, got {sc.commissioning_h}")
    req(sc.interval_min > 0, f"monitor.study.interval_min must be > 0, got {sc.interval_min}")
    lo, hi = sc.onset_window_h
    req(0 <= lo <= hi, f"monitor.study.onset_window_h must be [lo, hi] with 0 <= lo <= hi, got "
        f"{sc.onset_window_h}")
    req(sc.commissioning_h + hi <= sc.healthy_hours, "monitor.study.onset_window_h: the latest "
        f"onset, commissioning_h + {hi:g} h, must lie within the healthy life (healthy_hours="
        f"{sc.healthy_hours:g} h), whose monitor state a fault life starts from")
    for k in ("horizon_h", "growth_h", "train_fault_h", "train_healthy_h"):
        req(getattr(sc, k) > 0, f"monitor.study.{k} must be > 0, got {getattr(sc, k)}")
    req(sc.train_variants >= 1, "monitor.study.train_variants must be >= 1")
    req(sc.sensor_train_levels >= 2, "monitor.study.sensor_train_levels must be >= 2 (mild "
        f"and severe), got {sc.sensor_train_levels}")
    req(sc.rule.design_hours > 0, "monitor.study.rule.design_hours must be > 0")
    bad = sorted(set(sc.baselines) - set(BASELINES))
    req(not bad, f"monitor.study.baselines: unknown {bad}; allowed: {sorted(BASELINES)}")
    req(0 < sc.baseline_hours <= sc.healthy_hours - sc.commissioning_h,
        "monitor.study.baseline_hours must lie in (0, healthy_hours - commissioning_h = "
        f"{sc.healthy_hours - sc.commissioning_h:g}] h, got {sc.baseline_hours}")


def _hash(obj) -> str:
    return hashlib.sha256(json.dumps(obj, sort_keys=True, default=str).encode()).hexdigest()[:16]


def run_monitor(cfg) -> dict:
    """Run the evaluation (module docstring); return the figures' summary.

    Raises
    ------
    ValueError
        A bad ``monitor`` key or data set, or a ``report_dir`` holding a file this
        project cannot show it wrote (named); before any work.
    """
    from swgsim.datasets.plan import plan
    from swgsim.files import ownership

    app = typed_app(cfg)
    mc: MonitorExperiment = app.monitor
    check_study(mc.study)
    unknown = [d for d in mc.run_on if d not in mc.datasets]
    if unknown:
        raise ValueError(f"monitor.run_on: {unknown} not among monitor.datasets "
                         f"{sorted(mc.datasets)}")
    plans = {}
    for name in mc.run_on:  # every config checked before any work
        try:
            plans[name] = plan(mc.datasets[name])
        except ValueError as e:
            raise ValueError(f"monitor.datasets.{name}: {e}") from None
    out = Path(mc.report_dir)
    ownership.check(out, "monitor.report_dir")  # before any work
    with ownership.claim(out, "monitor", "monitor.report_dir") as claim:
        return _evaluate(app, mc, plans, out, claim)


def _evaluate(app, mc: MonitorExperiment, plans: dict, out: Path, claim) -> dict:
    """The evaluation into the claimed ``out`` (every file it writes recorded)."""
    from swgsim.files.ownership import atomic_write_json

    (out / "parts").mkdir(parents=True, exist_ok=True)
    (out / "models").mkdir(exist_ok=True)
    jobs = []
    for name, p in plans.items():
        gears = mc.study.gears or [int(g.id) for g in p.config.gears]
        for g in gears:
            key = _hash({"dataset": p.config_hash, "gear": g,
                         "study": dataclasses.asdict(mc.study)})
            jobs.append((name, g, key))
    t0 = time.perf_counter()
    parts = _run_jobs(plans, jobs, mc, out)
    wall = time.perf_counter() - t0
    res, fa, curve = to_frames(parts)
    res.to_csv(out / "results.csv", index=False)
    fa.to_csv(out / "false_alarms.csv", index=False)
    curve.to_csv(out / "tradeoff.csv", index=False)
    from learn.reports.monitor_report import figures, write_table

    timing = {"wall_s": wall, "parts": [{k: p[k] for k in ("dataset", "held_out_gear",
                                                          "train_s", "evaluate_s")}
                                         for p in parts]}
    atomic_write_json(out / "timing.json", timing)
    header = (f"# Condition monitor: leave-one-gear-out over simulated lives\n\n"
              f"Data sets {', '.join(mc.run_on)}; seeds {mc.study.seeds}; "
              f"{mc.study.healthy_hours:g} h per healthy life; design: one false alarm per "
              f"{mc.study.rule.design_hours:g} h. Wall time {wall / 60:.1f} min.\n")
    write_table(res, fa, out / "table.md", header)
    figs = figures(res, fa, out, curve)
    claim.record([out / f for f in ("results.csv", "false_alarms.csv", "tradeoff.csv",
                                    "table.md")] + list(figs))
    if mc.progress:  # the console's summary
        from learn.reports.monitor_report import targets

        print(f"\ntargets (monitor; held-out gears, {len(mc.study.seeds)} seed(s)):")
        for r in targets(res, fa).itertuples(index=False):
            print(f"  {r.dataset:<12s} {r.what:<66s} target {r.target:>7s}  {r.measured}")
        print(f"report: {out}/table.md (+ results.csv, false_alarms.csv, tradeoff.csv, "
              f"figures); wall time {wall / 60:.1f} min")
    if app.logger is not None:
        _log(app, res, fa, out, wall)
    det = res[(res.detector == "monitor")]
    return {"task": "monitor", "report_dir": str(out), "wall_s": wall,
            "lives": int(len(det)), "detected": float(det.detected.mean()),
            "false_alarms": int(fa[fa.detector == "monitor"].false_alarms.sum())}


def _run_jobs(plans, jobs, mc: MonitorExperiment, out: Path) -> list[dict]:
    """Each (data set, held-out gear): resumed from ``parts/`` when its key matches."""
    import joblib
    from tqdm.auto import tqdm

    from swgsim.files.ownership import atomic_write_json

    done, todo = [], []
    for name, g, key in jobs:
        f = out / "parts" / f"{name}_gear{g}.json"
        if f.is_file():
            try:
                part = json.loads(f.read_text())
                if part.get("key") == key:
                    done.append(part)
                    continue
            except json.JSONDecodeError:
                pass
        todo.append((name, g, key))
    if done:
        log.info("resuming: %d part(s) already done", len(done))
    bar = tqdm(total=len(todo), desc="monitor lives", unit="gear", disable=not mc.progress)
    par = joblib.Parallel(n_jobs=min(mc.n_jobs, max(1, len(todo))),
                          return_as="generator_unordered")
    for part in par(joblib.delayed(_job)(plans[n], n, g, k, mc.study, str(out))
                    for n, g, k in todo):
        atomic_write_json(out / "parts" / f"{part['dataset']}_gear{part['held_out_gear']}.json",
                          part)
        done.append(part)
        bar.update()
    bar.close()
    order = {(n, g): i for i, (n, g, _) in enumerate(jobs)}
    return sorted(done, key=lambda p: order[(p["dataset"], p["held_out_gear"])])


def _job(plan, name: str, g: int, key: str, study: MonitorStudyConfig, out: str) -> dict:
    import io

    import joblib

    from swgsim.files import ownership
    from swgsim.files.ownership import atomic_write_bytes

    ownership.join(out, "monitor")  # the model this worker writes is recorded
    part = run_held_out(plan, name, g, study)
    buf = io.BytesIO()
    joblib.dump(part.pop("model"), buf)
    atomic_write_bytes(Path(out) / "models" / f"{name}_without_gear{g}.joblib", buf.getvalue())
    part["key"] = key
    for k in ("rows", "curve"):
        part[k] = pd.DataFrame(part[k]).to_dict("records")
    return json.loads(json.dumps(part, default=float))


def _log(app, res: pd.DataFrame, fa: pd.DataFrame, out: Path, wall: float) -> None:
    import mlflow

    from learn.reports.monitor_report import false_alarm_table, summary_table
    from learn.tracking.store import check_tracking, use_tracking

    lcfg = app.logger
    check_tracking(lcfg.tracking_uri, "logger.tracking_uri")
    use_tracking(lcfg.tracking_uri, "logger.tracking_uri")  # one opener at a time
    mlflow.set_experiment("monitor")
    tab = summary_table(res)
    fat = false_alarm_table(fa)
    with mlflow.start_run(run_name="monitor"):
        mlflow.log_params({"run_on": ",".join(app.monitor.run_on),
                           "seeds": str(app.monitor.study.seeds),
                           "healthy_hours": app.monitor.study.healthy_hours,
                           "design_hours": app.monitor.study.rule.design_hours})
        mon = tab[tab.detector == "monitor"]
        mlflow.log_metrics({"detection_rate": float(mon.detection_rate.mean()),
                            "worst_false_alarms_per_1000h": float(
                                fat[fat.detector == "monitor"].per_1000_h.max()),
                            "wall_s": wall})
        for f in ("results.csv", "false_alarms.csv", "table.md", "time_to_detect.png",
                  "false_alarms_vs_ttd.png"):
            if (out / f).is_file():
                mlflow.log_artifact(str(out / f))


__all__ = ["MonitorExperiment", "check_study", "run_monitor"]
