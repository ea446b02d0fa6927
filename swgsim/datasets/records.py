"""Records of a gear's states, from which its life's windows are cut.

A gear in a steady state at one operating point repeats its signals once per output
revolution (the WG angle and the flexspline both return; N input revolutions, 3 s at
2000 rpm). Each (operating point, state) is therefore simulated once, as one *record* of
one output revolution plus a window (:class:`RecordBank`): the dynamics
(:func:`swgsim.gear.dynamics.simulate`), the gauge signals and the measurement chain up to
the converter's filter, exactly as a data set's windows
(:mod:`swgsim.datasets.grid_shard`). On an operating profile (:class:`ProfileRecordBank`) each
state is simulated once along the whole profile, and its record holds every slot
(:mod:`swgsim.datasets.slots`). The windows are cut by :mod:`swgsim.datasets.life`.
"""

from __future__ import annotations

import dataclasses
import math

import numpy as np

from swgsim.datasets.config import gear_params, layout_for
from swgsim.datasets.plan import DatasetPlan
from swgsim.datasets.schedule import DutyPoint, uses_position
from swgsim.datasets.slots import jitter_samples, profile_slots
from swgsim.datasets.steps import diverged, fine_motion, influences_for, sampling, unique_index
from swgsim.gear import dynamics, profile_dynamics
from swgsim.gear.chain import SimulationChain
from swgsim.gear.faults import ChainParams, apply_fault
from swgsim.sensing.acquisition import sample, start_angles
from swgsim.sensing.angles import measure_angles
from swgsim.sensing.effects import apply_sensor_effects
from swgsim.sensing.sensor_faults import is_sensor_fault

__all__ = ["SIGNAL_GROUP", "ProfileRecordBank", "RecordBank", "record_bank"]

#: Records whose gauge signals are synthesised at once on the fine grid (memory:
#: :mod:`swgsim.datasets.resources`).
SIGNAL_GROUP = 16


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
        Distinct motions per batch (bounds the memory of the dynamics).
    """

    def __init__(self, plan: DatasetPlan, gear_id: int, chunk: int = 96) -> None:
        self.plan, self.gear_id, self.chunk = plan, int(gear_id), int(chunk)
        self.healthy = gear_params(plan.config, plan.gears[self.gear_id])
        self._pending: set[tuple] = set()
        self._records: dict[tuple, dict] = {}
        self._influences: dict = {}

    @staticmethod
    def key(dp: DutyPoint, fault: str, severity: float, position_deg: float,
            viscous: float = 1.0) -> tuple:
        """The key of a record: (speed, torque, gear fault, severity, position), and the
        factor on the viscous friction b1, b2 where it is not 1 (a joint's warm or cold
        grease in its dynamics, :data:`swgsim.datasets.life.VISCOUS_LADDER`)."""
        if fault == "healthy" or is_sensor_fault(fault) or severity == 0:
            base = (float(dp.n_in_rpm), float(dp.t_out_nm), "healthy", 0.0, 0.0)
        else:
            pos = float(position_deg) if uses_position(fault) else 0.0
            base = (float(dp.n_in_rpm), float(dp.t_out_nm), fault, float(severity), pos)
        return base if viscous == 1.0 else (*base, float(viscous))

    def params(self, key: tuple) -> ChainParams:
        """Chain parameters of the gear in the state of a key (b1 and b2 times the key's
        viscous factor, where it has one)."""
        _, _, fault, sev, pos = key[:5]
        p = self.healthy if fault == "healthy" else apply_fault(self.healthy, fault, sev, pos)
        if len(key) > 5:
            g = p.gear
            p = dataclasses.replace(p, gear=dataclasses.replace(
                g, b1_nms=g.b1_nms * key[5], b2_nms3=g.b2_nms3 * key[5]))
        return p

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

    def release(self, healthy: bool = False) -> None:
        """Drop the records kept and asked for: those of gear faults, and with
        ``healthy`` the healthy ones too (bounded memory between lives; a record asked
        for again is simulated again)."""
        def kept(k: tuple) -> bool:
            return not healthy and k[2] == "healthy"
        self._records = {k: v for k, v in self._records.items() if kept(k)}
        self._pending = {k for k in self._pending if kept(k)}

    def record_samples(self, key: tuple) -> int:
        """Data-rate samples a record holds: one output revolution at its input speed
        plus a window."""
        fs, _, n_t, _ = sampling(self.plan.config)
        return int(math.ceil(self.healthy.gear.ratio * 60.0 / key[0] * fs)) + n_t

    def wanted(self) -> set[tuple]:
        """The keys of the records kept and asked for."""
        return set(self._records) | self._pending

    def simulate(self) -> None:
        """Simulate every pending record, in batches per input speed of at most
        ``chunk`` distinct motions (:meth:`motion`): an integration costs nearly the same
        for one motion as for a hundred, so a batch takes every record it can."""
        pending, self._pending = sorted(self._pending), set()
        for n in sorted({k[0] for k in pending}):
            by_motion: dict[tuple, list[tuple]] = {}
            for k in pending:
                if k[0] == n:
                    by_motion.setdefault(self.motion(k), []).append(k)
            groups = list(by_motion.values())
            for c in range(0, len(groups), self.chunk):
                self._simulate([k for g in groups[c:c + self.chunk] for k in g])

    def motion(self, key: tuple) -> tuple:
        """What a record's dynamics depend on: the gear's parameters and the load (the
        flexspline's faults share the healthy gear's motion, paper Table I)."""
        return (self.params(key).gear, key[1])

    def _chain(self, params: list[ChainParams]) -> SimulationChain:
        keys = {p.root_crack_key() for p in params} - {None} - set(self._influences)
        if keys or not self._influences:
            self._influences.update(influences_for(self.plan, [self.gear_id], keys)[self.gear_id])
        cfg = self.plan.config
        return SimulationChain.from_influences(layout_for(cfg, self.plan.gears[self.gear_id]),
                                               self._influences, cfg.chain)

    def _simulate(self, keys: list[tuple]) -> None:
        cfg = self.plan.config
        ch, n_in = cfg.chain, keys[0][0]
        fs, q, n_t, n_lead = sampling(cfg)
        n_period = int(math.ceil(self.healthy.gear.ratio * 60.0 / n_in * fs))
        n_rec = n_period + n_t
        params = [self.params(k) for k in keys]
        n_sim = n_rec + 2 * n_lead + (q > 1)
        first, motion = unique_index([self.motion(k) for k in keys])  # one per motion
        res = dynamics.simulate([params[i].gear for i in first], n_in,
                                np.array([keys[i][1] for i in first]), 0.0, fs, n_sim / fs,
                                ch.settle_s - n_lead / fs, ch.substeps,
                                friction_effects=self.plan.friction)
        if not res.success:
            raise ValueError(diverged(self.plan, f"gear {self.gear_id}'s life at {n_in:g} rpm",
                                      res.message))
        chain = self._chain(params)
        win = slice(n_lead, n_lead + n_rec)
        for c in range(0, len(keys), SIGNAL_GROUP):  # gauge signals in small groups
            rows = np.arange(c, min(c + SIGNAL_GROUP, len(keys)))
            psi, t_act = fine_motion(res, q, motion[rows])
            variants = [params[r] for r in rows]
            sig = self._measured(chain.signals_batch(variants, psi, t_act), n_in, n_lead)
            for i, r in enumerate(rows):
                cum = {k: np.concatenate([[0.0], np.cumsum(v[motion[r], win])])
                       for k, v in (("p_in", res.p_in), ("p_out", res.p_out),
                                    ("w_in", res.states[1]), ("t_out", res.t_out))}
                self._records[keys[r]] = {"signal": sig[i, :, :n_rec].astype(np.float32),
                                          "n_period": n_period, **cum}

    def _measured(self, sig: np.ndarray, n_in: float, n_lead: int) -> np.ndarray:
        """Ideal bridge signals on the fine grid through the measurement chain (sensor
        effects, the converter's filter and sampling before its noise), shape
        (V, 5, n)."""
        cfg = self.plan.config
        amp, fs = cfg.acquisition.amplifier, cfg.chain.sample_rate_hz
        if self.plan.sensor_effects:
            q = 1 if amp is None else amp.oversample
            t_fine = np.arange(sig.shape[-1]) / (fs * q)
            sig = apply_sensor_effects(sig, t_fine, np.full(len(sig), n_in),
                                       self.plan.sensor_effects,
                                       t_start_s=np.full(len(sig), -n_lead / fs))
        return sample(sig, amp, n_lead) if amp is not None else sig


class ProfileRecordBank(RecordBank):
    """Records of one gear along the profile: one per state, all its slots (module
    docstring). :meth:`get` gives, per slot over its window and jitter (n = n_t + jitter
    samples), ``signal`` (S, 5, n) [mV/V] sampled as the converter does (before its
    noise), the cumulative sums ``p_in``, ``p_out`` [W], ``w_in`` [rad/s], ``t_out``
    [N m] (S, n + 1) as a steady record's, ``phi_in`` (S, n) [rad] (the simulated input
    angle, for eq. (10)) and the recorded angle channels ``phi_in_meas`` (and
    ``phi_out_meas`` with an output encoder)."""

    def __init__(self, plan: DatasetPlan, gear_id: int, chunk: int = 32) -> None:
        super().__init__(plan, gear_id, chunk)
        self.slots = profile_slots(plan)

    @staticmethod
    def key(dp: DutyPoint, fault: str, severity: float, position_deg: float,
            viscous: float = 1.0) -> tuple:
        """The key of a record: the state alone (every slot is in the record)."""
        return (0.0, 0.0, *RecordBank.key(dp, fault, severity, position_deg, viscous)[2:])

    def record_samples(self, key: tuple) -> int:
        """Data-rate samples a record holds: every slot's window and jitter."""
        _, _, n_t, _ = sampling(self.plan.config)
        return len(self.slots.starts) * (n_t + jitter_samples(self.plan.config))

    def motion(self, key: tuple) -> tuple:
        """What a record's motion along the profile depends on: the gear's parameters."""
        return (self.params(key).gear,)

    def _simulate(self, keys: list[tuple]) -> None:
        cfg = self.plan.config
        ch, amp = cfg.chain, cfg.acquisition.amplifier
        fs, q, n_t, n_lead = sampling(cfg)
        n_t += jitter_samples(cfg)  # window + jitter
        params = [self.params(k) for k in keys]
        # the same pose every cycle: one start angle per gear, within one WG revolution
        ss = np.random.SeedSequence(int(cfg.seed), spawn_key=(self.gear_id, 2 ** 20))
        phi0 = np.mod(start_angles(cfg.acquisition, 1, np.random.default_rng(ss),
                                   self.healthy.gear.ratio), 2 * np.pi)
        starts = self.slots.starts
        n_rec = int(starts.max()) + n_t + n_lead + 1
        first, motion = unique_index([self.motion(k) for k in keys])  # one per motion
        res = profile_dynamics.simulate_profile([params[i].gear for i in first],
                                                self.plan.profile,
                                                np.full(len(first), phi0[0]), fs, n_rec / fs,
                                                ch.substeps, cfg.profile.feedforward)
        if not res.success:
            raise ValueError(diverged(self.plan, f"gear {self.gear_id}'s life on the profile",
                                      res.message))
        chain = self._chain(params)
        n_cut = q * (n_t + 2 * n_lead) if amp is not None else n_t
        idx = q * (starts - n_lead)[:, None] + np.arange(n_cut)[None, :]
        win = starts[:, None] + np.arange(n_t)[None, :]
        angles = cfg.profile.angles
        meas = measure_angles(res.states[0][:, win], res.states[2][:, win],
                              input_sensor=angles.input_sensor(),
                              output_encoder=angles.output_encoder())
        t_fine = np.arange(n_cut) / (fs * q)
        for r, k in enumerate(keys):
            v = motion[r]
            psi_f, t_f = fine_motion(res, q, np.array([v]))
            cut = chain.signals_batch([params[r]], psi_f, t_f)[0][:, idx].transpose(1, 0, 2)
            if self.plan.sensor_effects:
                cut = apply_sensor_effects(cut, t_fine, None, self.plan.sensor_effects,
                                           t_start_s=(starts - n_lead) / fs, psi=psi_f[0][idx])
            cut = sample(cut, amp, n_lead) if amp is not None else cut
            cum = {c: np.concatenate([np.zeros((len(starts), 1)), np.cumsum(x[v, win], axis=1)],
                                     axis=1)
                   for c, x in (("p_in", res.p_in), ("p_out", res.p_out),
                                ("w_in", res.states[1]), ("t_out", res.t_out))}
            self._records[k] = {
                "signal": cut.astype(np.float32), **cum,
                "phi_in": res.states[0][v, win],
                **{f"{c}_meas": m[v] for c, m in meas.items()},
            }


def record_bank(plan: DatasetPlan, gear_id: int) -> RecordBank:
    """The records of one gear's lives: along the profile for a profile data set, else
    at its steady operating points."""
    return ProfileRecordBank(plan, gear_id) if plan.profile is not None else RecordBank(
        plan, gear_id)
