"""The monitor's training data: simulated lives of the training gears, their features, the
diagnosis model and the per-window detectors trained on them.

For a data set (a checked :class:`~swgsim.datasets.plan.DatasetPlan`) and the gears it
trains on, each gear lives a healthy life (commissioning, then ``train_healthy_h`` hours)
and one short life per class, severity and fault position or bridge
(:func:`training_lives`); the diagnosis model learns the z-scores of their windows against
the gear's own normal behaviour (:func:`train_model`), the per-window detectors their
inputs against one reference window (:func:`train_detectors`). The held-out evaluation
(:mod:`.evaluate`) and the C export (:mod:`swgmon.export`) take their data
from here.
"""

from __future__ import annotations

import dataclasses
import hashlib
from collections.abc import Callable, Iterator
from contextlib import contextmanager
from contextvars import ContextVar

import numpy as np

from learn.inputs.health import feature_names, life_features
from swgmon.assessment.gear_monitor import normal_windows
from swgmon.assessment.model import HEALTHY, DiagnosisModel, design_matrix, fit_diagnosis
from swgmon.detection.normal import Conditions, NormalBehaviour
from swgmon.evaluation.detectors import (
    DETECTORS,
    References,
    WindowClassifier,
    fit_detector,
    window_inputs,
)
from swgmon.evaluation.study import MonitorStudyConfig
from swgsim.datasets.life import BLOCK, LifeSimulator
from swgsim.datasets.plan import DatasetPlan
from swgsim.datasets.records import RecordBank
from swgsim.datasets.schedule import FaultOnset, LifeConfig
from swgsim.sensing.sensor_faults import SENSOR_FAULTS
from swgsim.sensing.sensor_faults import SEVERITIES as SENSOR_SEVERITIES


def table_v_severities(plan: DatasetPlan, fault: str) -> list[float]:
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


def train_severities(plan: DatasetPlan, fault: str, cfg: MonitorStudyConfig) -> list[float]:
    """Severities of a class's training lives: a gear fault's ``cfg.fault_severities``
    or else its Table V ones, a sensor fault's ``cfg.sensor_train_levels`` from its mild to
    its severe one, geometrically."""
    if fault in cfg.fault_severities:
        return [float(v) for v in cfg.fault_severities[fault]]
    sevs = table_v_severities(plan, fault)
    if fault not in SENSOR_FAULTS:
        return sevs
    return [float(v) for v in np.geomspace(sevs[0], sevs[-1], cfg.sensor_train_levels)]


def classes(plan: DatasetPlan, cfg: MonitorStudyConfig) -> list[str]:
    """Healthy, then the evaluated gear faults and sensor faults."""
    gear = [f for f in plan.config.variants if f != HEALTHY]
    chosen = cfg.faults or [*gear, *SENSOR_FAULTS]
    return [HEALTHY, *chosen]


#: The lives' features kept inside :func:`shared_features`, per life (None: none kept).
_SHARED: ContextVar[dict | None] = ContextVar("shared_features", default=None)


@contextmanager
def shared_features() -> Iterator[None]:
    """Within the block, :func:`features_of` keeps every life's features per window and
    hands them to the next caller asking for the same life's windows (the monitor, its
    ablation and the baselines of the benchmark read the same lives); dropped at exit.
    A life is known by its plan, gear and :class:`~swgsim.datasets.schedule.LifeConfig`,
    which fix its windows."""
    token = _SHARED.set({})
    try:
        yield
    finally:
        _SHARED.reset(token)


def features_of(sim: LifeSimulator, start: int, stop: int,
                on_block: Callable[[np.ndarray, dict], None] | None = None
                ) -> tuple[np.ndarray, np.ndarray, dict[str, np.ndarray]]:
    """Health features, operating points and metadata of windows ``start:stop``;
    ``on_block(signals, meta)`` is called with each block of simulated windows. Inside
    :func:`shared_features` (and without ``on_block``), windows already computed for
    the same life are not computed again."""
    if stop <= start:
        n_f = len(feature_names(twist=has_twist(sim.plan)))
        return np.empty((0, n_f)), np.empty((0, 2)), {}
    memo = _SHARED.get()
    if memo is not None and on_block is None:
        return _shared(memo, sim, start, stop)
    return _computed(sim, start, stop, on_block)


def _shared(memo: dict, sim: LifeSimulator, start: int, stop: int
            ) -> tuple[np.ndarray, np.ndarray, dict[str, np.ndarray]]:
    """:func:`features_of` from the life's windows kept in ``memo``, computing the
    missing runs of windows and keeping them."""
    key = hashlib.sha256(repr((sim.plan.config_hash, sim.gear_id, sim.life)).encode()
                         ).hexdigest()
    have = memo.setdefault(key, {"done": np.zeros(len(sim), bool)})
    todo = np.flatnonzero(~have["done"][start:stop]) + start
    if todo.size:
        cut = np.flatnonzero(np.diff(todo) > 1) + 1
        for run in np.split(todo, cut):
            f, p, m = _computed(sim, int(run[0]), int(run[-1]) + 1)
            for name, v in (("f", f), ("p", p), *m.items()):
                if name not in have:  # strings as objects: a later run's may be longer
                    have[name] = np.empty((len(sim), *v.shape[1:]),
                                          object if v.dtype.kind == "U" else v.dtype)
                have[name][run] = v
            have["done"][run] = True
    meta = {k: np.array(v[start:stop].tolist()) if v.dtype == object else v[start:stop].copy()
            for k, v in have.items() if k not in ("done", "f", "p")}
    return have["f"][start:stop].copy(), have["p"][start:stop].copy(), meta


def _computed(sim: LifeSimulator, start: int, stop: int,
              on_block: Callable[[np.ndarray, dict], None] | None = None
              ) -> tuple[np.ndarray, np.ndarray, dict[str, np.ndarray]]:
    """Health features, operating points and metadata of windows ``start:stop``
    (``stop > start``), simulated block by block."""
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


def has_twist(plan: DatasetPlan) -> bool:
    """Whether a data set's lives record an output encoder (twist features)."""
    return plan.profile is not None and plan.config.profile.angles.output_encoder_bits is not None


def training_lives(plan: DatasetPlan, bank: RecordBank, g: int, cfg: MonitorStudyConfig
                   ) -> list[tuple[LifeSimulator, str, float]]:
    """The training lives of gear ``g``: (life, class, severity), the healthy life first.

    The healthy life is commissioning, then ``train_healthy_h`` hours; then one life per
    class and severity per fault position (``train_variants`` of them) or per bridge (a
    sensor fault): one window, then the fault for ``train_fault_h`` hours (no
    commissioning of its own: the healthy life's normal behaviour serves). Life seeds from 1000
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


def train_model(plan: DatasetPlan, banks: dict[int, RecordBank], gears: list[int],
                cfg: MonitorStudyConfig, seed: int = 0, release: bool = False
                ) -> DiagnosisModel:
    """The diagnosis model trained on the lives of ``gears`` (:func:`training_lives`):
    the healthy life gives the gear's normal behaviour (as the monitor builds it) and the healthy
    windows after commissioning, each fault life its windows after the first. With
    ``release``, each gear's records are dropped once its features are taken, so the peak
    holds one gear's (a lot of many instances); a record asked for again is simulated
    again, the same (a record is a function of its key). Without it, a worker's later
    parts read them (the monitor evaluation's)."""
    cls = classes(plan, cfg)
    n_comm = int(round(cfg.commissioning_h * 60 / cfg.interval_min))
    xs, ys, sev, gid = [], [], [], []
    for g in gears:
        lives = training_lives(plan, banks[g], g, cfg)
        f0, p0, m0 = features_of(lives[0][0], 0, len(lives[0][0]))
        c0 = Conditions.of(m0)
        fit = normal_windows(p0[:n_comm])  # as the monitor builds it
        base = NormalBehaviour.fit(f0[:n_comm][fit], p0[:n_comm][fit], c0[:n_comm][fit],
                                   cfg.normal)  # the laws the monitor will use
        for sim, c, s in lives:
            if c == HEALTHY:
                f, p, cond = f0[n_comm:], p0[n_comm:], c0[n_comm:]
            else:
                f, p, m = features_of(sim, 1, len(sim))
                cond = Conditions.of(m)
            xs.append(design_matrix(base.z(f, p, cond), p))
            ys.append(np.full(len(f), c, object))
            sev.append(np.full(len(f), s))
            gid.append(np.full(len(f), g))
        if release:
            banks[g].release(healthy=True)
    x = np.concatenate(xs)
    model = fit_diagnosis(x, np.concatenate(ys).astype(str), np.concatenate(sev),
                          np.concatenate(gid), cls, seed=seed, folds=cfg.severity_folds)
    model.points_range = np.stack([x[:, -2:].min(axis=0), x[:, -2:].max(axis=0)])
    model.n_features = x.shape[1] - 2
    model.sample_rate_hz = float(plan.config.chain.sample_rate_hz)
    model.window_s = float(plan.config.chain.window_s)
    return model


def _inputs(sim: LifeSimulator, start: int, stop: int, refs: References, kinds: set[str]
            ) -> dict[str, np.ndarray]:
    """The detectors' inputs of windows ``start:stop`` of a life, per input kind."""
    fs = sim.plan.config.chain.sample_rate_hz
    out: dict[str, list] = {k: [] for k in kinds}
    for a in range(start, stop, BLOCK):
        sig, meta = sim.windows(a, min(a + BLOCK, stop))
        for k in kinds:
            out[k].append(window_inputs(k, sig, meta, refs, fs))
    return {k: np.concatenate(v) for k, v in out.items()}


def detector_windows(plan: DatasetPlan, banks: dict[int, RecordBank], gears: list[int],
                     cfg: MonitorStudyConfig, kinds: set[str], seed: int = 0
                     ) -> tuple[dict[str, np.ndarray], np.ndarray]:
    """The per-window detectors' training set: the windows the diagnosis model is trained
    on (:func:`train_model`) as inputs ``kinds`` (of :func:`learn.inputs.signals.build_input`),
    each against its gear's references, as many of each class (:func:`_balanced`).

    Returns
    -------
    x : dict of ndarray, float32
        Per input kind, (n, F) or (n, C, T).
    y : ndarray of str, shape (n,)
        Class names.
    """
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
    return {k: np.concatenate(v)[keep] for k, v in xs.items()}, y[keep]


def train_detectors(plan: DatasetPlan, banks: dict[int, RecordBank], gears: list[int],
                    cfg: MonitorStudyConfig, names: list[str], seed: int = 0,
                    device: str = "cpu") -> list[WindowClassifier]:
    """The per-window detectors ``names`` (keys of
    :data:`.detectors.DETECTORS`) trained on :func:`detector_windows`; a
    torch net on ``device`` (resolved)."""
    if not names:
        return []
    x, y = detector_windows(plan, banks, gears, cfg, {DETECTORS[b].input for b in names},
                            seed)
    return [fit_detector(b, x[DETECTORS[b].input], y, classes(plan, cfg), seed, device)
            for b in names]


def _balanced(y: np.ndarray, seed: int) -> np.ndarray:
    """Indices of an equal number of windows of every class (that of the smallest class,
    drawn from the seed, kept in order): a class-balanced training set like the paper's
    data set, not one in which 15 fault positions per class outnumber healthy windows."""
    rng = np.random.default_rng([seed, 11])
    names, counts = np.unique(y, return_counts=True)
    n = int(counts.min())
    return np.sort(np.concatenate([rng.choice(np.flatnonzero(y == c), n, replace=False)
                                   for c in names]))


__all__ = ["classes", "detector_windows", "features_of", "has_twist", "shared_features",
           "table_v_severities", "train_detectors", "train_model", "train_severities",
           "training_lives"]
