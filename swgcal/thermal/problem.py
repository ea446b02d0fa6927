"""A joint log (data kind 3) as a thermal calibration problem, and its calibration.

:func:`build_problem` reads a joint log (:func:`swgsim.datasets.joint_log.read_joint_log`)
and wraps one joint: the measured temperature the target, the project's first-order model
the base (:class:`.library.FirstOrderJoint`), the candidate effects
(:data:`.library.THERMAL_LIBRARY`), the residual probes and the held-out split: the part
before the log's first gap is fitted, the part after it held out (its first half chooses
the effects, its second half gives the errors before and after). The model runs through
the whole log from its first reading, the gap included, with the joint standing still
there, powered and holding its link: no gear loss, the motor's squared current that of
its standstill readings [choice: the log does not say what the robot did; in the UR3 day
the cycle count does not advance over the 5.2-h gap (105 either side) while every joint
comes back 1.6-3.6 K warmer than it left: powered, not cycling].

:func:`calibrate` then checks that the fits are physical (:func:`physical_check`: no
parameter on a bound of its fit or outside its range) and cross-validates both ways
across the gap (:func:`cross_validate`); the sensor's resolution, the smallest step
between readings (:func:`sensor_resolution`), is the problem's ``resolution``.
"""

from __future__ import annotations

import dataclasses
import inspect
import os
from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np

from swgsim.base.typed import build, complete
from swgsim.datasets.joint_log import JOINTS, JointLog, read_joint_log

from ..core import fit_terms, integrated_autocorr_time, physical_check
from ..diagnose import BinnedProbe, PeriodicProbe, Probe, TrendProbe
from ..loop import (
    CalibrationResult,
    Problem,
    SelectionConfig,
    check_candidates,
    gain_floor,
    paired_gain,
    refit_final,
    select_effects,
)
from ..split import HeldOutSplit
from .library import THERMAL_LIBRARY, FirstOrderJoint, first_order_lag
from .options import POWERED_A, STANDSTILL_RAD_S, ThermalKindOptions, ThermalOptions

__all__ = ["OPTIONS", "ThermalSignals", "build_problem", "calibrate", "cross_validate",
           "physical_check", "sensor_resolution", "thermal_probes", "thermal_problem",
           "thermal_signals"]

#: The typed options of this kind's problem (read by :func:`swgcal.api.options_from_config`).
OPTIONS = ThermalKindOptions
#: Fewest readings in each of fit, validation and test [-] [choice: several time
#: constants' worth of the 0.0625-K steps of a joint sensor at 1 Hz].
MIN_READINGS = 60
_PROBE_LAG_MIN = 10.0  # lag of the probes' inputs [min] [choice: a winding's time scale]


@dataclass(frozen=True)
class ThermalSignals:
    """What a joint reports, as the thermal terms see it; inputs are held over the
    interval that ends at each reading (zero-order hold); over a gap the joint stands,
    powered (module docstring).

    Attributes
    ----------
    t_s, dt_s : ndarray, shape (n,)
        Seconds since the first reading; the interval ending at each (0 first) [s].
    loss_w : ndarray, shape (n,)
        The gear's loss proxy (1 − η) k_τ abs(I) abs(ω) [W].
    current_sq_a2, neighbour_sq_a2 : ndarray, shape (n,)
        The joint's squared motor current; that of joints j−1 and j+1 summed [A²].
    still : ndarray, shape (n,)
        1 where the joint stands (abs(ω) below :data:`.options.STANDSTILL_RAD_S`, or a gap).
    speed_abs : ndarray, shape (n,)
        abs(ω) held [rad/s].
    cycle : ndarray, shape (n,)
        The log's cycle count [-].
    powered : ndarray, shape (n,)
        1 where the arm is powered (its motor currents' magnitudes sum above
        :data:`.options.POWERED_A`, or a gap), else 0.
    room_max_c : float
        The coolest joint's first reading: the room is no warmer [°C] (the base's bound,
        :meth:`.library.FirstOrderJoint.linear_bounds`).
    room_c : float or None
        A measured room [°C] (:attr:`.options.ThermalOptions.room_c`), or None.
    """

    t_s: np.ndarray
    dt_s: np.ndarray
    loss_w: np.ndarray
    current_sq_a2: np.ndarray
    neighbour_sq_a2: np.ndarray
    still: np.ndarray
    speed_abs: np.ndarray
    cycle: np.ndarray
    joint: int
    powered: np.ndarray
    room_max_c: float
    room_c: float | None = None

    @property
    def n(self) -> int:
        return int(self.t_s.size)


def _held(x: np.ndarray, gap_rows: np.ndarray, at_gap: float = 0.0) -> np.ndarray:
    """x over the interval ending at each row: the previous row's (missing: the last
    reading before it), ``at_gap`` over a gap, 0 before the first row."""
    x = np.asarray(x, float)
    ok = np.isfinite(x)
    last = np.maximum.accumulate(np.where(ok, np.arange(x.size), 0))
    filled = np.where(ok[last], x[last], 0.0)
    out = np.concatenate([[0.0], filled[:-1]])
    out[gap_rows] = at_gap
    return out


def thermal_signals(log: JointLog, joint: int, torque_per_amp_nm: float,
                    gear_efficiency: float, room_c: float | None = None) -> ThermalSignals:
    """The signals of one joint of a log (:class:`ThermalSignals`).

    Parameters
    ----------
    joint : int
        0-5.
    torque_per_amp_nm, gear_efficiency : float
        k_τ [N m/A] and η [-] of the loss proxy (:mod:`.options`).
    room_c : float, optional
        A measured room [°C] (:attr:`.options.ThermalOptions.room_c`).
    """
    i, w = log.current_a[:, joint], log.speed_rad_s[:, joint]
    nb = [k for k in (joint - 1, joint + 1) if 0 <= k < JOINTS]
    loss = (1.0 - gear_efficiency) * torque_per_amp_nm * np.abs(i) * np.abs(w)
    g = log.gap_rows
    dt = np.concatenate([[0.0], np.diff(log.t_s)])
    stands = np.abs(w) < STANDSTILL_RAD_S
    nb_sq = np.nansum(log.current_a[:, nb] ** 2, axis=1)

    def holding(x):  # the mean over the standstill readings, over a gap
        return float(np.nanmean(x[stands])) if np.any(stands & np.isfinite(x)) else 0.0

    arm = np.abs(log.current_a)
    seen = np.isfinite(arm).any(axis=1)
    powered = np.where(seen, (np.nansum(arm, axis=1) > POWERED_A).astype(float), np.nan)
    firsts = [col[np.isfinite(col)][0] for col in log.temperature_c.T if np.isfinite(col).any()]
    return ThermalSignals(
        t_s=log.t_s, dt_s=dt, loss_w=_held(loss, g),
        current_sq_a2=_held(i * i, g, holding(i * i)),
        neighbour_sq_a2=_held(nb_sq, g, holding(nb_sq)),
        still=_held((np.abs(w) < STANDSTILL_RAD_S).astype(float), g, 1.0),
        speed_abs=_held(np.abs(w), g), cycle=log.cycle.astype(float), joint=joint,
        powered=_held(powered, g, 1.0), room_max_c=float(min(firsts)), room_c=room_c)


def sensor_resolution(y: np.ndarray) -> float:
    """The temperature sensor's resolution as the data show it: the smallest nonzero step
    between consecutive readings (0.0625 K in the UR3 day, as its README states).

    Parameters
    ----------
    y : ndarray, shape (n,)
        Readings [°C]; NaN: missing (skipped).

    Returns
    -------
    float
        [K]; 0 where no two readings differ (or the data are not quantised finer than
        their noise shows: a synthetic log's is its smallest difference).
    """
    d = np.abs(np.diff(np.asarray(y, float)[np.isfinite(y)]))
    d = d[d > 0]
    return float(d.min()) if d.size else 0.0


def thermal_probes() -> list[Probe]:
    """The residual probes of the thermal side (one per residual signature).

    Returns
    -------
    list of Probe
        current_squared, neighbour_current_squared, speed (bins over the input lagged by
        10 min), time (cubic trend), time_periodic (best sinusoid over t, 2 min to a
        third of the log), cycle (bins over the cycle count).
    """

    def lagged(name):
        return lambda s: first_order_lag(getattr(s, name), s.dt_s, _PROBE_LAG_MIN)

    def t_range(s):
        return 120.0, (s.t_s[-1] - s.t_s[0]) / 3.0

    return [
        BinnedProbe("current_squared", "follows the motor current squared (lagged 10 min)",
                    lagged("current_sq_a2"), 20),
        BinnedProbe("neighbour_current_squared", "follows the neighbours' current squared "
                    "(lagged 10 min)", lagged("neighbour_sq_a2"), 20),
        BinnedProbe("speed", "follows the joint's speed (lagged 10 min)", lagged("speed_abs"),
                    20),
        TrendProbe("time", "drifts over the day", lambda s: s.t_s),
        PeriodicProbe("time_periodic", "periodic in time", lambda s: s.t_s, t_range,
                      unit="s"),
        BinnedProbe("cycle", "depends on the cycle count", lambda s: s.cycle, 20),
    ]


def _split(log: JointLog, valid: np.ndarray, fit_frac: float) -> HeldOutSplit:
    """Fit before the first gap (or the first ``fit_frac`` of the log), then the rest's
    first half validation, its second half test; rows without a reading in none."""
    rows = np.arange(log.n)
    if log.gap_rows.size:
        cut, how = int(log.gap_rows[0]), "before the log's first gap"
    else:
        cut, how = int(np.searchsorted(log.t_s, fit_frac * log.t_s[-1])), \
            f"the first {fit_frac:g} of the log (no gap)"
    rest = rows[cut:]
    mid = int(rest[0] + np.searchsorted(log.t_s[rest], 0.5 * (log.t_s[rest[0]]
                                                             + log.t_s[-1])))
    fit, val, test = (r[valid[r]] for r in (rows[:cut], rows[cut:mid], rows[mid:]))
    for name, r in (("fit", fit), ("validation", val), ("test", test)):
        if r.size < MIN_READINGS:
            raise ValueError(f"joint log {log.name!r}: {r.size} readings to {name}, fewer "
                             f"than {MIN_READINGS}; fit: {how}, the rest halved into "
                             "validation and test")
    return HeldOutSplit(fit, val, test, {
        "kind": "after_gap", "fit": how, "validation": "the first half of the rest",
        "test": "the second half of the rest",
        "hours": {k: [float(log.t_s[r[0]] / 3600), float(log.t_s[r[-1]] / 3600)]
                  for k, r in (("fit", fit), ("validation", val), ("test", test))}})


def thermal_problem(log: JointLog, *, joint: int = ThermalOptions.joint,
                    torque_per_amp_nm: float = ThermalOptions.torque_per_amp_nm,
                    gear_efficiency: float = ThermalOptions.gear_efficiency,
                    fit_frac: float = ThermalOptions.fit_frac,
                    room_c: float | None = ThermalOptions.room_c,
                    candidates: Sequence[str] | None = None) -> Problem:
    """Calibration problem of one joint of a log (module docstring).

    Parameters
    ----------
    joint, torque_per_amp_nm, gear_efficiency, fit_frac, room_c
        :class:`.options.ThermalOptions` (defaults and ranges there).
    candidates : sequence of str, optional
        Library keys (default all of :data:`THERMAL_LIBRARY`).

    Returns
    -------
    Problem
        ``kind="thermal"``, the target the joint's temperature [°C].

    Raises
    ------
    ValueError
        An option outside its range (named by its app key, e.g. ``thermal.joint``), an
        unknown candidate, too few readings to fit, validate or test.
    """
    given = {"thermal": {"joint": joint, "torque_per_amp_nm": torque_per_amp_nm,
                         "gear_efficiency": gear_efficiency, "fit_frac": fit_frac,
                         "room_c": room_c}}
    build(complete(given, ThermalKindOptions, ""), ThermalKindOptions, "")
    keys = check_candidates(candidates, THERMAL_LIBRARY, "thermal")
    y = log.temperature_c[:, joint]
    split = _split(log, np.isfinite(y), fit_frac)
    sig = thermal_signals(log, joint, torque_per_amp_nm, gear_efficiency, room_c)
    res = sensor_resolution(y)
    return Problem(
        name=f"{log.name}_J{joint}", kind="thermal", units="K", signals=sig, resolution=res,
        y=np.where(np.isfinite(y), y, np.nanmean(y)), t=log.t_s,
        base_model=(FirstOrderJoint(),), library={k: THERMAL_LIBRARY[k] for k in keys},
        probes=thermal_probes(), split=split, screen_jointly=True,
        meta={"joint": joint, "n_samples": log.n, "start": log.start,
              "duration_h": float(log.t_s[-1] / 3600), "gaps_h": [
                  float((log.t_s[g] - log.t_s[g - 1]) / 3600) for g in log.gap_rows],
              "missing_readings": int(np.sum(~np.isfinite(y))),
              "protective_stops": int(log.protective_stop.sum()),
              "grip_losses": int(log.grip_lost.sum()),
              "torque_per_amp_nm": torque_per_amp_nm, "gear_efficiency": gear_efficiency,
              "resolution": res, "room_max_c": sig.room_max_c, "room_c": sig.room_c})


def build_problem(measured: str | os.PathLike | JointLog, **options: Any) -> Problem:
    """Calibration problem of a joint log (data kind 3).

    Parameters
    ----------
    measured : path-like or JointLog
        A joint log in the UR3 CobotOps format, or one read.
    **options
        ``joint``, ``torque_per_amp_nm``, ``gear_efficiency``, ``fit_frac``, ``room_c``,
        ``candidates``: see :func:`thermal_problem`.

    Raises
    ------
    TypeError
        An unknown option (the message lists the allowed ones).
    ValueError
        See :func:`swgsim.datasets.joint_log.read_joint_log` and :func:`thermal_problem`.
    """
    allowed = [k for k in inspect.signature(thermal_problem).parameters if k != "log"]
    unknown = sorted(set(options) - set(allowed))
    if unknown:
        raise TypeError(f"unknown thermal problem options {unknown}; allowed: {allowed}")
    log = measured if isinstance(measured, JointLog) else read_joint_log(measured)
    return thermal_problem(log, **options)


def calibrate(problem: Problem, config: SelectionConfig | None = None) -> CalibrationResult:
    """Calibrate a thermal problem: the selection loop (:func:`swgcal.loop.select_effects`),
    then every kept effect whose primary parameters the final fit (fit + validation) does
    not pin down is removed and the model refitted (a pair the loop accepted can carry a
    member that the final fit leaves at zero). The problem screens every candidate with
    the base's τ, gain and offset refitted with it (:attr:`swgcal.loop.Problem.screen_jointly`):
    a second heat source trades off against the base's own time constant, which, held at
    its value fitted without the effect, leaves a single effect too little to show.

    Then the fits are checked (:func:`physical_check`, of the base alone and of the final
    model) and cross-validated both ways across the gap (:func:`cross_validate`).

    Returns
    -------
    CalibrationResult
        ``problem.meta``: ``removed`` (the effects removed and why), ``physical``
        (``{"before": [...], "after": [...]}``: why the base alone and the final model are
        not physical; empty lists: both are) and ``crossval``.
    """
    res = _drop_unpinned(select_effects(problem, config))
    meta = {**res.problem.meta, "physical": {"before": physical_check(res.base_model_final),
                                             "after": physical_check(res.final)},
            "crossval": cross_validate(res)}
    return dataclasses.replace(res, problem=dataclasses.replace(res.problem, meta=meta))


def cross_validate(result: CalibrationResult) -> dict[str, Any]:
    """Blocked cross-validation both ways across the log's gap, effect by effect.

    Block A is the fit part (before the first gap), block B the held-out part (after it).
    Forward: fitted on A, scored on B. Backward: fitted on B, scored on A after its first
    reading, which sets the joint's temperature at the start (T_0 held: the model's initial
    condition, which B, hours later, cannot tell). Each model, the base alone and then with
    each kept effect in the order kept, is refitted (every parameter) on the fit block from
    the final model's time constants and each term's own starts (several optima). The
    selection itself (which effects) was made on the forward split (fit A, choose on B's
    first half), so B is not blind to it. An effect clears where its gain over the model
    before it exceeds both its floors (:func:`swgcal.loop.gain_floor`; the paired s.e. on
    the scored block with the τ_int of the model-before's residual) both ways.

    Parameters
    ----------
    result : CalibrationResult
        Of a thermal problem.

    Returns
    -------
    dict
        ``resolution_k`` (:func:`sensor_resolution`), ``noise_floor_k`` (the final
        residual's difference-based noise floor), ``z`` (``gain_noise_z``), ``blocks``
        (hours of A and B), ``rows``: per model ``model``, ``forward`` and ``backward``
        (``rmse`` on the scored block [K], ``gain`` over the model before it [K], for an
        effect ``gain_se``, ``floor`` [K] and ``why``; ``unphysical``:
        :func:`physical_check` of that fit) and, for an effect, ``clears``.
    """
    p, cfg = result.problem, result.config
    sp, y, sig, final, zero = p.split, p.y, p.signals, result.final, np.zeros_like(p.y)
    a, b = sp.fit, np.union1d(sp.validation, sp.test)
    th = {t.name: x for t, x in zip(final.terms, final.thetas, strict=True)}
    base = final.terms[0]
    effects = [t for t in final.terms if t.name in result.added]
    ways = (("forward", a, b, base),
            ("backward", b, a[1:], FirstOrderJoint(base.name, start_c=float(y[a[0]]))))
    rows: list[dict[str, Any]] = []
    before: dict[str, np.ndarray] = {}
    for k in range(len(effects) + 1):
        row: dict[str, Any] = {"model": base.name if k == 0 else "+ " + effects[k - 1].name}
        for way, fit_idx, score_idx, b0 in ways:
            terms = [b0, *effects[:k]]
            f = fit_terms(terms, sig, y, fit_idx, [[th[t.name], *t.starts(sig, zero, fit_idx)]
                                                   for t in terms], max_starts=cfg.max_starts,
                          max_rel_se=cfg.max_rel_se, max_abs_corr=cfg.max_abs_corr)
            r = (y - f.predict(sig))[score_idx]
            row[way] = {"rmse": float(np.sqrt(np.mean(r * r))), "gain": None,
                        "unphysical": physical_check(f)}
            if k:
                gain, se = paired_gain(before[way], r, integrated_autocorr_time(before[way]))
                row[way].update(zip(("gain", "gain_se", "floor", "why"),
                                    (gain, se, *gain_floor(p, se, cfg.gain_noise_z)),
                                    strict=True))
            before[way] = r
        if k:
            row["clears"] = bool(all(row[w]["gain"] > row[w]["floor"] for w, *_ in ways))
        rows.append(row)
    hours = {k: [float(p.t[r[0]] / 3600), float(p.t[r[-1]] / 3600)] for k, r in (("A", a),
                                                                                ("B", b))}
    return {"resolution_k": float(p.meta.get("resolution", 0.0)), "z": cfg.gain_noise_z,
            "noise_floor_k": float(result.diag_after.noise_floor), "blocks": hours,
            "rows": rows}


def _drop_unpinned(result: CalibrationResult) -> CalibrationResult:
    """Remove the kept effects whose primary parameters are weak in the final model."""
    p, cfg, final = result.problem, result.config, result.final
    weak = {}
    for term in result.effect_terms():
        est = final.estimates_of(term.name)
        bad = [f"{k} {est[k].flag}" for k in term.primary() if k in est and est[k].flag]
        if bad:
            weak[term.name] = "; ".join(bad)
    meta = {**p.meta, "removed": [{"name": k, "why": v} for k, v in weak.items()]}
    if not weak:
        return dataclasses.replace(result, problem=dataclasses.replace(p, meta=meta))
    keep = [i for i, t in enumerate(final.terms) if t.name not in weak]
    zero = np.zeros_like(p.y)  # each term's own starts beside its value: bounds make the
    cur = fit_terms([final.terms[i] for i in keep], p.signals, p.y, p.split.fit,  # fit
                    [[final.thetas[i], *final.terms[i].starts(p.signals, zero, p.split.fit)]
                     for i in keep], uncertainty=False,  # multimodal
                    max_rel_se=cfg.max_rel_se, max_abs_corr=cfg.max_abs_corr,
                    max_starts=cfg.max_starts)
    return refit_final(result, cur, meta, keep_note=False)
