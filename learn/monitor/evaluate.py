"""Evaluation of the monitor: leave-one-gear-out over simulated gear lives.

For each data set (a checked :class:`~swgsim.datasets.plan.DatasetPlan`) and held-out gear, the
diagnosis model is trained on the other gears' lives (:func:`train_model`); then, per
seed, the held-out gear lives ``healthy_hours`` of healthy operation (false alarms,
counted with the CUSUM restarted after each) and, from the same commissioning, one life
per fault, severity and onset kind (:func:`fault_lives`). A fault life is the healthy life
up to its onset (same seed, so the same windows: its monitor state at the onset is the
healthy life's) and the fault after it, for ``horizon_h`` hours. Nothing is chosen on the
held-out gear: the model, its settings and the rule's threshold are fixed before.

Detectors side by side: ``monitor`` (the conformal CUSUM, :mod:`.monitor`);
``per_window`` (an alarm whenever one window is classified faulty by the same diagnosis
model); the per-window baselines of :mod:`.baselines` (``paper_rf``, the paper's pipeline
with one reference window; ``cnn_res``, the best per-window classifier), trained on the
same lives, whose false alarms are counted over the first ``baseline_hours`` of each
healthy life (a rate of thousands per 1000 h needs no more); and ``always`` (an alarm at
every window).
"""

from __future__ import annotations

import dataclasses
import time
from collections.abc import Callable
from dataclasses import dataclass, field

import numpy as np
import pandas as pd

from swgsim.datasets.life import BLOCK, LifeSimulator
from swgsim.datasets.records import RecordBank, record_bank
from swgsim.datasets.schedule import FaultOnset, LifeConfig
from swgsim.sensing.sensor_faults import SENSOR_FAULTS
from swgsim.sensing.sensor_faults import SEVERITIES as SENSOR_SEVERITIES

from .baselines import BASELINES, References, WindowClassifier, fit_baseline, window_inputs
from .features import feature_names, health_features
from .model import HEALTHY, Baseline, design_matrix, fit_diagnosis
from .monitor import GearMonitor, Trace, baseline_windows, run_cusums
from .rule import RuleConfig, log_bets, threshold

DETECTORS = ("monitor", "per_window", *BASELINES, "always")
#: Design rates of the trade-off curve (one false alarm per this many hours), up to the
#: study's own: each is a threshold of the same rule on the same p-values.
CURVE_DESIGN_HOURS = (1.0, 3.0, 10.0, 30.0, 100.0, 300.0, 1000.0)


@dataclass
class MonitorStudyConfig:
    """The evaluation's design, declared before it runs.

    Attributes
    ----------
    seeds : list of int
        Life seeds per held-out gear.
    healthy_hours : float
        Operating hours of each held-out gear's healthy life, commissioning included.
    commissioning_h : float
        Commissioning period of every life [h].
    interval_min : float
        Minutes between windows.
    horizon_h : float
        Hours a fault life runs after its onset.
    onset_window_h : list of float
        The onset is drawn uniformly this many hours after commissioning, [lo, hi].
    growth_h : float
        Hours of a growing fault's linear growth to its largest severity.
    train_fault_h : float
        Hours of each training life after its fault's onset.
    train_variants : int
        Training lives per gear fault and severity: the fault at as many positions around
        the flexspline (at (j + 1/2) 360° / count, not the held-out lives' random ones); a
        sensor fault has one life on each of the five bridges. 15 (v3; 5 before): chosen
        on the training gears alone (``scripts/naming_study.py``: trained on one training
        gear, judged on the other, both ways, the root and tip cracks were named right in
        0.83-0.92 and 0.67 of lives with 5 positions, in 1.00 with 15).
    sensor_train_levels : int
        Training severities of a sensor fault: this many, geometrically spaced from its mild
        to its severe severity (:data:`swgsim.sensing.sensor_faults.SEVERITIES`; 2: those two).
    train_healthy_h : float
        Hours of each training gear's healthy life after commissioning.
    faults : list of str
        Classes evaluated; empty: every gear fault of the data set and every sensor fault.
    gears : list of int
        Held-out gears; empty: every gear of the data set.
    baselines : list of str
        Per-window baselines evaluated beside the monitor (keys of
        :data:`learn.monitor.baselines.BASELINES`).
    baseline_hours : float
        Hours of each healthy life, after commissioning, over which the baselines' false
        alarms are counted.
    rule : RuleConfig
    """

    seeds: list[int] = field(default_factory=lambda: [0, 1, 2, 3, 4])
    healthy_hours: float = 1000.0
    commissioning_h: float = 24.0
    interval_min: float = 1.0
    horizon_h: float = 24.0
    onset_window_h: list[float] = field(default_factory=lambda: [1.0, 100.0])
    growth_h: float = 10.0
    train_fault_h: float = 0.5
    train_variants: int = 15
    sensor_train_levels: int = 2
    train_healthy_h: float = 10.0
    faults: list[str] = field(default_factory=list)
    gears: list[int] = field(default_factory=list)
    baselines: list[str] = field(default_factory=lambda: list(BASELINES))
    baseline_hours: float = 100.0
    rule: RuleConfig = field(default_factory=RuleConfig)


def table_v_severities(plan, fault: str) -> list[float]:
    """The data set's severities of a class (paper Table V): its list, or the first, middle
    and last of its linspace; a sensor fault's from
    :data:`swgsim.sensing.sensor_faults.SEVERITIES`."""
    if fault in SENSOR_FAULTS:
        return list(SENSOR_SEVERITIES[fault])
    spec = plan.config.variants[fault]
    if spec.severities is not None:
        return [float(s) for s in spec.severities]
    a, b, _ = spec.severity_linspace
    return [float(a), float((a + b) / 2), float(b)]


def train_severities(plan, fault: str, cfg: MonitorStudyConfig) -> list[float]:
    """Severities of a class's training lives: a gear fault's Table V ones, a sensor
    fault's ``cfg.sensor_train_levels`` from its mild to its severe one, geometrically."""
    sevs = table_v_severities(plan, fault)
    if fault not in SENSOR_FAULTS:
        return sevs
    return [float(v) for v in np.geomspace(sevs[0], sevs[-1], cfg.sensor_train_levels)]


def classes(plan, cfg: MonitorStudyConfig) -> list[str]:
    """Healthy, then the evaluated gear faults and sensor faults."""
    gear = [f for f in plan.config.variants if f != HEALTHY]
    chosen = cfg.faults or [*gear, *SENSOR_FAULTS]
    return [HEALTHY, *chosen]


def features_of(sim: LifeSimulator, start: int, stop: int,
                on_block: Callable[[np.ndarray, dict], None] | None = None
                ) -> tuple[np.ndarray, np.ndarray, dict[str, np.ndarray]]:
    """Health features, operating points and metadata of windows ``start:stop``;
    ``on_block(signals, meta)`` is called with each block of simulated windows."""
    if stop <= start:
        n_f = len(feature_names(twist=has_twist(sim.plan)))
        return np.empty((0, n_f)), np.empty((0, 2)), {}
    f, pts, metas = [], [], []
    for a in range(start, stop, BLOCK):
        sig, meta = sim.windows(a, min(a + BLOCK, stop))
        f.append(life_features(sim.plan, sig, meta))
        pts.append(np.stack([meta["n_in_rpm"], meta["t_out_nm"]], axis=1))
        metas.append(meta)
        if on_block is not None:
            on_block(sig, meta)
    meta = {k: np.concatenate([m[k] for m in metas]) for k in metas[0]}
    return np.concatenate(f), np.concatenate(pts), meta


def has_twist(plan) -> bool:
    """Whether a data set's lives record an output encoder (twist features)."""
    return plan.profile is not None and plan.config.profile.angles.output_encoder_bits is not None


def life_features(plan, sig: np.ndarray, meta: dict[str, np.ndarray]) -> np.ndarray:
    """Health features of a block of a life's windows: :func:`window_features`, in the
    angle domain when the windows carry angle channels (a profile), and the twist
    features with an output encoder; shape (n, F)."""
    sensor = plan.config.profile.angles.input_sensor() if plan.profile is not None else None
    return health_features(sig, meta, plan.config.chain.sample_rate_hz, sensor)


def training_lives(plan, bank: RecordBank, g: int, cfg: MonitorStudyConfig
                   ) -> list[tuple[LifeSimulator, str, float]]:
    """The training lives of gear ``g``: (life, class, severity), the healthy life first.

    The healthy life is commissioning, then ``train_healthy_h`` hours; then one life per
    class and severity per fault position (``train_variants`` of them) or per bridge (a
    sensor fault): one window, then the fault for ``train_fault_h`` hours (no
    commissioning of its own: the healthy life's baseline serves). Life seeds from 1000
    on (the held-out gear's use the study's seeds): fault positions differ from the
    held-out lives'.
    """
    life = LifeConfig(hours=cfg.commissioning_h + cfg.train_healthy_h,
                      interval_min=cfg.interval_min, commissioning_h=cfg.commissioning_h,
                      life_seed=1000)
    lives = [(LifeSimulator(plan, g, life, bank), HEALTHY, 0.0)]
    c0 = cfg.interval_min / 60.0
    for c in classes(plan, cfg)[1:]:
        sensor = c in SENSOR_FAULTS
        n_var = 5 if sensor else cfg.train_variants
        for s in train_severities(plan, c, cfg):
            for j in range(n_var):
                fo = FaultOnset(c, c0, s, sensor=j if sensor else None,
                                position_deg=None if sensor else 360.0 * (j + 0.5) / n_var)
                fl = dataclasses.replace(life, hours=c0 + cfg.train_fault_h,
                                         commissioning_h=c0, fault=fo,
                                         life_seed=1000 + len(lives))
                lives.append((LifeSimulator(plan, g, fl, bank), c, s))
    return lives


def train_model(plan, banks: dict[int, RecordBank], gears: list[int], cfg: MonitorStudyConfig,
                seed: int = 0):
    """The diagnosis model trained on the lives of ``gears`` (:func:`training_lives`):
    the healthy life gives the gear's baseline (as the monitor builds it) and the healthy
    windows after commissioning, each fault life its windows after the first."""
    cls = classes(plan, cfg)
    n_comm = int(round(cfg.commissioning_h * 60 / cfg.interval_min))
    xs, ys, sev, gid = [], [], [], []
    for g in gears:
        lives = training_lives(plan, banks[g], g, cfg)
        f0, p0, _ = features_of(lives[0][0], 0, len(lives[0][0]))
        fit = baseline_windows(p0[:n_comm])  # as the monitor builds it
        base = Baseline.fit(f0[:n_comm][fit], p0[:n_comm][fit])
        for sim, c, s in lives:
            f, p = (f0[n_comm:], p0[n_comm:]) if c == HEALTHY else features_of(sim, 1, len(sim))[:2]
            xs.append(design_matrix(base.z(f, p), p))
            ys.append(np.full(len(f), c, object))
            sev.append(np.full(len(f), s))
            gid.append(np.full(len(f), g))
    x = np.concatenate(xs)
    model = fit_diagnosis(x, np.concatenate(ys).astype(str), np.concatenate(sev),
                          np.concatenate(gid), cls, seed=seed)
    model.points_range = np.stack([x[:, -2:].min(axis=0), x[:, -2:].max(axis=0)])
    model.n_features = x.shape[1] - 2
    model.sample_rate_hz = float(plan.config.chain.sample_rate_hz)
    model.window_s = float(plan.config.chain.window_s)
    return model


def _inputs(sim: LifeSimulator, start: int, stop: int, refs: References, kinds: set[str]
            ) -> dict[str, np.ndarray]:
    """The baselines' inputs of windows ``start:stop`` of a life, per input kind."""
    fs = sim.plan.config.chain.sample_rate_hz
    out: dict[str, list] = {k: [] for k in kinds}
    for a in range(start, stop, BLOCK):
        sig, meta = sim.windows(a, min(a + BLOCK, stop))
        for k in kinds:
            out[k].append(window_inputs(k, sig, meta, refs, fs))
    return {k: np.concatenate(v) for k, v in out.items()}


def train_baselines(plan, banks: dict[int, RecordBank], gears: list[int],
                    cfg: MonitorStudyConfig, seed: int = 0) -> list[WindowClassifier]:
    """The per-window baselines (:mod:`.baselines`) trained on the windows the diagnosis
    model is trained on (:func:`train_model`), each against its gear's references, as
    many of each class (:func:`_balanced`)."""
    if not cfg.baselines:
        return []
    kinds = {BASELINES[b].input for b in cfg.baselines}
    n_comm = int(round(cfg.commissioning_h * 60 / cfg.interval_min))
    xs: dict[str, list] = {k: [] for k in kinds}
    ys = []
    for g in gears:
        lives = training_lives(plan, banks[g], g, cfg)
        refs = References.of(lives[0][0], n_comm)
        for sim, c, _ in lives:
            x = _inputs(sim, n_comm if c == HEALTHY else 1, len(sim), refs, kinds)
            for k in kinds:
                xs[k].append(x[k])
            ys.append(np.full(len(x[next(iter(kinds))]), c, object))
    y = np.concatenate(ys).astype(str)
    keep = _balanced(y, seed)
    return [fit_baseline(b, np.concatenate(xs[BASELINES[b].input])[keep], y[keep],
                         classes(plan, cfg), seed) for b in cfg.baselines]


def _balanced(y: np.ndarray, seed: int) -> np.ndarray:
    """Indices of an equal number of windows of every class (that of the smallest class,
    drawn from the seed, kept in order): a class-balanced training set like the paper's
    data set, not one in which 15 fault positions per class outnumber healthy windows."""
    rng = np.random.default_rng([seed, 11])
    names, counts = np.unique(y, return_counts=True)
    n = int(counts.min())
    return np.sort(np.concatenate([rng.choice(np.flatnonzero(y == c), n, replace=False)
                                   for c in names]))


def fault_lives(plan, cfg: MonitorStudyConfig, seed: int) -> list[tuple[FaultOnset, str]]:
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


class _Labeller:
    """``on_block`` of :func:`features_of`: each baseline's class index (0: healthy) of
    the blocks it is handed, from their signals (no window simulated twice)."""

    def __init__(self, refs: References, baselines: list[WindowClassifier], fs: float):
        self.refs, self.baselines, self.fs = refs, baselines, fs
        self.out: dict[str, list] = {b.name: [] for b in baselines}

    def __call__(self, sig: np.ndarray, meta: dict) -> None:
        x = {k: window_inputs(k, sig, meta, self.refs, self.fs)
             for k in {b.input for b in self.baselines}}
        for b in self.baselines:
            self.out[b.name].append(b.labels(x[b.input]))

    def labels(self) -> dict[str, np.ndarray]:
        return {d: np.concatenate(v) for d, v in self.out.items()}


def evaluate_gear(plan, banks, g: int, model, cfg: MonitorStudyConfig, dataset: str,
                  baselines: list[WindowClassifier] = ()
                  ) -> tuple[list[dict], list[dict], list[dict]]:
    """Every life of held-out gear ``g`` for every seed: result rows, false-alarm rows and
    the rows of the trade-off curve (:func:`_curve_healthy`, :func:`_curve_fault`)."""
    rows, fa_rows, curve = [], [], []
    n_comm = int(round(cfg.commissioning_h * 60 / cfg.interval_min))
    n_base = int(round(cfg.baseline_hours * 60 / cfg.interval_min))
    for seed in cfg.seeds:
        base = LifeConfig(hours=cfg.healthy_hours, interval_min=cfg.interval_min,
                          commissioning_h=cfg.commissioning_h, life_seed=int(seed))
        lives = fault_lives(plan, cfg, int(seed))
        sims = [(LifeSimulator(plan, g, dataclasses.replace(
            base, hours=f.onset_h + cfg.horizon_h, fault=f), banks[g]), f, kind)
            for f, kind in lives]
        healthy = LifeSimulator(plan, g, base, banks[g])
        n_scored = min(len(healthy), n_comm + n_base) if baselines else n_comm
        refs = References.of(healthy, n_comm) if baselines else None
        scored = _Labeller(refs, list(baselines), plan.config.chain.sample_rate_hz) \
            if baselines else None
        parts = [features_of(healthy, 0, n_comm),  # the baselines' blocks start after it
                 features_of(healthy, n_comm, n_scored, on_block=scored),
                 features_of(healthy, n_scored, len(healthy))]
        parts = [q for q in parts if len(q[0])]
        f, p = (np.concatenate([q[i] for q in parts]) for i in (0, 1))
        meta = {k: np.concatenate([q[2][k] for q in parts]) for k in parts[0][2]}
        mon = GearMonitor(model, cfg.rule, cfg.interval_min, seed=int(seed))
        mon.commission(f[:n_comm], p[:n_comm])
        tr = mon.run(f[n_comm:], p[n_comm:], meta["hour"][n_comm:], latch=False)
        hours_h = cfg.healthy_hours - cfg.commissioning_h
        counts = [("monitor", hours_h, len(tr.alarms)),
                  ("per_window", hours_h, int(_per_window(tr.log_proba).sum()))]
        if baselines:
            counts += [(b, (n_scored - n_comm) * cfg.interval_min / 60, int(np.sum(v != 0)))
                       for b, v in scored.labels().items()]
        counts.append(("always", hours_h, len(tr.score)))
        key = {"dataset": plan.config.name if plan.profile is not None else dataset,
               "output_encoder": has_twist(plan), "held_out_gear": g, "seed": seed}
        fa_rows += [{**key, "detector": d, "healthy_hours": h, "false_alarms": n}
                    for d, h, n in counts]
        healthy_curve = _curve_healthy(tr, cfg, key, hours_h, curve)
        for sim, fo, kind in sims:
            k0 = int(np.searchsorted(sim.schedule.hour, fo.onset_h, side="left"))
            start = 0.0 if k0 <= n_comm else tr.cusums[k0 - 1 - n_comm]
            ftr, ff, pp, mm, labels = _fault_life(mon, sim, k0, start, cfg, refs,
                                                  list(baselines))
            row = {**key, "fault": fo.fault,
                   "severity": max((q[1] for q in fo.points), key=abs) if fo.points
                   else fo.severity, "onset": kind, "onset_h": fo.onset_h,
                   "bridge": f"s{sim.sensor}" if fo.fault in SENSOR_FAULTS else ""}
            _curve_fault(ftr, fo, k0 - 1 - n_comm, healthy_curve, cfg, row, curve)
            rows.append({**row, **_monitor_row(mon, ftr, ff, pp, mm, fo)})
            for d, lab in labels.items():
                rows.append({**row, **_per_window_row(d, model.classes, lab, mm, fo)})
            rows.append({**row, "detector": "always", "detected": True, "time_to_detect_h": 0.0,
                         "fault_at_alarm": "unknown", "fault_after_1h": "unknown",
                         "severity_est": np.nan, "severity_at_alarm": 0.0,
                         "severity_low": np.nan, "severity_high": np.nan})
    return rows, fa_rows, curve


def _curve_thresholds(cfg: MonitorStudyConfig) -> dict[float, float]:
    return {d: threshold(dataclasses.replace(cfg.rule, design_hours=d), cfg.interval_min)
            for d in CURVE_DESIGN_HOURS if d <= cfg.rule.design_hours}


def _curve_healthy(tr: Trace, cfg: MonitorStudyConfig, key: dict, hours_h: float,
                   out: list[dict]) -> dict[float, np.ndarray]:
    """False alarms of the healthy life at each design rate of the curve; returns each
    rate's CUSUMs (the state a fault life starts from)."""
    lf = log_bets(tr.p, cfg.rule)
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
    lf = log_bets(ftr.p[:n], cfg.rule)
    for d, h in _curve_thresholds(cfg).items():
        start = 0.0 if before < 0 else states[d][before]
        _, al = run_cusums(lf, h, start, latch=True)
        out.append({**row, "design_hours": d, "life": "fault",
                    "time_to_detect_h": float(ftr.hour[al[0]] - fo.onset_h) if al else np.nan})


def _fault_life(mon: GearMonitor, sim: LifeSimulator, k0: int, start, cfg: MonitorStudyConfig,
                refs: References | None, baselines: list[WindowClassifier], chunk: int = 120):
    """A fault life from its onset, in chunks of windows, until ``confirm_h`` after the
    monitor's alarm and every per-window detector's (or the horizon): what they need, and
    no more windows. Returns the monitor's trace, features, operating points, metadata
    and each per-window detector's class indices (-1 where it was not run)."""
    traces, feats, pts, metas = [], [], [], []
    labels = {d: [] for d in ("per_window", *(b.name for b in baselines))}
    first: dict[str, float | None] = dict.fromkeys(["monitor", *labels])
    state = start
    for a in range(k0, len(sim), chunk):
        b = min(a + chunk, len(sim))
        last_start = float(sim.schedule.hour[a])
        pending = [x for x in baselines if first[x.name] is None
                   or last_start <= first[x.name] + mon.confirm_h]
        lab = _Labeller(refs, pending, sim.plan.config.chain.sample_rate_hz) \
            if pending else None
        f, p, m = features_of(sim, a, b, on_block=lab)
        t = mon.run(f, p, m["hour"], latch=True, start=state) if first["monitor"] is None \
            else mon.score_only(f, p, m["hour"])
        if first["monitor"] is None and t.alarms:
            first["monitor"] = float(t.hour[t.alarms[0]])
        elif first["monitor"] is None:
            state = t.cusums[-1]
        last = float(m["hour"][-1])
        chunk_labels = {"per_window": np.argmax(t.log_proba, axis=1),
                        **(lab.labels() if lab else {})}
        for d in labels:
            lab = chunk_labels.get(d, np.full(b - a, -1))
            labels[d].append(lab)
            bad = np.flatnonzero(lab > 0)
            if first[d] is None and bad.size:
                first[d] = float(t.hour[bad[0]])
        traces.append(t), feats.append(f), pts.append(p), metas.append(m)
        if all(x is not None and last >= x + mon.confirm_h for x in first.values()):
            break
    meta = {k: np.concatenate([m[k] for m in metas]) for k in metas[0]}
    return (Trace.concat(traces), np.concatenate(feats), np.concatenate(pts), meta,
            {d: np.concatenate(v) for d, v in labels.items()})


def _monitor_row(mon, tr, ff, pp, mm, fo) -> dict:
    if not tr.alarms:
        return {"detector": "monitor", "detected": False, "time_to_detect_h": np.nan,
                "fault_at_alarm": "", "fault_after_1h": "", "severity_est": np.nan,
                "severity_at_alarm": np.nan, "severity_low": np.nan, "severity_high": np.nan}
    a = tr.alarms[0]
    al = mon.diagnose(tr, a, ff, pp)
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


def run_held_out(plan, dataset: str, g: int, cfg: MonitorStudyConfig) -> dict:
    """Train on the other gears and evaluate held-out gear ``g``: rows, timing."""
    t0 = time.perf_counter()
    gears = [int(x.id) for x in plan.config.gears]
    banks = {x: record_bank(plan, x) for x in gears}
    train = [x for x in gears if x != g]
    model = train_model(plan, banks, train, cfg)
    # the per-window baselines' inputs (time-domain statistics, the synchronous residual)
    # are defined at a steady speed: on a profile the monitor runs without them
    baselines = train_baselines(plan, banks, train, cfg) if plan.profile is None else []
    t1 = time.perf_counter()
    rows, fa, curve = evaluate_gear(plan, banks, g, model, cfg, dataset, baselines)
    t2 = time.perf_counter()
    return {"rows": rows, "false_alarms": fa, "curve": curve, "train_s": t1 - t0,
            "evaluate_s": t2 - t1, "dataset": dataset, "held_out_gear": g, "model": model}


def to_frames(parts: list[dict]) -> tuple[pd.DataFrame, pd.DataFrame, pd.DataFrame]:
    """Results, false-alarm and trade-off-curve tables of :func:`run_held_out` parts."""
    return tuple(pd.DataFrame([r for p in parts for r in p[k]])
                 for k in ("rows", "false_alarms", "curve"))


__all__ = ["DETECTORS", "MonitorStudyConfig", "classes", "evaluate_gear", "fault_lives",
           "features_of", "run_held_out", "table_v_severities", "to_frames",
           "train_baselines", "train_model", "train_severities", "training_lives"]
