"""Gear lives: one gear's operation as a time-ordered stream of windows.

A life runs a duty cycle over operating points (each held for its dwell time, in turn)
and records one window every ``interval_min`` of operation. It starts with a
commissioning period known to be healthy; then, optionally, a fault of any class (a gear
fault of :data:`swgsim.faults.FAULTS` or a sensor fault of
:data:`swgsim.sensor_faults.SENSOR_FAULTS`) sets in at ``onset_h`` and follows a severity
schedule: a step, linear growth to a final severity, or (hour, severity) pairs.

How windows are made. A gear in a steady state at one operating point repeats its signals
once per output revolution (the WG angle and the flexspline both return; N input
revolutions, 3 s at 2000 rpm). Each (operating point, state) is therefore simulated
once, as one *record* of one output revolution plus a window (:class:`LifeSimulator`):
the dynamics (:func:`swgsim.dynamics.simulate`), the gauge signals and the measurement
chain up to the converter's filter, exactly as a data set's windows
(:mod:`swgsim.shard`). A window is cut from its record at a random start, and gets its
own eq. (10) draws (if ``disturbed``), its sensor fault and the converter's noise and
quantisation. A growing severity is simulated as a staircase of ``severity_levels`` steps
(the window's ``severity`` is the step's, i.e. what its signals hold).

Randomness: the fault's position (gear faults) or bridge (sensor faults) from
``SeedSequence(seed, spawn_key=(gear, life_seed, 0))``; window k from its own stream,
``spawn_key=(gear, life_seed, 1 + k)`` (its start, eq. (10), noise), so a life is the same
whatever slice of it is asked for, and any slice costs only its windows.
"""

from __future__ import annotations

import dataclasses
import math
from dataclasses import dataclass, field

import numpy as np

from . import dynamics
from .acquisition import digitise, sample
from .chain import SimulationChain
from .disturbance import disturb
from .faults import ChainParams, apply_fault, get_fault
from .measurement import apply_sensor_effects
from .sensor_faults import SENSOR_FAULTS, apply_sensor_fault, is_sensor_fault

#: Windows made at once (memory).
BLOCK = 1024
GROWTH = ("step", "linear", "points")


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
        Final severity (``step``, ``linear``).
    growth : {"step", "linear", "points"}
        ``step``: ``severity`` from the onset on; ``linear``: from 0 at the onset to
        ``severity`` ``growth_h`` hours later, then constant; ``points``: linear between
        the (hour, severity) pairs of ``points``, 0 before the first.
    growth_h : float
        Hours of linear growth, > 0 for ``linear``.
    points : list of [hour, severity]
        Increasing hours, for ``points``.
    position_deg : float or None
        Circumferential position of a gear fault on the flexspline [deg]; None draws it
        uniformly from the life's seed.
    sensor : int or None
        Faulty bridge of a sensor fault (0..4); None draws it from the life's seed.
    """

    fault: str = "healthy"
    onset_h: float = 0.0
    severity: float = 0.0
    growth: str = "step"
    growth_h: float = 0.0
    points: list[list[float]] = field(default_factory=list)
    position_deg: float | None = None
    sensor: int | None = None


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
        The first hours, known healthy: the monitor's baseline. The default, 24 h (1,440
        windows, 240 per operating point of the paper's six), is above the minimum of the
        monitor's default design (one false alarm per 1000 h; ``learn.monitor``).
    duty : list of DutyPoint
        The duty cycle; empty: the data set's operating points, 10 min each.
    fault : FaultOnset
    severity_levels : int
        Steps of the staircase that simulates a growing severity, >= 1.
    disturbed : bool
        Add eq. (10)'s per-window disturbance to every window.
    life_seed : int
        Number of this life among the lives of one gear and data-set seed, >= 0.
    """

    hours: float = 1000.0
    interval_min: float = 1.0
    commissioning_h: float = 24.0
    duty: list[DutyPoint] = field(default_factory=list)
    fault: FaultOnset = field(default_factory=FaultOnset)
    severity_levels: int = 8
    disturbed: bool = True
    life_seed: int = 0


def _req(cond: bool, msg: str) -> None:
    if not cond:
        raise ValueError(msg)


def duty_cycle(life: LifeConfig, n_in_rpm: list[float], t_out_nm: list[float]
               ) -> list[DutyPoint]:
    """The life's duty cycle: ``life.duty`` or every (speed, torque) pair, 10 min each."""
    if life.duty:
        return list(life.duty)
    return [DutyPoint(float(n), float(t)) for n in n_in_rpm for t in t_out_nm]


def check_life(life: LifeConfig, key: str = "dataset.life") -> None:
    """Refuse a life config outside its ranges, in one line naming the key.

    Parameters
    ----------
    life : LifeConfig
    key : str
        Full name of ``life`` for messages.

    Raises
    ------
    ValueError
        NaN or infinity in any float (checked first, :func:`swgsim.config.check_finite`),
        or a value outside its range, naming the key.
    """
    from .config import check_finite  # swgsim.config imports this module

    check_finite(life, key)
    for k in ("hours", "interval_min"):
        v = float(getattr(life, k))
        _req(np.isfinite(v) and v > 0, f"{key}.{k} must be > 0, got {v}")
    c = float(life.commissioning_h)
    _req(np.isfinite(c) and 0 < c < life.hours, f"{key}.commissioning_h must lie in (0, "
         f"{life.hours:g}) h (a commissioning period known healthy, inside the life), got {c}")
    _req(c * 60.0 / life.interval_min >= 1, f"{key}.commissioning_h={c:g} h holds no window "
         f"at interval_min={life.interval_min:g}")
    for i, d in enumerate(life.duty):
        _req(d.dwell_min > 0, f"{key}.duty[{i}].dwell_min must be > 0, got {d.dwell_min}")
        _req(0 < d.n_in_rpm <= 6500, f"{key}.duty[{i}].n_in_rpm must lie in (0, 6500] rpm, "
             f"got {d.n_in_rpm}")
        _req(0 <= d.t_out_nm <= 107, f"{key}.duty[{i}].t_out_nm must lie in [0, 107] N m, "
             f"got {d.t_out_nm}")
    _req(int(life.severity_levels) >= 1, f"{key}.severity_levels must be >= 1, got "
         f"{life.severity_levels}")
    _req(int(life.life_seed) >= 0, f"{key}.life_seed must be >= 0, got {life.life_seed}")
    _check_fault(life.fault, c, f"{key}.fault")


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
    sev = [p[1] for p in f.points] if f.growth == "points" else [f.severity]
    for s in sev:
        _req(lo <= s <= hi, f"{key}: severity {s} outside the allowed range [{lo}, {hi}] of "
             f"{f.fault}")
    if f.growth == "linear":
        _req(f.growth_h > 0, f"{key}.growth_h must be > 0 for linear growth, got {f.growth_h}")
    if f.growth == "points":
        hrs = [p[0] for p in f.points]
        _req(len(hrs) >= 1 and all(len(p) == 2 for p in f.points)
             and all(b > a for a, b in zip(hrs, hrs[1:], strict=False))
             and hrs[0] >= f.onset_h, f"{key}.points must be [hour, severity] pairs with "
             f"increasing hours from onset_h on, got {f.points}")


def severity_at(f: FaultOnset, hours: np.ndarray, levels: int) -> np.ndarray:
    """Severity of the fault at each hour, on the staircase of ``levels`` steps.

    The exact schedule is rounded down to the nearest of ``levels`` equal steps of its
    largest value (a step schedule is exact); 0 before the onset.

    Returns
    -------
    ndarray, shape like ``hours``
    """
    h = np.asarray(hours, float)
    if f.fault == "healthy":
        return np.zeros_like(h)
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
    if top == 0:
        return np.zeros_like(h)
    step = abs(top) / int(levels)
    q = np.floor(np.abs(exact) / step + 1e-9) * step
    # a growing fault is there from its onset: its first step is taken at once
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
    """

    hour: np.ndarray
    duty_index: np.ndarray
    fault: np.ndarray
    severity: np.ndarray
    commissioning: np.ndarray
    duty: list[DutyPoint]


def schedule(life: LifeConfig, n_in_rpm: list[float], t_out_nm: list[float]) -> Schedule:
    """The windows of a life (checked config), in time order.

    Window k is taken at ``k · interval_min`` minutes of operation; its operating point is
    the duty point held at that time.
    """
    duty = duty_cycle(life, n_in_rpm, t_out_nm)
    n_w = int(math.floor(life.hours * 60.0 / life.interval_min + 1e-9))
    minutes = np.arange(n_w) * float(life.interval_min)
    edges = np.cumsum([d.dwell_min for d in duty])
    idx = np.searchsorted(edges, minutes % edges[-1], side="right")
    hour = minutes / 60.0
    sev = severity_at(life.fault, hour, life.severity_levels)
    fault = np.where(sev != 0, life.fault.fault, "healthy")
    return Schedule(hour, idx.astype(np.int64), fault.astype(object), sev,
                    hour < life.commissioning_h, duty)


__all__ = ["BLOCK", "DutyPoint", "FaultOnset", "LifeConfig", "Schedule", "check_life",
           "duty_cycle", "schedule", "severity_at", "LifeSimulator", "RecordBank",
           "life_dataset", "simulate_life_shard"]


class RecordBank:
    """Records of one gear: one output revolution plus a window per (duty point, state).

    States are asked for first (:meth:`want`) and simulated together at the first
    :meth:`get` (:meth:`simulate`): the RK4 integration costs nearly the same per step
    for one variant as for a hundred, so every record of a speed is one batch.

    Parameters
    ----------
    plan : DatasetPlan
        The checked data set.
    gear_id : int
    chunk : int
        Variants per batch (bounds the memory of the dynamics and gauge signals).
    """

    def __init__(self, plan, gear_id: int, chunk: int = 96) -> None:
        from .plan import gear_params

        self.plan, self.gear_id, self.chunk = plan, int(gear_id), int(chunk)
        self.healthy = gear_params(plan.config, plan.gear(self.gear_id))
        self._pending: set[tuple] = set()
        self._records: dict[tuple, dict] = {}
        self._influences: dict = {}

    @staticmethod
    def key(dp: DutyPoint, fault: str, severity: float, position_deg: float) -> tuple:
        """The key of a record: (speed, torque, gear fault, severity, position)."""
        if fault == "healthy" or is_sensor_fault(fault) or severity == 0:
            return (float(dp.n_in_rpm), float(dp.t_out_nm), "healthy", 0.0, 0.0)
        pos = float(position_deg) if _uses_position(fault) else 0.0
        return (float(dp.n_in_rpm), float(dp.t_out_nm), fault, float(severity), pos)

    def params(self, key: tuple) -> ChainParams:
        """Chain parameters of the gear in the state of a key."""
        _, _, fault, sev, pos = key
        return self.healthy if fault == "healthy" else apply_fault(self.healthy, fault, sev,
                                                                    pos)

    def want(self, keys) -> None:
        """Ask for records, simulated at the next :meth:`get`."""
        self._pending |= {k for k in keys if k not in self._records}

    def get(self, key: tuple) -> dict[str, np.ndarray]:
        """A record: ``signal`` (5, n_rec) [mV/V] sampled as the bench's converter does
        (before its noise), ``n_period`` (samples of one output revolution) and the
        cumulative sums ``p_in``, ``p_out`` [W], ``w_in`` [rad/s], ``t_out`` [N m] over its
        samples, shape (n_rec + 1,)."""
        if key not in self._records:
            self.want([key])
            self.simulate()
        return self._records[key]

    def simulate(self) -> None:
        """Simulate every pending record, in batches per input speed."""
        pending, self._pending = sorted(self._pending), set()
        for n in sorted({k[0] for k in pending}):
            group = [k for k in pending if k[0] == n]
            for c in range(0, len(group), self.chunk):
                self._simulate(group[c:c + self.chunk])

    def _chain(self, params: list[ChainParams]) -> SimulationChain:
        from .plan import layout_for
        from .shard import influences_for

        keys = {p.root_crack_key() for p in params} - {None} - set(self._influences)
        if keys or not self._influences:
            self._influences.update(influences_for(self.plan, [self.gear_id], keys)[self.gear_id])
        cfg = self.plan.config
        return SimulationChain.from_influences(layout_for(cfg, self.plan.gear(self.gear_id)),
                                               self._influences, cfg.chain)

    def _simulate(self, keys: list[tuple]) -> None:
        from .shard import fine_motion

        cfg = self.plan.config
        ch, amp = cfg.chain, cfg.acquisition.amplifier
        fs, n_in = ch.sample_rate_hz, keys[0][0]
        q = 1 if amp is None else amp.oversample
        n_lead = 0 if amp is None else amp.lead_samples(fs)
        n_t = int(round(ch.window_s * fs))
        n_period = int(math.ceil(self.healthy.gear.ratio * 60.0 / n_in * fs))
        n_rec = n_period + n_t
        params = [self.params(k) for k in keys]
        n_sim = n_rec + 2 * n_lead + (q > 1)
        res = dynamics.simulate([p.gear for p in params], n_in, np.array([k[1] for k in keys]),
                                0.0, fs, n_sim / fs, ch.settle_s - n_lead / fs, ch.substeps,
                                friction_effects=self.plan.friction)
        if not res.success:
            from .shard import diverged

            raise ValueError(diverged(self.plan, f"gear {self.gear_id}'s life at {n_in:g} rpm",
                                      res.message))
        chain = self._chain(params)
        win = slice(n_lead, n_lead + n_rec)
        for c in range(0, len(keys), 16):  # gauge signals in small groups (memory)
            rows = np.arange(c, min(c + 16, len(keys)))
            psi, t_act = fine_motion(res, q, rows)
            sig = chain.signals_batch([params[r] for r in rows], psi, t_act)
            if self.plan.sensor_effects:
                t_fine = np.arange(sig.shape[-1]) / (fs * q)
                sig = apply_sensor_effects(sig, t_fine, np.full(rows.size, n_in),
                                           self.plan.sensor_effects,
                                           t_start_s=np.full(rows.size, -n_lead / fs))
            sig = sample(sig, amp, n_lead) if amp is not None else sig[:, :, :n_rec]
            for i, r in enumerate(rows):
                cum = {k: np.concatenate([[0.0], np.cumsum(v[r, win])])
                       for k, v in (("p_in", res.p_in), ("p_out", res.p_out),
                                    ("w_in", res.states[1]), ("t_out", res.t_out))}
                self._records[keys[r]] = {"signal": sig[i, :, :n_rec].astype(np.float32),
                                          "n_period": n_period, **cum}


class LifeSimulator:
    """Makes the windows of one gear's life from its records (module docstring).

    Parameters
    ----------
    plan : DatasetPlan
        The checked data set: chain, gear, recording, disturbance, sensor effects.
    gear_id : int
    life : LifeConfig
        Checked (:func:`check_life`).
    bank : RecordBank, optional
        The gear's records, shared with other lives of it; a new one when not given. The
        life's records are asked for at once, and simulated at the first window.
    """

    def __init__(self, plan, gear_id: int, life: LifeConfig,
                 bank: RecordBank | None = None) -> None:
        self.plan, self.life, self.gear_id = plan, life, int(gear_id)
        cfg = plan.config
        ops = cfg.operating_points
        from .life_profile import record_bank

        self.bank = record_bank(plan, self.gear_id) if bank is None else bank
        slots = getattr(self.bank, "slots", None)  # a profile: one duty point per slot
        self.schedule = schedule(life if slots is None else dataclasses.replace(
            life, duty=slots.duty(life.interval_min)), list(ops.n_in_rpm), list(ops.t_out_nm))
        ss = np.random.SeedSequence(int(cfg.seed), spawn_key=(self.gear_id, int(life.life_seed), 0))
        u = np.random.default_rng(ss).uniform(size=2)
        f = life.fault
        self.position_deg = float(360.0 * u[0] if f.position_deg is None else f.position_deg)
        self.sensor = int(5 * u[1]) if f.sensor is None else int(f.sensor)
        self.bank.want(self._key(d, s) for d, s in
                       {(int(d), float(s)) for d, s in zip(self.schedule.duty_index,
                                                           self.schedule.severity,
                                                           strict=True)})

    def _key(self, d: int, severity: float) -> tuple:
        return RecordBank.key(self.schedule.duty[d], self.life.fault.fault, severity,
                              self.position_deg)

    # ------------------------------------------------------------------ windows
    def windows(self, start: int, stop: int) -> tuple[np.ndarray, dict[str, np.ndarray]]:
        """Windows ``start:stop`` of the life.

        Returns
        -------
        signals : ndarray, float32, shape (stop − start, 5, n_t)
            Bridge outputs [mV/V].
        meta : dict of ndarray, shape (stop − start,)
            The schema's per-sample variables plus ``hour`` and ``commissioning``.
        """
        out_s, out_m = [], []
        for a in range(start, stop, BLOCK):  # in blocks: bounded memory
            s, m = self._rows(np.arange(a, min(a + BLOCK, stop)))
            out_s.append(s)
            out_m.append(m)
        meta = {k: np.concatenate([m[k] for m in out_m]) for k in out_m[0]}
        return np.concatenate(out_s), meta

    def __len__(self) -> int:
        return self.schedule.hour.size

    def _rows(self, rows: np.ndarray):
        cfg = self.plan.config
        ch, amp = cfg.chain, cfg.acquisition.amplifier
        fs = ch.sample_rate_hz
        n_t = int(round(ch.window_s * fs))
        time_s = np.arange(n_t) / fs
        sch = self.schedule
        sig = np.empty((rows.size, 5, n_t))
        eff, n_mean, t_mean = (np.empty(rows.size) for _ in range(3))
        rngs = [np.random.default_rng(np.random.SeedSequence(
            int(cfg.seed), spawn_key=(self.gear_id, int(self.life.life_seed), 1 + int(r))))
            for r in rows]
        slots = getattr(self.bank, "slots", None)
        angles: dict[str, np.ndarray] = {}
        for i, r in enumerate(rows):
            d = int(sch.duty_index[r])
            rec = self.bank.get(self._key(d, float(sch.severity[r])))
            if slots is not None:  # a profile: slot d, started within its jitter
                rec = {k: v[d] for k, v in rec.items()}
                o = int(rngs[i].uniform() * (rec["signal"].shape[-1] - n_t + 1))
                for k in ("phi_in", "phi_in_meas", "phi_out_meas"):
                    if k in rec:
                        angles.setdefault(k, np.empty((rows.size, n_t)))[i] = rec[k][o:o + n_t]
            else:
                o = int(rngs[i].uniform() * rec["n_period"])
            sig[i] = rec["signal"][:, o:o + n_t]
            e = o + n_t
            eff[i] = (rec["p_out"][e] - rec["p_out"][o]) / (rec["p_in"][e] - rec["p_in"][o])
            n_mean[i] = (rec["w_in"][e] - rec["w_in"][o]) / n_t * 60 / (2 * np.pi)
            t_mean[i] = (rec["t_out"][e] - rec["t_out"][o]) / n_t
        phi_in = angles.pop("phi_in", None)
        fault = sch.fault[rows]
        if is_sensor_fault(self.life.fault.fault):
            on = fault != "healthy"
            if on.any():
                sig[on] = apply_sensor_fault(sig[on], self.life.fault.fault,
                                             sch.severity[rows][on], self.sensor)
        for i in range(rows.size):  # each window from its own stream
            if self.life.disturbed:
                sig[i:i + 1] = disturb(sig[i:i + 1], time_s, n_mean[i:i + 1], cfg.disturbance,
                                       rngs[i], None if phi_in is None else phi_in[i:i + 1])
            if amp is not None:
                sig[i:i + 1] = digitise(sig[i:i + 1], amp, rngs[i])
        duty = [sch.duty[int(d)] for d in sch.duty_index[rows]]
        gear_fault = (fault != "healthy") & _uses_position(self.life.fault.fault)
        meta = {
            "gear": np.full(rows.size, self.gear_id),
            "fault": fault.astype(str),
            "variant": np.zeros(rows.size, np.int64),
            "severity": sch.severity[rows],
            "position_deg": np.where(gear_fault,
                                     self.position_deg, np.nan),
            "n_in_rpm": np.array([d.n_in_rpm for d in duty]),
            "t_out_nm": np.array([d.t_out_nm for d in duty]),
            "disturbed": np.full(rows.size, bool(self.life.disturbed)),
            "reference": np.zeros(rows.size, bool),
            "efficiency": eff,
            "n_in_mean_rpm": n_mean,
            "t_out_mean_nm": t_mean,
            "hour": sch.hour[rows],
            "commissioning": sch.commissioning[rows],
            **angles,  # a profile's angle channels, (n, n_t) [rad]
        }
        return sig.astype(np.float32), meta


def _uses_position(name: str) -> bool:
    """Whether a fault class has a circumferential position (False for sensor faults)."""
    if name == "healthy" or is_sensor_fault(name):
        return False
    return bool(get_fault(name).uses_position)


def life_dataset(sim: LifeSimulator, start: int = 0, stop: int | None = None):
    """Windows ``start:stop`` of a life as a schema-v1 ``xarray.Dataset``, with the per-sample
    variables ``hour`` [h] and ``commissioning`` (bool) and the life in the attributes."""
    from . import data as dsio

    stop = len(sim) if stop is None else stop
    sig, meta = sim.windows(start, stop)
    extra = {k: meta.pop(k) for k in ("hour", "commissioning")}
    angles = {k: meta.pop(k) for k in [k for k, v in meta.items() if v.ndim == 2]}
    cfg = sim.plan.config
    n_t = sig.shape[-1]
    attrs = {"config": sim.plan.as_dict(), "seed": int(cfg.seed),
             "life": dataclasses.asdict(sim.life), "gear_id": sim.gear_id,
             "fault_position_deg": sim.position_deg, "fault_sensor": sim.sensor}
    ds = dsio.make_dataset(sig, np.arange(n_t) / cfg.chain.sample_rate_hz, meta, attrs)
    ds["hour"] = ("sample", extra["hour"], {"units": "h"})
    ds["commissioning"] = ("sample", extra["commissioning"])
    for k, v in angles.items():  # a profile's angle channels
        ds[k] = (("sample", "time"), v, {"units": "rad"})
    return ds


def simulate_life_shard(plan, shard):
    """One gear's life as a data-set shard (``dataset.life``); returns (Dataset, n).

    The shard's attributes are those of a grid shard (config, seed, ``content_sha256`` of
    the float32 signals and the sorted per-sample variables, provenance) plus ``life``,
    ``fault_position_deg`` and ``fault_sensor``.
    """
    import hashlib

    from .outdir import git_revision, package_version

    sim = LifeSimulator(plan, shard.gear, plan.config.life)
    ds = life_dataset(sim)
    h = hashlib.sha256(ds["strain_signal"].values.tobytes())
    for k in sorted(v for v in ds.data_vars if v != "strain_signal"):
        v = ds[k].values
        h.update(np.ascontiguousarray(v.astype(str) if v.dtype.kind in "OU" else v).tobytes())
    ds.attrs.update({"shard": shard.name, "content_sha256": h.hexdigest(),
                     "package_version": package_version(), "git_revision": git_revision()})
    return ds, len(sim)
