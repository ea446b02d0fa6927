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

__all__ = ["BLOCK", "LifeSimulator", "life_dataset", "simulate_life_shard"]


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
        lam = (np.ones(len(self.schedule.hour)) if self.conditions is None
               else self.conditions.payload)
        self.bank.want(self._key(d, s, x) for d, s, x in
                       {(int(d), float(s), float(x)) for d, s, x in zip(
                           self.schedule.duty_index, self.schedule.severity, lam,
                           strict=True)})

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

    def _key(self, d: int, severity: float, payload: float = 1.0) -> tuple:
        """The record of duty point ``d`` in a state, at the acting load (the commanded
        one times ``payload``)."""
        dp = self.schedule.duty[d]
        if payload != 1.0:
            dp = dataclasses.replace(dp, t_out_nm=dp.t_out_nm * payload)
        return RecordBank.key(dp, self.life.fault.fault, severity, self.position_deg)

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
            rec = self.bank.get(keys[-1])
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
        return sig, keys, eff, n_mean, t_mean, angles

    def _condition(self, rows: np.ndarray, keys: list[tuple], sig: np.ndarray,
                   eff: np.ndarray) -> None:
        """The life's conditions on windows ``rows``, in place: the efficiency at the
        acting friction, the bridges' drift (:mod:`swgsim.datasets.conditions`; the
        acting load is the record's)."""
        c = self.conditions
        for key in set(keys):  # the state's own gear parameters, at the record's load
            m = np.array([k == key for k in keys])
            eff[m] *= efficiency_ratio(self.bank.params(key), key[0], key[1],
                                       c.friction[rows][m], c.mu_factor[rows][m],
                                       None if c.coulomb is None else c.coulomb[rows][m])
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
