"""Evaluation of the monitor: leave-one-gear-out over simulated gear lives
(docs/monitor/evaluation.md, "The evaluation"). Per data set and held-out gear the diagnosis model
is trained on the other gears' lives; per seed the held-out gear lives healthy (false
alarms, the CUSUM restarted after each) and, from the same commissioning, once per fault,
severity and onset kind, a fault life being the healthy life up to its onset. Nothing is
chosen on the held-out gear. Compared side by side (:data:`COMPARED`): the monitor, the
per-window rule, ``always`` and the per-window detectors of :mod:`.detectors`, each
evaluated on its own (:func:`run_detectors`).
"""

from __future__ import annotations

import dataclasses
import time

import numpy as np

from swgmon.advisories.report import advisories
from swgmon.advisories.stream import (
    adopt_change,
    read_without,
    reading_lost,
    run_stream,
)
from swgmon.assessment.gear_monitor import GearMonitor, MaintenanceEvent, Trace
from swgmon.assessment.model import DiagnosisModel
from swgmon.assessment.naming import diagnose
from swgmon.detection.normal import Conditions, Outside
from swgmon.detection.rule import (
    TEMPERATURE_SENSOR,
    UNEXPLAINED_CHANGE,
    Alarm,
    judged_bets,
    run_cusums,
    threshold,
)
from swgmon.evaluation.detectors import References, WindowClassifier, window_inputs
from swgmon.evaluation.study import MonitorStudyConfig, family_of, life_conditions
from swgmon.evaluation.training import (
    classes,
    features_of,
    has_twist,
    table_v_severities,
    train_detectors,
    train_model,
)
from swgsim.base.lazy import lazy_module
from swgsim.datasets.conditions import ConditionsConfig
from swgsim.datasets.life import LifeSimulator
from swgsim.datasets.plan import DatasetPlan
from swgsim.datasets.records import RecordBank, record_bank
from swgsim.datasets.schedule import FaultOnset, LifeConfig
from swgsim.sensing.sensor_faults import SENSOR_FAULTS

pd = lazy_module("pandas")

#: The rows every evaluation has, beside the chosen per-window detectors.
COMPARED = ("monitor", "per_window", "always")


def fault_lives(plan: DatasetPlan, cfg: MonitorStudyConfig, seed: int
                ) -> list[tuple[FaultOnset, str]]:
    """The faults of one held-out gear and seed: every class at every severity with a step
    onset, and every class growing linearly to its largest severity; onsets drawn from
    the seed in ``onset_window_h`` after commissioning."""
    rng = np.random.default_rng([seed, 7])
    out = []
    for c in classes(plan, cfg)[1:]:
        sevs = table_v_severities(plan, c)
        for s in sevs:
            on = cfg.commissioning_h + rng.uniform(*cfg.onset_window_h)
            out.append((FaultOnset(c, on, s), "step"))
        on = cfg.commissioning_h + rng.uniform(*cfg.onset_window_h)
        top = max(sevs, key=abs)
        pts = [[on, sevs[0]]] + [[on + cfg.growth_h * abs(v / top), v] for v in sevs[1:]]
        out.append((FaultOnset(c, on, top, growth="points", points=pts), "growing"))
    return out


def _per_window(lp: np.ndarray) -> np.ndarray:
    """Windows the per-window rule calls faulty (its most probable class is not healthy)."""
    return np.argmax(lp, axis=1) != 0


def nuisance_fault_lives(plan: DatasetPlan, cfg: MonitorStudyConfig, seed: int,
                         growing: bool = False) -> list[tuple[FaultOnset, str]]:
    """The faults lived under a nuisance by one held-out gear and seed.

    Parameters
    ----------
    plan : DatasetPlan
    cfg : MonitorStudyConfig
    seed : int
        The life's seed: the onsets are drawn from it, uniformly in ``onset_window_h``
        after commissioning.
    growing : bool
        Also every gear fault at its mildest Table V severity growing linearly from 0 at
        its onset to that severity ``cfg.family_growth_h`` later (a family's lives;
        onsets from a stream of their own, so the step faults' are those without).

    Returns
    -------
    list of (FaultOnset, str)
        Every gear fault at its mildest and largest Table V severity with a step onset
        (``step``), then, with ``growing``, the growing ones (``growing``); with
        ``growing`` and ``cfg.family_steps`` False, the growing ones only.
    """
    rng = np.random.default_rng([seed, 8])
    grow = np.random.default_rng([seed, 9])
    out, slow = [], []
    for c in classes(plan, cfg)[1:]:
        if c in SENSOR_FAULTS:
            continue
        sevs = table_v_severities(plan, c)
        for s in sorted({min(sevs, key=abs), max(sevs, key=abs)}):
            on = cfg.commissioning_h + rng.uniform(*cfg.onset_window_h)
            out.append((FaultOnset(c, on, s), "step"))
        if growing:
            on = cfg.commissioning_h + grow.uniform(*cfg.onset_window_h)
            slow.append((FaultOnset(c, on, min(sevs, key=abs), growth="linear",
                                    growth_h=cfg.family_growth_h), "growing"))
    return slow if growing and not cfg.family_steps else out + slow


def lives_of(plan: DatasetPlan, banks: dict[int, RecordBank], g: int, cfg: MonitorStudyConfig,
             seed: int, nuisance: str = "none"
             ) -> tuple[LifeSimulator, list[tuple[LifeSimulator, FaultOnset, str]]]:
    """The healthy life of held-out gear ``g`` for a seed, under a nuisance of
    ``cfg.nuisances``, a family of ``cfg.families`` (``family:<key>``) or none, and its
    fault lives (:func:`fault_lives`, :func:`nuisance_fault_lives`, growing ones under a
    family), sharing its records; a fault life runs ``fault_life_h`` after its onset, or
    after its linear growth's end."""
    healthy = healthy_life(plan, banks[g], g, cfg, seed, nuisance)
    return healthy, [(LifeSimulator(plan, g, life, banks[g]), f, kind)
                     for life, f, kind in fault_life_configs(plan, cfg, seed, nuisance,
                                                             healthy.life)]


def fault_life_configs(plan: DatasetPlan, cfg: MonitorStudyConfig, seed: int, nuisance: str,
                       base: LifeConfig) -> list[tuple[LifeConfig, FaultOnset, str]]:
    """The fault lives of :func:`lives_of` as configs: the healthy life ``base`` with each
    fault onset, running ``fault_life_h`` after it (or after its linear growth's end)."""
    onsets = (fault_lives(plan, cfg, int(seed)) if nuisance == "none" else
              nuisance_fault_lives(plan, cfg, int(seed), family_of(nuisance) is not None))
    return [(dataclasses.replace(base, hours=f.onset_h + cfg.fault_life_h
                                 + (f.growth_h if f.growth == "linear" else 0.0), fault=f),
             f, kind) for f, kind in onsets]


def healthy_life(plan: DatasetPlan, bank: RecordBank, g: int, cfg: MonitorStudyConfig,
                 seed: int, nuisance: str = "none") -> LifeSimulator:
    """The healthy life of held-out gear ``g`` that the evaluation lives for a seed:
    ``healthy_hours`` without a nuisance, ``nuisance_hours`` under one of
    ``cfg.nuisances`` or of ``cfg.families`` (``family:<key>``, its conditions drawn by
    the seed: :func:`.study.life_conditions`) (the same windows as
    :func:`evaluate_gear`'s, for a look at one life: ``scripts/life_diagnostics.py``).

    Raises
    ------
    KeyError
        ``nuisance`` is neither ``none``, a key of ``cfg.nuisances`` nor ``family:`` and
        a key of ``cfg.families``.
    """
    cond = life_conditions(cfg, nuisance, seed)
    base = LifeConfig(hours=cfg.healthy_hours if cond is None else cfg.nuisance_hours,
                      interval_min=cfg.interval_min, commissioning_h=cfg.commissioning_h,
                      life_seed=int(seed), conditions=cond)
    return LifeSimulator(plan, g, base, bank)


def maintenance_log(cfg: MonitorStudyConfig, life: str, cond: ConditionsConfig | None
                    ) -> list[MaintenanceEvent]:
    """The maintenance log the evaluation hands the monitor for a life: its re-greasings
    where its family is ``logged`` (:class:`~.families.NuisanceFamily`),
    else none (an undeclared re-greasing is to be named an unexplained change)."""
    fam = family_of(life)
    if fam is None or not cfg.families[fam].logged or cond is None or cond.regrease is None:
        return []
    return [MaintenanceEvent(float(h), "regrease") for h in cond.regrease.hours]


def monitor_healthy(model: DiagnosisModel, cfg: MonitorStudyConfig, life: LifeSimulator,
                    seed: int, nuisance: str = "none"
                    ) -> tuple[GearMonitor, GearMonitor, Trace, list[Alarm], tuple]:
    """The monitor on a healthy ``life`` (:func:`healthy_life`) as the evaluation counts
    its false alarms: the life's maintenance log (``nuisance``'s) declared, commissioned on
    its first ``commissioning_h``, then run over the rest by
    :func:`~swgmon.advisories.stream.run_stream`; ``seed`` the monitor's (the life's).

    Returns
    -------
    commissioned, monitor : GearMonitor
        As commissioned (a fork the run leaves alone), and the one that ran.
    trace : Trace
        Every window after commissioning.
    alarms : list of Alarm
        Every alarm, named.
    windows : tuple
        Features (n, F), operating points (n, 2) and :class:`Conditions` of those windows.
    """
    n_comm = int(round(cfg.commissioning_h * 60 / cfg.interval_min))
    f, p, meta = features_of(life, 0, len(life))
    cond = Conditions.of(meta)
    mon = GearMonitor(model, cfg.rule, cfg.interval_min, seed=int(seed), normal=cfg.normal,
                      naming=cfg.naming)
    mon.declare(maintenance_log(cfg, nuisance, life.life.conditions))
    mon.commission(f[:n_comm], p[:n_comm], cond[:n_comm])
    commissioned = mon.fork()
    f, p, c = f[n_comm:], p[n_comm:], cond[n_comm:]
    tr, named, _ = run_stream(mon, f, p, meta["hour"][n_comm:], c)
    return commissioned, mon, tr, named, (f, p, c)


def _key(plan: DatasetPlan, dataset: str, g: int, seed: int, nuisance: str) -> dict:
    """The columns that name a life's data set, gear, seed and nuisance in every table."""
    return {"dataset": plan.config.name if plan.profile is not None else dataset,
            "output_encoder": has_twist(plan), "held_out_gear": g, "seed": seed,
            "nuisance": nuisance}


def _fault_row(key: dict, sim: LifeSimulator, fo: FaultOnset, kind: str) -> dict:
    return {**key, "fault": fo.fault,
            "severity": max((q[1] for q in fo.points), key=abs) if fo.points else fo.severity,
            "onset": kind, "onset_h": fo.onset_h,
            "bridge": f"s{sim.sensor}" if fo.fault in SENSOR_FAULTS else ""}


def evaluate_gear(plan: DatasetPlan, banks: dict[int, RecordBank], g: int,
                  model: DiagnosisModel, cfg: MonitorStudyConfig, dataset: str,
                  nuisance: str = "none", seeds: list[int] | None = None
                  ) -> tuple[list[dict], list[dict], list[dict]]:
    """The monitor (and the per-window rule and ``always``) on every life of held-out gear
    ``g`` for every seed, under a nuisance of ``cfg.nuisances``, a family
    (``family:<key>``) or none: result rows, false-alarm rows (every alarm, the gear-fault
    alarms among them, the advisories, the hour of the first alarm naming the temperature
    sensor, ``temperature_sensor_h``, NaN: none) and, without a nuisance, the rows of the
    trade-off curve (:func:`_curve_healthy`, :func:`_curve_fault`). ``seeds`` None:
    ``cfg.seeds``, and for a family ``cfg.family_seeds``."""
    rows, fa_rows, curve = [], [], []
    n_comm = int(round(cfg.commissioning_h * 60 / cfg.interval_min))
    if seeds is None:
        seeds = cfg.family_seeds if family_of(nuisance) is not None else cfg.seeds
    for seed in seeds:
        healthy, sims = lives_of(plan, banks, g, cfg, seed, nuisance)
        commissioned, mon, tr, named, (f, p, c) = monitor_healthy(model, cfg, healthy, seed,
                                                                  nuisance)
        lost_h = next((a.hour for a in named if a.fault == TEMPERATURE_SENSOR), None)
        key = _key(plan, dataset, g, seed, nuisance)
        hours_h = float(healthy.life.hours - cfg.commissioning_h)
        fa_rows.append({**key, "detector": "monitor", "healthy_hours": hours_h,
                        "false_alarms": len(named),
                        "gear_fault_alarms": sum(a.kind == "gear_fault" for a in named),
                        "sensor_fault_alarms": sum(a.kind == "sensor_fault" for a in named),
                        "unexplained_changes": sum(a.kind == "unexplained_change"
                                                   for a in named),
                        "advisories": len(advisories(tr, mon)),
                        "temperature_sensor_h": np.nan if lost_h is None else float(lost_h)})
        fa_rows += [{**key, "detector": d, "healthy_hours": hours_h, "false_alarms": n}
                    for d, n in (("per_window", int(_per_window(tr.log_proba).sum())),
                                 ("always", len(tr.score)))]
        healthy_curve = _curve_healthy(tr, cfg, key, hours_h, curve) \
            if nuisance == "none" else None
        for sim, fo, kind in sims:
            k0 = int(np.searchsorted(sim.schedule.hour, fo.onset_h, side="left"))
            before = k0 - 1 - n_comm  # the healthy trace's window before the onset
            start = (0.0, None) if before < 0 else (tr.cusums[before], tr.state(before))
            fmon = _monitor_at(commissioned, tr, before, f, p, c, named)
            lost = lost_h is not None and before >= 0 and lost_h <= tr.hour[before]
            fmon = reading_lost(fmon) if lost else fmon
            life = _fault_life(fmon, sim, k0, *start, cfg.windows_at_once, lost=lost)
            ftr, mm = life[0], life[3]
            row = _fault_row(key, sim, fo, kind)
            if healthy_curve is not None:
                _curve_fault(ftr, fo, before, healthy_curve, cfg, row, curve)
            past = _past_changes(sim, k0, life, cfg.windows_at_once)
            rows.append({**row, **_monitor_row(*past, fo)})
            rows.append({**row, **_per_window_row("per_window", model.classes,
                                                  np.argmax(ftr.log_proba, axis=1), mm, fo)})
            rows.append({**row, "detector": "always", "detected": True, "time_to_detect_h": 0.0,
                         "fault_at_alarm": "unknown", "fault_after_1h": "unknown",
                         "severity_est": np.nan, "severity_at_alarm": 0.0,
                         "severity_low": np.nan, "severity_high": np.nan})
    return rows, fa_rows, curve


def _labels(sim: LifeSimulator, start: int, stop: int, refs: References,
            detectors: list[WindowClassifier]) -> tuple[dict[str, np.ndarray], np.ndarray,
                                                       np.ndarray]:
    """Each detector's class index (0: healthy) of windows ``start:stop`` of a life, with
    the windows' hours and true severities."""
    sig, meta = sim.windows(start, stop)
    fs = sim.plan.config.chain.sample_rate_hz
    x = {k: window_inputs(k, sig, meta, refs, fs) for k in {d.input for d in detectors}}
    return {d.name: d.labels(x[d.input]) for d in detectors}, meta["hour"], meta["severity"]


def evaluate_detectors(plan: DatasetPlan, banks: dict[int, RecordBank], g: int,
                       detectors: list[WindowClassifier], cfg: MonitorStudyConfig,
                       dataset: str, nuisance: str = "none") -> tuple[list[dict], list[dict]]:
    """Per-window detectors on the lives of held-out gear ``g`` (those of
    :func:`evaluate_gear`, under the same nuisance): false alarms over the first
    ``detector_hours`` of each healthy life, and each fault life from its onset until an
    hour after the detector's first alarm (or the fault life's end). Returns result rows and
    false-alarm rows."""
    rows, fa_rows = [], []
    n_comm = int(round(cfg.commissioning_h * 60 / cfg.interval_min))
    n_det = int(round(cfg.detector_hours * 60 / cfg.interval_min))
    for seed in cfg.seeds:
        healthy, sims = lives_of(plan, banks, g, cfg, seed, nuisance)
        refs = References.of(healthy, n_comm)
        stop = min(len(healthy), n_comm + n_det)
        labels, _, _ = _labels(healthy, n_comm, stop, refs, detectors)
        key = _key(plan, dataset, g, seed, nuisance)
        fa_rows += [{**key, "detector": d, "healthy_hours": (stop - n_comm) * cfg.interval_min
                     / 60, "false_alarms": int(np.sum(v != 0))} for d, v in labels.items()]
        for sim, fo, kind in sims:
            k0 = int(np.searchsorted(sim.schedule.hour, fo.onset_h, side="left"))
            row = _fault_row(key, sim, fo, kind)
            for d in detectors:
                lab, mm = _detector_life(sim, k0, refs, d, cfg.windows_at_once)
                rows.append({**row, **_per_window_row(d.name, d.classes, lab, mm, fo)})
    return rows, fa_rows


def _detector_life(sim: LifeSimulator, k0: int, refs: References, det: WindowClassifier,
                   chunk: int) -> tuple[np.ndarray, dict[str, np.ndarray]]:
    """A detector's labels of a fault life from its onset, ``chunk`` windows at a time,
    until an hour after its first faulty window (or the fault life's end); with the
    windows' ``hour`` and ``severity``."""
    labs, hours, sevs = [], [], []
    first = None
    for a in range(k0, len(sim), chunk):
        lab, hour, sev = _labels(sim, a, min(a + chunk, len(sim)), refs, [det])
        labs.append(lab[det.name]), hours.append(hour), sevs.append(sev)
        bad = np.flatnonzero(lab[det.name] > 0)
        if first is None and bad.size:
            first = float(hour[bad[0]])
        if first is not None and float(hour[-1]) >= first + 1.0:
            break
    return np.concatenate(labs), {"hour": np.concatenate(hours),
                                  "severity": np.concatenate(sevs)}


def _curve_thresholds(cfg: MonitorStudyConfig) -> dict[float, float]:
    return {d: threshold(dataclasses.replace(cfg.rule, design_hours=d), cfg.interval_min)
            for d in cfg.curve_hours if d <= cfg.rule.design_hours}


def _curve_healthy(tr: Trace, cfg: MonitorStudyConfig, key: dict, hours_h: float,
                   out: list[dict]) -> dict[float, np.ndarray]:
    """False alarms of the healthy life at each design rate of the curve; returns each
    rate's CUSUMs (the state a fault life starts from)."""
    lf = judged_bets(tr.p, tr.outside, cfg.rule)
    states = {}
    for d, h in _curve_thresholds(cfg).items():
        cus, al = run_cusums(lf, h, latch=False)
        states[d] = cus
        out.append({**key, "design_hours": d, "life": "healthy", "healthy_hours": hours_h,
                    "false_alarms": len(al)})
    return states


def _curve_fault(ftr: Trace, fo: FaultOnset, before: int, states: dict, cfg, row: dict,
                 out: list[dict]) -> None:
    """Time to detect of a fault life at each design rate of the curve (NaN: not within
    the windows scored before the default rule's alarm, i.e. later than it)."""
    n = int(np.sum(~np.isnan(ftr.p)))
    lf = judged_bets(ftr.p[:n], ftr.outside[:n], cfg.rule)
    for d, h in _curve_thresholds(cfg).items():
        start = 0.0 if before < 0 else states[d][before]
        _, al = run_cusums(lf, h, start, latch=True)
        out.append({**row, "design_hours": d, "life": "fault",
                    "time_to_detect_h": float(ftr.hour[al[0]] - fo.onset_h) if al else np.nan})


def _monitor_at(commissioned: GearMonitor, tr: Trace, before: int, f: np.ndarray,
                p: np.ndarray, c: Conditions, named: list[Alarm]) -> GearMonitor:
    """The monitor of the healthy run ``tr`` as it was after its window ``before``, for a
    fault life that branches off there: a fork of the monitor at commissioning's end,
    the healthy windows replayed through it where a point's load had left commissioning's
    range by then (its recommissioning; :meth:`GearMonitor.run`), following the friction
    as after a re-greasing from each unexplained change ``named`` by then
    (:func:`swgmon.advisories.stream.run_stream`), and not relearning from an alarm
    named a gear fault on (:attr:`GearMonitor.fault_suspected`; the replay, one run,
    relearns nothing from its first alarm on, as the stream where no later cut explains
    it away)."""
    if before < 0 or not (tr.outside[:before + 1] & Outside.LOAD).any():
        m = commissioned.fork()
    else:
        m = commissioned.fork(fresh_draws=True)
        w = slice(0, before + 1)
        m.run(f[w], p[w], tr.hour[w], c[w], latch=False)
    m.fault_suspected = any(a.kind == "gear_fault" and a.index <= before for a in named)
    for a in named:
        if before >= 0 and a.fault == UNEXPLAINED_CHANGE and a.hour <= tr.hour[before]:
            adopt_change(m, a, 1.0)  # the factor itself is in the trace's state
    return m


def _fault_life(mon: GearMonitor, sim: LifeSimulator, k0: int, start,
                friction_start: tuple[float, float] | None, chunk: int, lost: bool = False):
    """A fault life from its onset, ``chunk`` windows at a time, until ``confirm_h`` after the
    monitor's alarm and the per-window rule's (or the fault life's end); the CUSUMs and the
    friction factor start from ``start`` and ``friction_start`` (the healthy life's before
    the onset; None: the monitor's own). ``lost``: the temperature sensor has failed, the
    monitor goes on without its reading (:func:`~swgmon.advisories.stream.read_without`), as it
    does from a reading that drops out (NaN), its CUSUMs anew, as
    :func:`~swgmon.advisories.stream.run_stream`
    does. Returns the trace, features, operating points, metadata and conditions, the monitor in
    force at the end and whether the reading was lost by then."""
    traces, feats, pts, metas, conds = [], [], [], [], []
    first: dict[str, float | None] = {"monitor": None, "per_window": None}
    state, fstate = start, friction_start
    for a in range(k0, len(sim), chunk):
        f, p, m = features_of(sim, a, min(a + chunk, len(sim)))
        cond = Conditions.of(m)
        for w, lose in _reading_spans(cond, len(f), lost):
            if lose:  # the reading lost at window w.start
                lost, mon = True, reading_lost(mon)
                state = 0.0 if first["monitor"] is None else state
                fstate = traces[-1].state(len(traces[-1].hour) - 1) if traces else fstate
            hours = m["hour"][w]
            c = read_without(mon, f[w], p[w], cond[w], hours, (mon.friction, mon.last_hour)
                             if fstate is None else fstate) if lost else cond[w]
            t = mon.run(f[w], p[w], hours, c, latch=True, start=state, friction_start=fstate) \
                if first["monitor"] is None else mon.score_only(f[w], p[w], hours, c, fstate)
            fstate = None  # from the next span on, the monitor's own
            if first["monitor"] is None and t.alarms:
                first["monitor"] = float(t.hour[t.alarms[0]])
            elif first["monitor"] is None:
                state = t.cusums[-1]
            bad = np.flatnonzero(_per_window(t.log_proba))
            if first["per_window"] is None and bad.size:
                first["per_window"] = float(t.hour[bad[0]])
            traces.append(t), feats.append(f[w]), pts.append(p[w]), conds.append(c)
            metas.append({k: v[w] for k, v in m.items()})
        last = float(m["hour"][-1])
        if all(x is not None and last >= x + mon.confirm_h for x in first.values()):
            break
    meta = {k: np.concatenate([m[k] for m in metas]) for k in metas[0]}
    return (Trace.concat(traces), np.concatenate(feats), np.concatenate(pts), meta,
            Conditions.concat(conds), mon, lost)


def _reading_spans(cond: Conditions, n: int, lost: bool) -> list[tuple[slice, bool]]:
    """A chunk's windows before its first missing reading and from it, each with whether
    the reading is lost at its first window."""
    t = None if lost else cond.temperature_c
    j = int(np.argmin(np.isfinite(t))) if t is not None and not np.isfinite(t).all() else n
    return [(w, w.start == j) for w in (slice(0, j), slice(j, n)) if w.stop > w.start]


def _benign(al: Alarm, cond: ConditionsConfig | None) -> bool:
    """Whether the life itself holds what an alarm names: a re-greasing at or before an
    alarm named an unexplained change, a temperature sensor failed at or before one named
    it. Any other alarm after a fault's onset is that fault's detection, named right or
    not (an unexplained change the life holds no re-greasing for is the fault's alarm)."""
    if cond is None:
        return False
    if al.fault == UNEXPLAINED_CHANGE:
        return cond.regrease is not None and min(cond.regrease.hours) <= al.hour
    sensor = cond.temperature_sensor
    return (al.fault == TEMPERATURE_SENSOR and sensor is not None and sensor.fault != "none"
            and sensor.fault_hour <= al.hour)


def _past_changes(sim: LifeSimulator, k0: int, life: tuple, chunk: int):
    """The monitor and a fault life's trace (with its windows, :func:`_fault_life`'s
    ``life``, from window ``k0``) from its first alarm that is not the fault's
    (:func:`_benign`: a re-greasing's or a failed temperature sensor's alarm, named so, is
    not the fault's detection): after such an unexplained change the monitor goes on from
    the friction's new level, after the temperature sensor's fault without the reading, as
    :func:`swgmon.advisories.stream.run_stream` does."""
    k, tr, mon, lost = k0, life[0], life[5], life[6]
    while tr.alarms:
        a = tr.alarms[0]
        al = diagnose(mon, tr, a, *life[1:3], life[4])
        if not _benign(al, sim.life.conditions) or a + 1 >= len(tr.hour) \
                or (al.fault == TEMPERATURE_SENSOR and lost):
            break
        fr, hour = tr.state(a)
        if al.fault == UNEXPLAINED_CHANGE:
            fr = adopt_change(mon, al, fr)
        else:
            lost, mon = True, reading_lost(mon)
        k += a + 1
        life = _fault_life(mon, sim, k, 0.0, (fr, hour), chunk, lost=lost)
        tr, mon, lost = life[0], life[5], life[6]
    return mon, *life[:5]


def _monitor_row(mon, tr, ff, pp, mm, cond, fo) -> dict:
    if not tr.alarms:
        return {"detector": "monitor", "detected": False, "time_to_detect_h": np.nan,
                "fault_at_alarm": "", "fault_after_1h": "", "severity_est": np.nan,
                "severity_at_alarm": np.nan, "severity_low": np.nan, "severity_high": np.nan}
    a = tr.alarms[0]
    al = diagnose(mon, tr, a, ff, pp, cond)
    return {"detector": "monitor", "detected": True, "time_to_detect_h": al.hour - fo.onset_h,
            "fault_at_alarm": al.fault_at_alarm, "fault_after_1h": al.fault,
            "severity_est": al.severity, "severity_at_alarm": float(mm["severity"][a]),
            "severity_low": al.severity_low, "severity_high": al.severity_high,
            "bridge_named": al.bridge or ""}


def _per_window_row(detector: str, classes: list[str], labels: np.ndarray, mm, fo) -> dict:
    """A per-window detector's row: alarm at its first window classified faulty; the fault
    named at it, and by the most frequent faulty class of the hour from it."""
    bad = np.flatnonzero(labels > 0)
    if bad.size == 0:
        return {"detector": detector, "detected": False, "time_to_detect_h": np.nan,
                "fault_at_alarm": "", "fault_after_1h": "", "severity_est": np.nan,
                "severity_at_alarm": np.nan, "severity_low": np.nan, "severity_high": np.nan}
    a = int(bad[0])
    hour = mm["hour"]
    end = int(np.searchsorted(hour, hour[a] + 1.0, side="right"))
    later = labels[a:end]
    later = later[later > 0]
    return {"detector": detector, "detected": True, "time_to_detect_h": hour[a] - fo.onset_h,
            "fault_at_alarm": classes[int(labels[a])],
            "fault_after_1h": classes[int(np.bincount(later).argmax())],
            "severity_est": np.nan, "severity_at_alarm": float(mm["severity"][a]),
            "severity_low": np.nan, "severity_high": np.nan}


def _nuisances(cfg: MonitorStudyConfig) -> list[str]:
    return ["none", *cfg.nuisances]


def banks_of(plan: DatasetPlan) -> dict[int, RecordBank]:
    """Every gear's records, shared by all its lives (and by the parts of one held-out
    gear run in one worker: :func:`learn.tasks.parts.run_parts`; a record is
    the same whichever batch simulated it)."""
    return {int(x.id): record_bank(plan, int(x.id)) for x in plan.config.gears}


def _steady_only(cfg: MonitorStudyConfig, life: str) -> bool:
    """Whether a life's conditions change the payload or the duty cycle (a family:
    whether it draws either), which need steady operating points."""
    fam = family_of(life)
    if fam is not None:
        return bool({"payload", "duty"} & set(cfg.families[fam].parts))
    c = None if life == "none" else cfg.nuisances[life]
    return c is not None and (bool(c.payload) or c.duty_change is not None)


def _runnable(plan: DatasetPlan, cfg: MonitorStudyConfig, lives: list[str] | None = None
              ) -> list[str]:
    """The lives a data set can live (default: none and every fixed nuisance): payload
    and duty changes need steady operating points."""
    return [n for n in (_nuisances(cfg) if lives is None else lives)
            if plan.profile is None or not _steady_only(cfg, n)]


def run_held_out(plan: DatasetPlan, dataset: str, g: int, cfg: MonitorStudyConfig,
                 lives: list[str] | None = None, seeds: list[int] | None = None,
                 banks: dict[int, RecordBank] | None = None) -> dict:
    """Train the diagnosis model on the other gears and evaluate the monitor on held-out
    gear ``g`` (:func:`evaluate_gear`) without and under every nuisance: rows, false
    alarms, curve, timing and the model.

    ``lives``: the lives evaluated instead (``none``, keys of ``cfg.nuisances``,
    ``family:<key>`` of ``cfg.families``), those a data set cannot live left out;
    ``seeds``: their seeds (None: :func:`evaluate_gear`'s); ``banks``: the gears' records
    (:func:`banks_of`; None: new ones), shared with other parts of the same plan.

    Raises
    ------
    KeyError
        A life that names no nuisance or family, before any work.
    """
    for life in lives or []:
        life_conditions(cfg, life, 0)
    t0 = time.perf_counter()
    gears = [int(x.id) for x in plan.config.gears]
    banks = banks_of(plan) if banks is None else banks
    model = train_model(plan, banks, [x for x in gears if x != g], cfg)
    t1 = time.perf_counter()
    rows, fa, curve = [], [], []
    for nuisance in _runnable(plan, cfg, lives):
        r, a, c = evaluate_gear(plan, banks, g, model, cfg, dataset, nuisance, seeds)
        rows, fa, curve = rows + r, fa + a, curve + c
    t2 = time.perf_counter()
    return {"rows": rows, "false_alarms": fa, "curve": curve, "train_s": t1 - t0,
            "evaluate_s": t2 - t1, "dataset": dataset, "held_out_gear": g, "model": model}


def run_detectors(plan: DatasetPlan, dataset: str, g: int, cfg: MonitorStudyConfig,
                  names: list[str], device: str = "cpu",
                  banks: dict[int, RecordBank] | None = None) -> list[dict]:
    """Train the per-window detectors ``names`` on the other gears and evaluate them on
    held-out gear ``g`` (:func:`evaluate_detectors`) without and under every nuisance;
    one part per detector (rows, false alarms, an empty curve, timing). A torch net runs
    on ``device`` (resolved: ``cpu``, ``cuda:0``; ``monitor.device``); ``banks`` as
    :func:`run_held_out`'s."""
    t0 = time.perf_counter()
    gears = [int(x.id) for x in plan.config.gears]
    banks = banks_of(plan) if banks is None else banks
    dets = train_detectors(plan, banks, [x for x in gears if x != g], cfg, names,
                           device=device)
    t1 = time.perf_counter()
    rows, fa = [], []
    for nuisance in _runnable(plan, cfg):
        r, a = evaluate_detectors(plan, banks, g, dets, cfg, dataset, nuisance)
        rows, fa = rows + r, fa + a
    t2 = time.perf_counter()
    return [{"rows": [r for r in rows if r["detector"] == d],
             "false_alarms": [r for r in fa if r["detector"] == d], "curve": [],
             "train_s": (t1 - t0) / len(names), "evaluate_s": (t2 - t1) / len(names),
             "dataset": dataset, "held_out_gear": g, "detector": d} for d in names]


def to_frames(parts: list[dict]) -> tuple[pd.DataFrame, pd.DataFrame, pd.DataFrame]:
    """Results, false-alarm and trade-off-curve tables of the parts of
    :func:`run_held_out` and :func:`run_detectors`."""
    return tuple(pd.DataFrame([r for p in parts for r in p[k]])
                 for k in ("rows", "false_alarms", "curve"))


__all__ = ["COMPARED", "banks_of", "evaluate_detectors", "evaluate_gear",
           "fault_life_configs", "fault_lives", "healthy_life", "monitor_healthy",
           "nuisance_fault_lives", "run_detectors", "run_held_out", "to_frames"]
