"""The slots of a gear life on an operating profile: the data set's profile is the duty
cycle (docs/DATASET.md, "Gear lives": "A life on a profile").

Each state of the gear (healthy, a fault at one severity and position) is simulated once
along the whole profile (:func:`swgsim.gear.profile_dynamics.simulate_profile`; the
records: :mod:`swgsim.datasets.records`) and every window of the life is a cut of that
motion, in a *slot*: a window of the data set in which the wave generator turns at least
:data:`MIN_WG_REVOLUTIONS` revolutions one way (the angle-domain features need about 1.45
revolutions, :mod:`learn.inputs.health`; gauge misplacement needs a monotone ψ,
:mod:`swgsim.sensing.effects`). Window k lies in slot k mod S, starting up to
``dataset.profile.start_jitter_s`` after the slot's start; its operating point is the
slot's *commanded* one, the same for every state of the gear. From cycle to cycle only
the start within the jitter, eq. (10)'s draws (in the input angle,
:func:`swgsim.sensing.disturbance.disturb`) and the converter's noise and quantisation
differ: the gear returns to its pose every cycle (no payload, temperature or speed
variation between cycles is modelled).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from swgsim.datasets.config import gear_params
from swgsim.datasets.schedule import DutyPoint
from swgsim.gear import profile as pf

#: Least wave-generator revolutions (one way) of a window recorded by a profile life.
MIN_WG_REVOLUTIONS = 2.0


@dataclass(frozen=True)
class Slots:
    """The windows of one profile cycle that a life records.

    Attributes
    ----------
    starts : ndarray of int, shape (S,)
        First sample of each slot in the profile's motion.
    n_in_rpm : ndarray, shape (S,)
        Mean desired input speed [rpm] (signed).
    t_out_nm : ndarray, shape (S,)
        Mean load along the desired motion [N m].
    """

    starts: np.ndarray
    n_in_rpm: np.ndarray
    t_out_nm: np.ndarray

    def duty(self, interval_min: float) -> list[DutyPoint]:
        """One duty point per slot, each held one window interval: window k in slot k mod S."""
        return [DutyPoint(float(n), float(t), float(interval_min))
                for n, t in zip(self.n_in_rpm, self.t_out_nm, strict=True)]


def profile_slots(plan) -> Slots:
    """The slots of a profile data set (module docstring; :func:`slots_of` of its plan)."""
    return slots_of(plan.config, plan.profile, plan.shards[0].window_starts_s)


def slots_of(cfg, profile: pf.Profile, starts_s) -> Slots:
    """The slots of a profile (module docstring).

    Parameters
    ----------
    cfg : DatasetConfig
        With a profile (its chain, its first gear's ratio).
    profile : swgsim.gear.profile.Profile
        The checked profile.
    starts_s : sequence of float
        The data set's window starts [s].

    Returns
    -------
    Slots

    Raises
    ------
    ValueError
        If no window of the profile turns the wave generator :data:`MIN_WG_REVOLUTIONS`
        revolutions one way, naming ``dataset.profile``.
    """
    fs = float(cfg.chain.sample_rate_hz)
    n_t = int(round(cfg.chain.window_s * fs))
    n_jit = jitter_samples(cfg)
    starts = np.round(np.asarray(starts_s) * fs).astype(np.int64)
    t = np.arange(int(starts.max()) + n_t + n_jit + 1) / fs
    w_d, _ = pf.speed_at(profile, t)  # [rad/s]
    ratio = float(gear_params(cfg, cfg.gears[0]).gear.ratio)
    q_d = np.concatenate([[0.0], np.cumsum((w_d[1:] + w_d[:-1]) / 2) / fs]) / ratio
    load = np.broadcast_to(pf.load_at(profile.load, t, q=q_d, q_dot=w_d / ratio,
                                      ratio=ratio), t.shape)
    keep, n_mean, t_mean = [], [], []
    for s in starts:
        w, span = w_d[s:s + n_t], w_d[s:s + n_t + n_jit]
        turns = min(abs(w.sum()), abs(w_d[s + n_jit:s + n_jit + n_t].sum())) / fs / (2 * np.pi)
        if span.min() * span.max() >= 0 and turns >= MIN_WG_REVOLUTIONS:
            keep.append(s)
            n_mean.append(w.mean() * 60 / (2 * np.pi))
            t_mean.append(load[s:s + n_t].mean())
    if not keep:
        raise ValueError(f"dataset.profile: no window turns the wave generator "
                         f"{MIN_WG_REVOLUTIONS:g} revolutions one way; a gear life on the "
                         "profile records only such windows")
    return Slots(np.array(keep), np.round(n_mean, 6), np.round(t_mean, 6))


def jitter_samples(cfg) -> int:
    """``dataset.profile.start_jitter_s`` of a data set's config in samples of its rate."""
    return int(round(float(cfg.profile.start_jitter_s) * float(cfg.chain.sample_rate_hz)))


__all__ = ["MIN_WG_REVOLUTIONS", "Slots", "jitter_samples", "profile_slots", "slots_of"]
