"""Windows of simulated gear lives through the embedded stage's Python reference.

Each gear lives as the monitor's training lives
(:func:`swgmon.evaluation.evaluate.training_lives`); its normal behaviour comes from its own
commissioning windows (:func:`swgmon.assessment.gear_monitor.normal_windows`), its labelled
windows are the healthy ones after commissioning and each fault life's after its first.
The lives are steady: each window's input angle is the nominal one
(:func:`.reference.nominal_angle`). ``docs/EXPORT.md``, "Method".
"""

from __future__ import annotations

from dataclasses import dataclass, replace

import numpy as np

from swgmon.assessment.gear_monitor import normal_windows
from swgmon.assessment.model import HEALTHY
from swgmon.evaluation.study import MonitorStudyConfig
from swgmon.evaluation.training import classes, training_lives
from swgmon.export import reference as ref
from swgsim.datasets.life import BLOCK
from swgsim.datasets.records import RecordBank


@dataclass
class GearWindows:
    """One gear's labelled windows through the reference stage.

    Attributes
    ----------
    gear : int
    feats : ndarray, float32, shape (n, F)
        Reference features (:func:`.reference.stage_features`).
    op : ndarray of int, shape (n,)
        Operating-point row of each window.
    y : ndarray of int, shape (n,)
        Class index (0: healthy).
    efficiency : ndarray, float32, shape (n,)
    mean, inv_std : ndarray, float32, shape (K, F)
        The gear's normal behaviour from its commissioning windows.
    feats64 : ndarray, shape (n, F)
        The monitor's own least-squares features of the same windows
        (:func:`learn.inputs.health.window_features`).
    mean64, inv_std64 : ndarray, shape (K, F)
        The gear's normal behaviour of ``feats64``.
    signals : ndarray, float32, shape (n, 5, n_t) or None
        The windows' bridge outputs [mV/V], kept when asked (for the C's check).
    """

    gear: int
    feats: np.ndarray
    op: np.ndarray
    y: np.ndarray
    efficiency: np.ndarray
    mean: np.ndarray
    inv_std: np.ndarray
    feats64: np.ndarray
    mean64: np.ndarray
    inv_std64: np.ndarray
    signals: np.ndarray | None = None


def base_tables(plan, n_harmonics: int = ref.N_HARMONICS) -> ref.StageTables:
    """The stage's tables of a data set without a normal behaviour (mean 0, 1 / std 1): window
    length, normal equations per speed, operating points and their classifier inputs.

    Raises
    ------
    ValueError
        If a speed's basis is ill-conditioned or reaches Nyquist
        (:func:`.reference.normal_equations`).
    """
    ch = plan.config.chain
    fs, n_t = float(ch.sample_rate_hz), int(round(ch.window_s * ch.sample_rate_hz))
    points = plan_points(plan)
    speeds = np.unique(points[:, 0])
    ne = [ref.normal_equations(v, fs, n_t, n_harmonics) for v in speeds]
    inputs = np.stack([np.round(points[:, 0]), np.round(points[:, 1] * 10)], axis=1)
    f = 5 * (n_harmonics + 2) + 1
    return ref.StageTables(
        n_t=n_t, fs_hz=fs, n_harmonics=n_harmonics, speeds_rpm=speeds,
        g_inv=np.stack([a for a, _ in ne]), gram=np.stack([b for _, b in ne]),
        points=points, speed_index=np.searchsorted(speeds, points[:, 0]),
        mean=np.zeros((len(points), f), np.float32),
        inv_std=np.ones((len(points), f), np.float32),
        point_inputs=inputs.astype(np.int16))


def plan_points(plan) -> np.ndarray:
    """Operating points (n_in_rpm, t_out_nm) of a data set, rows as the stage's tables."""
    ops = plan.config.operating_points
    return np.array([(float(v), float(t)) for v in ops.n_in_rpm for t in ops.t_out_nm])


def nominal_phi(tables: ref.StageTables, op: np.ndarray) -> np.ndarray:
    """Each window's nominal input angle at its operating point's speed
    (:func:`.reference.nominal_angle`), shape (n, n_t) [rad]."""
    return np.stack([ref.nominal_angle(tables.points[o, 0], tables.fs_hz, tables.n_t)
                     for o in op]) if len(op) else np.empty((0, tables.n_t), np.float32)


def op_rows(tables: ref.StageTables, n_in_rpm: np.ndarray, t_out_nm: np.ndarray
            ) -> np.ndarray:
    """Row of each window's operating point in ``tables.points``, shape (n,).

    Raises
    ------
    ValueError
        If a window's operating point is not in the table.
    """
    pts = np.stack([n_in_rpm, t_out_nm], axis=1)
    hit = (pts[:, None, :] == tables.points[None]).all(axis=2)
    if not hit.any(axis=1).all():
        bad = pts[np.flatnonzero(~hit.any(axis=1))[0]]
        raise ValueError(f"operating point {bad[0]:g} rpm, {bad[1]:g} N m is not one of the "
                         "data set's")
    return np.argmax(hit, axis=1)


def life_windows(sim, start: int, stop: int, tables: ref.StageTables, keep: bool = False):
    """Reference features of windows ``start:stop`` of a life: (feats (n, F), op (n,),
    efficiency (n,), signals (n, 5, n_t) or None, the monitor's features (n, F))."""
    from learn.inputs.health import window_features

    feats, ops, eff, sigs, f64 = [], [], [], [], []
    for a in range(start, stop, BLOCK):
        sig, meta = sim.windows(a, min(a + BLOCK, stop))
        op = op_rows(tables, meta["n_in_rpm"], meta["t_out_nm"])
        phi = nominal_phi(tables, op)
        e = meta["efficiency"].astype(np.float32)
        feats.append(ref.stage_features(sig, phi, e, op, tables))
        f64.append(window_features(sig, meta["n_in_rpm"], meta["efficiency"], tables.fs_hz,
                                   tables.n_harmonics))
        ops.append(op)
        eff.append(e)
        if keep:
            sigs.append(np.asarray(sig, np.float32))
    return (np.concatenate(feats), np.concatenate(ops), np.concatenate(eff),
            np.concatenate(sigs) if keep else None, np.concatenate(f64))


def normal32(feats: np.ndarray, op: np.ndarray, n_ops: int) -> tuple[np.ndarray, np.ndarray]:
    """Mean and 1 / std (ddof 1, std at least 1e-12, as swgmon.detection.normal.NormalBehaviour) of
    each operating point's normal-behaviour windows, float32, each shape (K, F).

    Raises
    ------
    ValueError
        If an operating point has fewer than two normal-behaviour windows.
    """
    mean = np.zeros((n_ops, feats.shape[1]))
    std = np.ones_like(mean)
    for k in range(n_ops):
        f = feats[op == k].astype(float)
        if len(f) < 2:
            raise ValueError(f"operating point {k} has {len(f)} commissioning windows for "
                             "the normal behaviour; at least 2 needed (raise commissioning_h)")
        mean[k], std[k] = f.mean(axis=0), np.maximum(f.std(axis=0, ddof=1), 1e-12)
    return mean.astype(np.float32), (1.0 / std).astype(np.float32)


def gear_windows(plan, g: int, cfg: MonitorStudyConfig, tables: ref.StageTables,
                 keep: bool = False) -> GearWindows:
    """One gear's normal behaviour and labelled windows (module docstring)."""
    cls = classes(plan, cfg)
    n_comm = int(round(cfg.commissioning_h * 60 / cfg.interval_min))
    lives = training_lives(plan, RecordBank(plan, g), g, cfg)
    healthy = lives[0][0]
    f0, op0, e0, s0, g0 = life_windows(healthy, 0, len(healthy), tables, keep)
    fit = normal_windows(tables.points[op0[:n_comm]])
    k = len(tables.points)
    mean, inv_std = normal32(f0[:n_comm][fit], op0[:n_comm][fit], k)
    mean64, inv_std64 = normal32(g0[:n_comm][fit], op0[:n_comm][fit], k)
    parts = [(f0[n_comm:], op0[n_comm:], e0[n_comm:], None if s0 is None else s0[n_comm:],
              g0[n_comm:], HEALTHY)]
    for sim, c, _ in lives[1:]:
        parts.append((*life_windows(sim, 1, len(sim), tables, keep), c))
    return GearWindows(
        gear=g, feats=np.concatenate([p[0] for p in parts]),
        op=np.concatenate([p[1] for p in parts]),
        y=np.concatenate([np.full(len(p[0]), cls.index(p[5])) for p in parts]),
        efficiency=np.concatenate([p[2] for p in parts]), mean=mean, inv_std=inv_std,
        feats64=np.concatenate([p[4] for p in parts]), mean64=mean64.astype(float),
        inv_std64=inv_std64.astype(float),
        signals=np.concatenate([p[3] for p in parts]) if keep else None)


def with_normal(tables: ref.StageTables, gw: GearWindows) -> ref.StageTables:
    """``tables`` with gear ``gw``'s normal behaviour."""
    return replace(tables, mean=gw.mean, inv_std=gw.inv_std)
