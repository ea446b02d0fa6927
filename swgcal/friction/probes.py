"""Residual probes of the friction side: one per residual signature of a joint-friction
effect (over velocity, acceleration, joint angle, travel since reversal, time).

The probe machinery (bins, best sinusoid, trends; out-of-sample scores) is
:mod:`swgcal.diagnose`.
"""

from __future__ import annotations

from typing import Any

import numpy as np

from ..diagnose import BinnedProbe, PeriodicProbe, Probe, TrendProbe

__all__ = ["friction_probes", "travel_since_reversal"]


def travel_since_reversal(sig: Any) -> np.ndarray:
    """Unsigned travel since the last reversal of motion [rad]."""
    q = sig.q_rad
    dq = np.diff(q, prepend=q[0])
    d = np.sign(dq)
    # carry the last nonzero direction forward
    idx = np.where(d != 0, np.arange(d.size), 0)
    np.maximum.accumulate(idx, out=idx)
    d = d[idx]
    rev = np.flatnonzero(np.diff(d) != 0) + 1
    start = np.zeros(q.size, int)
    start[rev] = rev
    np.maximum.accumulate(start, out=start)
    return np.abs(q - q[start])


def friction_probes(temperature: bool = False) -> list[Probe]:
    """The residual probes of the friction side (one per residual signature).

    Parameters
    ----------
    temperature : bool, default False
        The recording has a temperature column: add temperature_odd (bins over the
        measured temperature, odd in direction).

    Returns
    -------
    list of Probe
        velocity, velocity_hysteresis (bins over q̇ per sign of q̈), acceleration,
        position and position_odd (bins over q), position_periodic(_odd) (best
        sinusoid over q), travel_since_reversal (odd), time and time_odd (cubic trend),
        time_periodic(_odd) (best sinusoid over t); temperature_odd where asked.
    """

    def q_range(sig):
        s = sig.scales
        return max(4.0 * s.dq_med, s.q_span / 2000.0), s.q_span / 2.0

    def t_range(sig):
        s = sig.scales
        return 10.0 * s.dt_med, s.t_span / 3.0

    extra: list[Probe] = [BinnedProbe(
        "temperature_odd", "follows the measured temperature with a sign that flips with "
        "direction", lambda s: s.temperature_c, 20, odd=True)] if temperature else []
    return extra + [
        BinnedProbe("velocity", "depends on the velocity q̇", lambda s: s.dq_rad_s, 40),
        BinnedProbe("velocity_hysteresis",
                    "depends on q̇ differently when accelerating and decelerating",
                    lambda s: s.dq_rad_s, 20,
                    split_by=lambda s: (np.sign(s.ddq_rad_s2) * np.sign(s.dq_rad_s)
                                        ).astype(int)),
        BinnedProbe("acceleration", "depends on the acceleration q̈", lambda s: s.ddq_rad_s2,
                    30),
        BinnedProbe("position", "depends on the joint angle q (same in both directions)",
                    lambda s: s.q_rad, 60),
        BinnedProbe("position_odd", "depends on q with a sign that flips with direction",
                    lambda s: s.q_rad, 60, odd=True),
        PeriodicProbe("position_periodic", "periodic in q, same in both directions",
                      lambda s: s.q_rad, q_range, unit="rad", wg_order=True),
        PeriodicProbe("position_periodic_odd", "periodic in q, flipping with direction",
                      lambda s: s.q_rad, q_range, odd=True, unit="rad", wg_order=True),
        BinnedProbe("travel_since_reversal",
                    "depends on the travel since the last reversal (presliding)",
                    travel_since_reversal, 30, odd=True),
        TrendProbe("time", "drifts over time (same in both directions)", lambda s: s.t_s),
        TrendProbe("time_odd", "drifts over time with a sign flipping with direction",
                   lambda s: s.t_s, odd=True),
        PeriodicProbe("time_periodic", "periodic in time, same in both directions",
                      lambda s: s.t_s, t_range, unit="s"),
        PeriodicProbe("time_periodic_odd", "periodic in time, flipping with direction",
                      lambda s: s.t_s, t_range, odd=True, unit="s"),
    ]
