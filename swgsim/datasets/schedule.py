"""A gear life's schedule: duty cycle, commissioning, fault onset and severity over the
operating hours, decided before any simulation.

A life runs a duty cycle over operating points (each held for its dwell time, in turn;
from a duty change's hour on, for other times: ``conditions.duty_change``) and records one
window every ``interval_min`` of operation. It starts with a
commissioning period known to be healthy; then, optionally, a fault of any class (a gear
fault of :data:`swgsim.gear.faults.FAULTS` or a sensor fault of
:data:`swgsim.sensing.sensor_faults.SENSOR_FAULTS`) sets in at ``onset_h`` and follows a
severity schedule: a step, linear growth to a final severity, (hour, severity) pairs, or
growth to failure by a law driven by what the joint does (Paris' law for cracks, Archard's
for wear, :mod:`swgsim.datasets.growth`). The types here are what the data-set config
(:mod:`swgsim.datasets.config`) holds; the simulation of a life's windows is
:mod:`swgsim.datasets.life`.
"""

from __future__ import annotations

import dataclasses
import math
from dataclasses import dataclass, field

import numpy as np

from swgsim.base.typed import LATER
from swgsim.datasets.conditions import ConditionsConfig
from swgsim.datasets.growth import (
    LAWS,
    RunToFailure,
    check_to_failure,
    failure_hour,
    grown_severity,
)
from swgsim.gear.faults import get_fault
from swgsim.gear.thermal import REF_TEMP_C
from swgsim.sensing.sensor_faults import SENSOR_FAULTS, is_sensor_fault

__all__ = ["GROWTH", "MAX_WINDOWS", "DutyPoint", "FaultOnset", "LifeConfig", "Schedule",
           "duty_cycle", "grow", "n_windows", "schedule", "severity_at",
           "staircase", "uses_position"]

GROWTH = ("step", "linear", "points", *LAWS)


@dataclass
class DutyPoint:
    """One operating point of a duty cycle and how long it is held each cycle.

    Attributes
    ----------
    n_in_rpm : float
        Input (WG) speed [rpm].
    t_out_nm : float
        Load torque [N m].
    dwell_min : float
        Operating time at this point per cycle [min], > 0.
    """

    n_in_rpm: float = 2000.0
    t_out_nm: float = 7.0
    dwell_min: float = 10.0


@dataclass
class FaultOnset:
    """The fault of a life and its severity schedule.

    Attributes
    ----------
    fault : str
        ``healthy`` (no fault), a gear fault or a ``sensor_*`` fault.
    onset_h : float
        Operating hours at which the fault sets in, >= the commissioning period.
    severity : float
        Final severity (``step``, ``linear``); the severity at the onset (``paris``,
        ``archard``).
    growth : {"step", "linear", "points", "paris", "archard"}
        ``step``: ``severity`` from the onset on; ``linear``: from 0 at the onset to
        ``severity`` ``growth_h`` hours later, then constant; ``points``: linear between
        the (hour, severity) pairs of ``points``, 0 before the first (a known degradation
        replayed); ``paris`` (cracks), ``archard`` (wear): grown from ``severity`` at the
        onset by the law, driven by each window's speed, acting load and temperature, to
        the failure severity, then held there (:mod:`swgsim.datasets.growth`).
    growth_h : float
        Hours of linear growth, > 0 for ``linear``.
    points : list of [hour, severity]
        Increasing hours, for ``points``.
    position_deg : float or None
        Circumferential position of a gear fault on the flexspline [deg]; None draws it
        uniformly from the life's seed.
    sensor : int or None
        Faulty bridge of a sensor fault (0..4); None draws it from the life's seed.
    to_failure : RunToFailure or None
        The law's constants and the failure severity (``paris``, ``archard``); None: their
        defaults. Left out of the config hash when None.
    """

    fault: str = "healthy"
    onset_h: float = 0.0
    severity: float = 0.0
    growth: str = "step"
    growth_h: float = 0.0
    points: list[list[float]] = field(default_factory=list)
    position_deg: float | None = None
    sensor: int | None = None
    to_failure: RunToFailure | None = field(default=None, metadata={LATER: "runs to failure"})


@dataclass
class LifeConfig:
    """One gear's life (module docstring).

    Attributes
    ----------
    hours : float
        Operating hours recorded, commissioning included, > 0.
    interval_min : float
        Operating minutes between windows, > 0 (default one a minute).
    commissioning_h : float
        The first hours, known healthy: the monitor's commissioning. The default, 24 h (1,440
        windows, 240 per operating point of the paper's six), is above the minimum of the
        monitor's default design (one false alarm per 1000 h; ``swgmon``).
    duty : list of DutyPoint
        The duty cycle; empty: the data set's operating points, 10 min each.
    fault : FaultOnset
    severity_levels : int
        Steps of the staircase that simulates a growing severity, >= 1.
    disturbed : bool
        Add eq. (10)'s per-window disturbance to every window.
    life_seed : int
        Number of this life among the lives of one gear and data-set seed, >= 0.
    conditions : ConditionsConfig or None
        What changes while the gear stays healthy: temperature, run-in, payload, a new
        program's dwells, the bridges' drift (:mod:`swgsim.datasets.conditions`); None:
        nothing but the fault.
    """

    hours: float = 1000.0
    interval_min: float = 1.0
    commissioning_h: float = 24.0
    duty: list[DutyPoint] = field(default_factory=list)
    fault: FaultOnset = field(default_factory=FaultOnset)
    severity_levels: int = 8
    disturbed: bool = True
    life_seed: int = 0
    conditions: ConditionsConfig | None = field(default=None, metadata={LATER: "the real day"})

    def check(self, where: str) -> None:
        """Refuse a life config outside its ranges, in one line naming the key (run by
        :func:`swgsim.base.typed.check_tree`, which refuses NaN and infinity first).

        Parameters
        ----------
        where : str
            Full name of the life for messages, e.g. ``dataset.life``.

        Raises
        ------
        ValueError
            A value outside its range, naming the key: ``hours``, ``interval_min`` not
            > 0, too many windows or none, ``commissioning_h`` outside the life or
            holding no window, a duty point outside its range, ``severity_levels`` < 1,
            ``life_seed`` < 0, the fault (unknown, before commissioning, its growth and
            severity), a payload step, re-greasing or duty change outside the life
            (:meth:`~swgsim.datasets.conditions.ConditionsConfig.check_inside`).
        """
        for k in ("hours", "interval_min"):
            v = float(getattr(self, k))
            _req(np.isfinite(v) and v > 0, f"{where}.{k} must be > 0, got {v}")
        n = n_windows(self)
        _req(n <= MAX_WINDOWS, f"{where}.hours={self.hours:g} h at interval_min="
             f"{self.interval_min:g} min is {n:.3g} windows; allowed: at most {MAX_WINDOWS:.0e} "
             f"(up to {MAX_WINDOWS * self.interval_min / 60:.3g} h at this interval)")
        _req(n >= 1, f"{where}.hours={self.hours:g} h holds no window at interval_min="
             f"{self.interval_min:g} min")
        c = float(self.commissioning_h)
        _req(np.isfinite(c) and 0 < c < self.hours, f"{where}.commissioning_h must lie in (0, "
             f"{self.hours:g}) h (a commissioning period known healthy, inside the life), got {c}")
        _req(c * 60.0 / self.interval_min >= 1, f"{where}.commissioning_h={c:g} h holds no window "
             f"at interval_min={self.interval_min:g}")
        for i, d in enumerate(self.duty):
            _req(d.dwell_min > 0, f"{where}.duty[{i}].dwell_min must be > 0, got {d.dwell_min}")
            _req(0 < d.n_in_rpm <= 6500, f"{where}.duty[{i}].n_in_rpm must lie in (0, 6500] rpm, "
                 f"got {d.n_in_rpm}")
            _req(0 <= d.t_out_nm <= 107, f"{where}.duty[{i}].t_out_nm must lie in [0, 107] N m, "
                 f"got {d.t_out_nm}")
        _req(int(self.severity_levels) >= 1, f"{where}.severity_levels must be >= 1, got "
             f"{self.severity_levels}")
        _req(int(self.life_seed) >= 0, f"{where}.life_seed must be >= 0, got {self.life_seed}")
        _check_fault(self.fault, c, f"{where}.fault")
        if self.conditions is not None:
            self.conditions.check_inside(float(self.hours), f"{where}.conditions")


def _req(cond: bool, msg: str) -> None:
    if not cond:
        raise ValueError(msg)


def duty_cycle(life: LifeConfig, n_in_rpm: list[float], t_out_nm: list[float]
               ) -> list[DutyPoint]:
    """The life's duty cycle: ``life.duty`` or every (speed, torque) pair, 10 min each."""
    if life.duty:
        return list(life.duty)
    return [DutyPoint(float(n), float(t)) for n in n_in_rpm for t in t_out_nm]


def _check_fault(f: FaultOnset, commissioning_h: float, key: str) -> None:
    if f.fault == "healthy":
        return
    if is_sensor_fault(f.fault):
        lo, hi = SENSOR_FAULTS[f.fault].severity_range
        _req(f.sensor is None or 0 <= int(f.sensor) <= 4, f"{key}.sensor must lie in "
             f"[0, 4] (bridges s0..s4) or be null, got {f.sensor}")
    else:
        try:
            lo, hi = get_fault(f.fault).severity_range
        except (KeyError, ValueError):
            raise ValueError(f"{key}.fault: unknown fault {f.fault!r}; allowed: healthy, "
                             f"the gear faults and {sorted(SENSOR_FAULTS)}") from None
    _req(f.onset_h >= commissioning_h, f"{key}.onset_h must be >= the commissioning period "
         f"({commissioning_h:g} h), got {f.onset_h}")
    _req(f.growth in GROWTH, f"{key}.growth must be one of {list(GROWTH)}, got {f.growth!r}")
    _req(f.to_failure is None or f.growth in LAWS, f"{key}.to_failure is for growth "
         f"{' or '.join(LAWS)} (a fault that runs to failure), got growth {f.growth!r}")
    sev = ([(f"{key}.points[{i}][1]", p[1]) for i, p in enumerate(f.points)]
           if f.growth == "points" else [(f"{key}.severity", f.severity)])
    for where, s in sev:
        _req(lo <= s <= hi, f"{where}={s}: outside the allowed range [{lo}, {hi}] of "
             f"{f.fault}")
    if f.growth in LAWS:
        check_to_failure(f.to_failure or RunToFailure(), f.fault, f.growth, f.severity, key)
    if f.growth == "linear":
        _req(f.growth_h > 0, f"{key}.growth_h must be > 0 for linear growth, got {f.growth_h}")
    if f.growth == "points":
        hrs = [p[0] for p in f.points]
        _req(len(hrs) >= 1 and all(len(p) == 2 for p in f.points)
             and all(b > a for a, b in zip(hrs, hrs[1:], strict=False))
             and hrs[0] >= f.onset_h, f"{key}.points must be [hour, severity] pairs with "
             f"strictly increasing hours from onset_h ({f.onset_h:g} h) on, got {f.points}")


#: Most windows of one life: 5 million (about 9.5 years at one window a minute); its
#: windows' signals alone are then about 12 GB (float32, 5 bridges, 1200 samples).
MAX_WINDOWS = 5_000_000


def n_windows(life: LifeConfig) -> int:
    """Windows of a life, ``floor(hours · 60 / interval_min)``, computed without building
    anything (:func:`schedule` builds them)."""
    return int(math.floor(float(life.hours) * 60.0 / float(life.interval_min) + 1e-9))


def severity_at(f: FaultOnset, hours: np.ndarray, levels: int) -> np.ndarray:
    """Severity of the fault at each hour, on the staircase of ``levels`` steps.

    The exact schedule is rounded down to the nearest of ``levels`` equal steps of its
    largest value (a step schedule is exact); 0 before the onset. A growth to failure
    depends on the duty, the load and the temperature: :func:`grow`.

    Returns
    -------
    ndarray, shape like ``hours``

    Raises
    ------
    ValueError
        Growth ``paris`` or ``archard``.
    """
    h = np.asarray(hours, float)
    if f.fault == "healthy":
        return np.zeros_like(h)
    _req(f.growth not in LAWS, f"severity_at: growth {f.growth!r} needs the life's duty "
         "(schedule, grow)")
    if f.growth == "step":
        return np.where(h >= f.onset_h, f.severity, 0.0)
    if f.growth == "linear":
        set_in = h >= f.onset_h
        exact = np.clip((h - f.onset_h) / f.growth_h, 0.0, 1.0) * f.severity
        top = f.severity
    else:
        hp = np.array([p[0] for p in f.points], float)
        sp = np.array([p[1] for p in f.points], float)
        set_in = h >= max(hp[0], f.onset_h)
        exact = np.interp(h, hp, sp)
        top = sp[np.argmax(np.abs(sp))]
    return staircase(exact, top, levels, set_in)


def staircase(exact: np.ndarray, top: float, levels: int, set_in: np.ndarray) -> np.ndarray:
    """A growing severity rounded down to the nearest of ``levels`` equal steps of ``top``,
    at least the first step where ``set_in`` (a growing fault is there from its onset), 0
    elsewhere.

    Parameters
    ----------
    exact : ndarray, shape (W,)
        The exact severity [-].
    top : float
        Its largest value (signed) [-].
    levels : int
        Steps, >= 1.
    set_in : ndarray of bool, shape (W,)
        From the onset on.

    Returns
    -------
    ndarray, shape (W,)
    """
    if top == 0:
        return np.zeros_like(exact)
    step = abs(top) / int(levels)
    q = np.floor(np.abs(exact) / step + 1e-9) * step
    q = np.maximum(q, step) * np.sign(np.where(exact != 0, exact, top))
    return np.where(set_in, q, 0.0)


@dataclass(frozen=True)
class Schedule:
    """What each window of a life is: hour, operating point and true state.

    Attributes
    ----------
    hour : ndarray, shape (W,)
        Operating hours since the start of commissioning [h].
    duty_index : ndarray of int, shape (W,)
        Index into ``duty``.
    fault : ndarray of str, shape (W,)
        True class (``healthy`` before the onset).
    severity : ndarray, shape (W,)
        True severity (the staircase's step).
    commissioning : ndarray of bool, shape (W,)
        Inside the commissioning period.
    duty : list of DutyPoint
    failure_h : float
        Operating hour of failure of a fault growing to failure [h]; NaN: none in the life.
    """

    hour: np.ndarray
    duty_index: np.ndarray
    fault: np.ndarray
    severity: np.ndarray
    commissioning: np.ndarray
    duty: list[DutyPoint]
    failure_h: float = float("nan")


def schedule(life: LifeConfig, n_in_rpm: list[float], t_out_nm: list[float]) -> Schedule:
    """The windows of a life (checked config), in time order.

    Window k is taken at ``k · interval_min`` minutes of operation; its operating point is
    the duty point held at that time. From a duty change's hour on
    (``life.conditions.duty_change``) the cycle restarts with its dwells times the change's
    factors. A fault growing to failure grows at the commanded load and 20 °C here
    (:func:`grow` for the life's conditions).

    Raises
    ------
    ValueError
        A duty change's ``dwell_factors`` not one per duty point, in one line naming
        ``life.conditions.duty_change.dwell_factors``.
    """
    duty = duty_cycle(life, n_in_rpm, t_out_nm)
    minutes = np.arange(n_windows(life)) * float(life.interval_min)
    idx = _cycle_index(minutes, [d.dwell_min for d in duty])
    hour = minutes / 60.0
    change = None if life.conditions is None else life.conditions.duty_change
    if change is not None:  # a new program: the cycle restarts at its hour, new dwells
        f = change.factors([d.t_out_nm for d in duty], "life.conditions.duty_change")
        after = hour >= change.hour_h
        since = np.maximum(minutes[after] - 60.0 * float(change.hour_h), 0.0)
        idx[after] = _cycle_index(since, [d.dwell_min * x for d, x in zip(duty, f, strict=True)])
    if life.fault.growth in LAWS and life.fault.fault != "healthy":
        sch = Schedule(hour, idx.astype(np.int64), np.full(hour.shape, "healthy", object),
                       np.zeros_like(hour), hour < life.commissioning_h, duty)
        return grow(sch, life)
    sev = severity_at(life.fault, hour, life.severity_levels)
    fault = np.where(sev != 0, life.fault.fault, "healthy")
    return Schedule(hour, idx.astype(np.int64), fault.astype(object), sev,
                    hour < life.commissioning_h, duty)


def _cycle_index(minutes: np.ndarray, dwell_min: list[float]) -> np.ndarray:
    """The duty point held at each of ``minutes`` of a cycle of ``dwell_min``, from 0."""
    edges = np.cumsum(dwell_min)
    return np.searchsorted(edges, minutes % edges[-1], side="right")


def grow(sch: Schedule, life: LifeConfig, payload: np.ndarray | None = None,
         temp_c: np.ndarray | None = None, scale: float = 1.0) -> Schedule:
    """The schedule with the life's fault grown to failure (growth ``paris`` or
    ``archard``, :func:`swgsim.datasets.growth.grown_severity`) on the staircase of
    ``severity_levels`` steps of the failure severity.

    Parameters
    ----------
    sch : Schedule
    life : LifeConfig
        Checked, its fault growing by a law.
    payload, temp_c : ndarray, shape (W,), optional
        Each window's factor on the load [-] (default 1) and the joint's temperature [°C]
        (default 20, :data:`swgsim.gear.thermal.REF_TEMP_C`).
    scale : float
        The gear's factor on the law's coefficient (scatter) [-].

    Returns
    -------
    Schedule
        ``severity``, ``fault`` and ``failure_h`` (the exact law's) replaced.
    """
    f = life.fault
    law = f.to_failure or RunToFailure()
    n = np.array([d.n_in_rpm for d in sch.duty])[sch.duty_index]
    t = np.array([d.t_out_nm for d in sch.duty])[sch.duty_index]
    t = t if payload is None else t * payload
    temp = np.full(sch.hour.shape, REF_TEMP_C) if temp_c is None else temp_c
    exact = grown_severity(f.fault, f.growth, law, f.onset_h, f.severity, sch.hour,
                           life.interval_min, n, t, temp, scale)
    fail = law.failure_severity(f.fault)
    sev = staircase(exact, fail, life.severity_levels, sch.hour >= f.onset_h)
    fault = np.where(sev != 0, f.fault, "healthy").astype(object)
    return dataclasses.replace(sch, severity=sev, fault=fault,
                               failure_h=failure_hour(sch.hour, exact, fail))


def uses_position(name: str) -> bool:
    """Whether a fault class has a circumferential position (False for sensor faults)."""
    if name == "healthy" or is_sensor_fault(name):
        return False
    return bool(get_fault(name).uses_position)
