"""Gear lives: one gear's operation as a time-ordered stream of windows.

The schedule (duty cycle, commissioning, fault onset and severity) is
:mod:`swgsim.datasets.schedule`. Each (operating point, state) is simulated once, as one
*record* (:mod:`swgsim.datasets.records`, through :class:`LifeSimulator`); a window is cut
from its record at a random start, and gets its own eq. (10) draws (if ``disturbed``), its
sensor fault and the converter's noise and quantisation. A growing severity is simulated
as a staircase of ``severity_levels`` steps (the window's ``severity`` is the step's, i.e.
what its signals hold).

Randomness: the fault's position (gear faults) or bridge (sensor faults) from
``SeedSequence(seed, spawn_key=(gear, life_seed, 0))``; window k from its own stream,
``spawn_key=(gear, life_seed, 1 + k)`` (its start, eq. (10), noise), so a life is the same
whatever slice of it is asked for, and any slice costs only its windows; a fault growing
to failure, its gear's scatter from ``spawn_key=(gear, life_seed, 2**23)``.
"""

from __future__ import annotations

import dataclasses

import numpy as np

from swgsim.datasets.conditions import WindowConditions, efficiency_ratio, window_conditions
from swgsim.datasets.config import layout_for
from swgsim.datasets.growth import LAWS, RunToFailure, draw_scale
from swgsim.datasets.plan import DatasetPlan, ShardSpec
from swgsim.datasets.recording_table import content_hash
from swgsim.datasets.records import RecordBank, record_bank
from swgsim.datasets.schedule import LifeConfig, Schedule, grow, schedule, uses_position
from swgsim.datasets.schema import make_dataset
from swgsim.files.provenance import git_revision, package_version
from swgsim.gear.influence import Influence
from swgsim.sensing.acquisition import quantise
from swgsim.sensing.disturbance import apply_disturbance, draw_disturbance
from swgsim.sensing.sensor_faults import apply_sensor_fault, is_sensor_fault

#: Windows made at once (memory).
BLOCK = 1024
#: Factors on the viscous friction at which a life whose friction acts in the dynamics
#: (``conditions.viscous_in_dynamics``) is simulated, 2^(1/4) apart: each window's signals
#: are the quadratic through the three nearest (Lagrange in the factor). Measured on the
#: tiny bench's gear 3 at 4000 rpm, interpolating to 0.627 (the grease's factor at 40 °C):
#: RMS error 0.9 % of the signals' change from the nominal gear at 7 N m, 0.04 % at 70 N m
#: (rungs √2 apart: 5.0 % and 0.28 %) [derived]. From 1/256: the benchmark's families
#: thin a hot joint's grease to 0.03 of its 20 °C viscosity (bench, family ``all``,
#: design seeds), 1/32 was too short.
VISCOUS_LADDER = tuple(2.0 ** (k / 4) for k in range(-32, 9))  # 1/256 ... 4

__all__ = ["BLOCK", "VISCOUS_LADDER", "LifeSimulator", "ladder_weights", "life_dataset",
           "simulate_life_shard"]


def ladder_weights(factor: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """The three rungs of :data:`VISCOUS_LADDER` nearest each factor and their quadratic
    (Lagrange) weights, which sum to 1; a factor on a rung weighs it 1 exactly.

    Parameters
    ----------
    factor : ndarray, shape (W,)
        Factors on the viscous friction, within the ladder's span [-].

    Returns
    -------
    rungs : ndarray of float, shape (W, 3)
    weights : ndarray, shape (W, 3)

    Raises
    ------
    ValueError
        A factor outside the ladder's span (1/256 to 4), naming the first.
    """
    f = np.asarray(factor, dtype=float)
    lad = np.asarray(VISCOUS_LADDER)
    bad = np.flatnonzero(~((f >= lad[0]) & (f <= lad[-1])))
    if bad.size:
        raise ValueError(f"conditions.viscous_in_dynamics: a viscous friction factor of "
                         f"{f[bad[0]]:g} lies outside [{lad[0]:g}, {lad[-1]:g}] (the "
                         f"ladder of simulated factors)")
    k0 = int(round(-4.0 * np.log2(lad[0])))  # the lowest rung's -k
    j = np.clip(np.rint(4.0 * np.log2(f)).astype(int) + k0, 1, lad.size - 2)  # middle rung
    rungs = lad[np.stack([j - 1, j, j + 1], axis=1)]  # (W, 3)
    w = np.ones_like(rungs)
    for a in range(3):
        for b in range(3):
            if a != b:
                w[:, a] *= (f - rungs[:, b]) / (rungs[:, a] - rungs[:, b])
    on = np.isclose(rungs, f[:, None], rtol=0, atol=1e-12)
    w = np.where(on.any(axis=1, keepdims=True), on.astype(float), w)
    return rungs, w


class LifeSimulator:
    """Makes the windows of one gear's life from its records (module docstring).

    Parameters
    ----------
    plan : DatasetPlan
        The checked data set: chain, gear, acquisition, disturbance, sensor effects.
    gear_id : int
    life : LifeConfig
        Checked (:meth:`LifeConfig.check <swgsim.datasets.schedule.LifeConfig.check>`, by
        :func:`swgsim.base.typed.check_tree`).
    bank : RecordBank, optional
        The gear's records, shared with other lives of it; a new one when not given. The
        life's records are asked for at once, and simulated at the first window.
    """

    def __init__(self, plan: DatasetPlan, gear_id: int, life: LifeConfig,
                 bank: RecordBank | None = None) -> None:
        self.plan, self.life, self.gear_id = plan, life, int(gear_id)
        cfg = plan.config
        ops = cfg.operating_points
        self.bank = record_bank(plan, self.gear_id) if bank is None else bank
        # the bridges' zero offsets in the records' signals (the span drift leaves them)
        self.zero_offsets_mvv = layout_for(cfg, plan.gears[self.gear_id]).zero_offsets_mvv
        slots = getattr(self.bank, "slots", None)  # a profile: one duty point per slot
        self.schedule = schedule(life if slots is None else dataclasses.replace(
            life, duty=slots.duty(life.interval_min)), list(ops.n_in_rpm), list(ops.t_out_nm))
        ss = np.random.SeedSequence(int(cfg.seed), spawn_key=(self.gear_id, int(life.life_seed), 0))
        u = np.random.default_rng(ss).uniform(size=2)
        f = life.fault
        self.position_deg = float(360.0 * u[0] if f.position_deg is None else f.position_deg)
        self.sensor = int(5 * u[1]) if f.sensor is None else int(f.sensor)
        self.conditions = None if life.conditions is None else self._conditions(life)
        if f.growth in LAWS and f.fault != "healthy":  # grown by the life's load and heat
            self.schedule = self._grow(life)
        self.rungs = self.rung_weights = None
        if life.conditions is not None and life.conditions.viscous_in_dynamics:
            self.rungs, self.rung_weights = ladder_weights(self.conditions.friction)
        self._ask()

    def _ask(self) -> None:
        """Ask the bank for the records of every state the life passes through."""
        lam = (np.ones(len(self.schedule.hour)) if self.conditions is None
               else self.conditions.payload)
        states = {(int(d), float(s), float(x)) for d, s, x in zip(
            self.schedule.duty_index, self.schedule.severity, lam, strict=True)}
        if self.rungs is not None:
            used = sorted({float(r) for r in self.rungs[self.rung_weights != 0]})
            self.bank.want(self._key(d, s, x, v) for d, s, x in states for v in used)
        else:
            self.bank.want(self._key(d, s, x) for d, s, x in states)

    def to_bank(self, bank: RecordBank) -> LifeSimulator:
        """This life with its records from ``bank`` (another bank of the same gear,
        shared with its other lives), asked for there; returns itself.

        Raises
        ------
        ValueError
            If ``bank`` is of another gear or plan.
        """
        if bank.gear_id != self.gear_id or bank.plan is not self.plan:
            raise ValueError(f"LifeSimulator.to_bank: a bank of gear {bank.gear_id} for a life "
                             f"of gear {self.gear_id} (or of another plan)")
        self.bank = bank
        self._ask()
        return self

    def _conditions(self, life: LifeConfig) -> WindowConditions:
        """The life's conditions per window
        (:func:`swgsim.datasets.conditions.window_conditions`).

        Raises
        ------
        ValueError
            Payload changes on a profile.
        """
        if life.conditions.payload and getattr(self.bank, "slots", None) is not None:
            raise ValueError("dataset.life.conditions.payload: payload changes are for lives "
                             "at steady operating points; on a profile, set the link's "
                             "dataset.profile.load.gravity.payload_kg")
        sch = self.schedule
        duty = [sch.duty[int(d)] for d in sch.duty_index]
        return window_conditions(life.conditions, sch.hour,
                                 np.array([d.n_in_rpm for d in duty]),
                                 np.array([d.t_out_nm for d in duty]), self.bank.healthy,
                                 int(self.plan.config.seed), self.gear_id, int(life.life_seed))

    def _grow(self, life: LifeConfig) -> Schedule:
        """The schedule with the fault grown to failure under the life's conditions (payload,
        temperature) and this gear's scatter (:mod:`swgsim.datasets.growth`), drawn from
        ``SeedSequence(seed, spawn_key=(gear, life_seed, 2**23))``."""
        ss = np.random.SeedSequence(int(self.plan.config.seed),
                                    spawn_key=(self.gear_id, int(life.life_seed), 2**23))
        scale = draw_scale(life.fault.to_failure or RunToFailure(), np.random.default_rng(ss))
        c = self.conditions
        return grow(self.schedule, life, None if c is None else c.payload,
                    None if c is None else c.temperature_c, scale)

    def failure_h_by(self, to_failure: RunToFailure) -> float:
        """The hour this life's fault would fail by another law [h], under the same
        windows, conditions and gear scatter; NaN where it would not within the life.
        Only the schedule is grown again (:func:`~swgsim.datasets.schedule.grow`): no
        window is simulated, no record asked for."""
        fault = dataclasses.replace(self.life.fault, to_failure=to_failure)
        return float(self._grow(dataclasses.replace(self.life, fault=fault)).failure_h)

    def _key(self, d: int, severity: float, payload: float = 1.0,
             viscous: float = 1.0) -> tuple:
        """The record of duty point ``d`` in a state, at the acting load (the commanded
        one times ``payload``) and with b1, b2 times ``viscous``."""
        dp = self.schedule.duty[d]
        if payload != 1.0:
            dp = dataclasses.replace(dp, t_out_nm=dp.t_out_nm * payload)
        return RecordBank.key(dp, self.life.fault.fault, severity, self.position_deg,
                              viscous)

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

    def _rows(self, rows: np.ndarray) -> tuple[np.ndarray, dict[str, np.ndarray]]:
        """Windows ``rows`` (a block): cut from their records, under the life's
        conditions, through the measurement chain, with their metadata."""
        cfg = self.plan.config
        rngs = [np.random.default_rng(np.random.SeedSequence(
            int(cfg.seed), spawn_key=(self.gear_id, int(self.life.life_seed), 1 + int(r))))
            for r in rows]
        sig, keys, eff, n_mean, t_mean, angles = self._cut(rows, rngs)
        if self.conditions is not None:
            self._condition(rows, keys, sig, eff)
        phi_in = angles.pop("phi_in", None)
        fault = self.schedule.fault[rows]
        if is_sensor_fault(self.life.fault.fault):
            on = fault != "healthy"
            if on.any():
                sig[on] = apply_sensor_fault(sig[on], self.life.fault.fault,
                                             self.schedule.severity[rows][on], self.sensor,
                                             self.zero_offsets_mvv[self.sensor])
        self._record(sig, n_mean, rngs, phi_in)
        meta = self._meta(rows, fault, eff, n_mean, t_mean)
        return sig.astype(np.float32), {**meta, **angles}

    def _cut(self, rows: np.ndarray, rngs: list[np.random.Generator]):
        """Each window cut from its record at its start (drawn from its stream): signals
        (n, 5, n_t) [mV/V], record keys, efficiency, mean speed [rpm] and torque [N m],
        and a profile's angle channels (n, n_t) [rad]."""
        fs = self.plan.config.chain.sample_rate_hz
        n_t = int(round(self.plan.config.chain.window_s * fs))
        sch = self.schedule
        sig = np.empty((rows.size, 5, n_t))
        eff, n_mean, t_mean = (np.empty(rows.size) for _ in range(3))
        slots = getattr(self.bank, "slots", None)
        angles: dict[str, np.ndarray] = {}
        keys = []
        for i, r in enumerate(rows):
            d = int(sch.duty_index[r])
            lam = 1.0 if self.conditions is None else float(self.conditions.payload[r])
            keys.append(self._key(d, float(sch.severity[r]), lam))
            recs = self._records(r, keys[-1], d, lam)
            if slots is not None:  # a profile: slot d, started within its jitter
                recs = [({k: v[d] for k, v in rc.items()}, w) for rc, w in recs]
                o = int(rngs[i].uniform() * (recs[0][0]["signal"].shape[-1] - n_t + 1))
                for k in ("phi_in", "phi_in_meas", "phi_out_meas"):
                    if k in recs[0][0]:
                        angles.setdefault(k, np.empty((rows.size, n_t)))[i] = _mix(
                            recs, k, slice(o, o + n_t))
            else:
                o = int(rngs[i].uniform() * recs[0][0]["n_period"])
            sig[i] = _mix(recs, "signal", (slice(None), slice(o, o + n_t)))
            e = o + n_t

            def step(name: str, e=e, o=o, recs=recs) -> float:
                return _mix(recs, name, e) - _mix(recs, name, o)
            eff[i] = step("p_out") / step("p_in")
            n_mean[i] = step("w_in") / n_t * 60 / (2 * np.pi)
            t_mean[i] = step("t_out") / n_t
        return sig, keys, eff, n_mean, t_mean, angles

    def _records(self, r: int, key: tuple, d: int, payload: float) -> list[tuple[dict, float]]:
        """Window ``r``'s records and their weights: its state's record alone (weight 1),
        or, with the friction in the dynamics, the ladder's rungs around its viscous factor
        (:func:`ladder_weights`; weights 0 left out)."""
        if self.rungs is None:
            return [(self.bank.get(key), 1.0)]
        sev = float(self.schedule.severity[r])
        return [(self.bank.get(self._key(d, sev, payload, float(v))), float(w))
                for v, w in zip(self.rungs[r], self.rung_weights[r], strict=True) if w != 0]

    def _condition(self, rows: np.ndarray, keys: list[tuple], sig: np.ndarray,
                   eff: np.ndarray) -> None:
        """The life's conditions on windows ``rows``, in place: the efficiency at the
        acting friction, the bridges' drift (:mod:`swgsim.datasets.conditions`; the
        acting load is the record's)."""
        c = self.conditions
        simulated = None if self.rungs is None else c.friction[rows]  # in the records
        for key in set(keys):  # the state's own gear parameters, at the record's load
            m = np.array([k == key for k in keys])
            eff[m] *= efficiency_ratio(self.bank.params(key), key[0], key[1],
                                       c.friction[rows][m], c.mu_factor[rows][m],
                                       None if c.coulomb is None else c.coulomb[rows][m],
                                       None if simulated is None else simulated[m])
        gain, offset = c.bridge_gain_offset(rows, self.zero_offsets_mvv)
        sig *= gain[:, :, None]
        sig += offset[:, :, None]

    def _record(self, sig: np.ndarray, n_mean: np.ndarray, rngs: list[np.random.Generator],
                phi_in: np.ndarray | None) -> None:
        """eq. (10) and the converter's noise and quantisation, each window from its own
        stream, in place."""
        cfg = self.plan.config
        amp, fs = cfg.acquisition.amplifier, cfg.chain.sample_rate_hz
        time_s = np.arange(sig.shape[-1]) / fs
        draws, noise = [], []
        for i in range(sig.shape[0]):  # each window's draws from its own stream, in order
            if self.life.disturbed:
                draws.append(draw_disturbance(cfg.disturbance, rngs[i], (1, sig.shape[1])))
            if amp is not None and amp.noise_uv_rms > 0:
                noise.append(rngs[i].normal(0.0, amp.noise_mvv, size=(1, *sig.shape[1:])))
        if self.life.disturbed:  # then the arithmetic for the whole block
            a0, aj, alpha = (np.concatenate(d) for d in zip(*draws, strict=True))
            sig[:] = apply_disturbance(sig, time_s, n_mean, (a0, aj, alpha), phi_in)
        if amp is not None:
            sig[:] = quantise(sig, amp, np.concatenate(noise) if noise else None)

    def _meta(self, rows: np.ndarray, fault: np.ndarray, eff: np.ndarray,
              n_mean: np.ndarray, t_mean: np.ndarray) -> dict[str, np.ndarray]:
        """The per-sample variables of windows ``rows``: the schema's, ``hour``,
        ``commissioning`` and, with a temperature sensor, ``temperature_c``."""
        sch = self.schedule
        duty = [sch.duty[int(d)] for d in sch.duty_index[rows]]
        gear_fault = (fault != "healthy") & uses_position(self.life.fault.fault)
        meta = {
            "gear": np.full(rows.size, self.gear_id),
            "fault": fault.astype(str),
            "variant": np.zeros(rows.size, np.int64),
            "severity": sch.severity[rows],
            "position_deg": np.where(gear_fault, self.position_deg, np.nan),
            "n_in_rpm": np.array([d.n_in_rpm for d in duty]),
            "t_out_nm": np.array([d.t_out_nm for d in duty]),
            "disturbed": np.full(rows.size, bool(self.life.disturbed)),
            "reference": np.zeros(rows.size, bool),
            "efficiency": eff,
            "n_in_mean_rpm": n_mean,
            "t_out_mean_nm": t_mean,
            "hour": sch.hour[rows],
            "commissioning": sch.commissioning[rows],
        }
        if self.conditions is not None and self.conditions.reading_c is not None:
            meta["temperature_c"] = self.conditions.reading_c[rows]
        return meta


def _mix(recs: list[tuple[dict, float]], name: str, index) -> np.ndarray | float:
    """Σ weight · record[name][index] over the records; a record of weight 1 alone is read
    as it is (the bits of a life without the friction in its dynamics)."""
    if len(recs) == 1 and recs[0][1] == 1.0:
        return recs[0][0][name][index]
    return sum(w * np.asarray(rc[name][index], dtype=float) for rc, w in recs)


def life_dataset(sim: LifeSimulator, start: int = 0, stop: int | None = None):
    """Windows ``start:stop`` of a life as a schema-v1 ``xarray.Dataset``, with the per-sample
    variables ``hour`` [h], ``commissioning`` (bool) and, with a temperature sensor,
    ``temperature_c`` [degC], and the life in the attributes."""
    stop = len(sim) if stop is None else stop
    sig, meta = sim.windows(start, stop)
    extra = {k: meta.pop(k) for k in ("hour", "commissioning", "temperature_c") if k in meta}
    angles = {k: meta.pop(k) for k in [k for k, v in meta.items() if v.ndim == 2]}
    cfg = sim.plan.config
    n_t = sig.shape[-1]
    attrs = {"config": sim.plan.plain, "seed": int(cfg.seed),
             "life": _life_attr(sim.life), "gear_id": sim.gear_id,
             "fault_position_deg": sim.position_deg, "fault_sensor": sim.sensor}
    ds = make_dataset(sig, np.arange(n_t) / cfg.chain.sample_rate_hz, meta, attrs)
    ds["hour"] = ("sample", extra["hour"], {"units": "h"})
    ds["commissioning"] = ("sample", extra["commissioning"])
    if "temperature_c" in extra:  # the joint's temperature reading
        ds["temperature_c"] = ("sample", extra["temperature_c"].astype(np.float64),
                               {"units": "degC"})
    for k, v in angles.items():  # a profile's angle channels
        ds[k] = (("sample", "time"), v, {"units": "rad"})
    return ds


def _life_attr(life: LifeConfig) -> dict:
    """The life config as a shard's attribute: without ``conditions`` and
    ``fault.to_failure`` when None (as before these options)."""
    out = {k: v for k, v in dataclasses.asdict(life).items()
           if not (k == "conditions" and v is None)}
    if out["fault"]["to_failure"] is None:
        out["fault"] = {k: v for k, v in out["fault"].items() if k != "to_failure"}
    return out


def simulate_life_shard(plan: DatasetPlan, shard: ShardSpec,
                        influences: dict[tuple | None, Influence] | None = None):
    """One gear's life as a data-set shard (``dataset.life``); returns (Dataset, n).

    ``influences`` is not used: the life's records compute the influences of the root
    cracks they meet (:class:`swgsim.datasets.records.RecordBank`); it is taken so that
    every shard runner has one signature (:data:`swgsim.datasets.generate.RUNNERS`).

    The shard's attributes are those of a grid shard (config, seed, ``content_sha256`` of
    the float32 signals and the sorted per-sample variables, provenance) plus ``life``,
    ``fault_position_deg`` and ``fault_sensor``.
    """
    sim = LifeSimulator(plan, shard.gear, plan.config.life)
    ds = life_dataset(sim)
    ds.attrs.update({"shard": shard.name, "content_sha256": content_hash(ds),
                     "package_version": package_version(), "git_revision": git_revision()})
    return ds, len(sim)
