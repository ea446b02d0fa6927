"""Synthetic joint logs with known thermal constants, for the thermal calibration's tests
(not a test module).

A log of one joint (the others quiet) at one reading a second: a pick-and-place duty whose
speed level changes every 4 cycles and its holding current (a payload's) every 6, where
asked pauses standing still, a gap standing still, and the temperature from the project's
first-order model (:class:`swgcal.thermal.library.FirstOrderJoint`) with the given
constants, plus, where asked, one or more library effects (the motor's copper loss, a
second slow time constant, cooling at standstill, the motor's and drive's heat while
powered, with the arm powered off for a while) or a cooling fan switching with the
cycle count (an effect outside the library), plus white noise. Nothing here is a
measurement.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from swgcal.thermal.library import (
    CopperLoss,
    FirstOrderJoint,
    HousingLag,
    PoweredHeat,
    StandstillCooling,
    first_order_lag,
)
from swgcal.thermal.options import GEAR_EFFICIENCY, TORQUE_PER_AMP_NM
from swgcal.thermal.problem import thermal_signals
from swgsim.datasets.joint_log import JOINTS, JointLog

__all__ = ["SyntheticThermal", "synthetic_joint_log"]


@dataclass(frozen=True)
class SyntheticThermal:
    """Known constants of a synthetic log (all [choice], of the UR3 day's size).

    Attributes
    ----------
    r_th_k_per_w, tau_min, ambient_c, initial_k : float
        The base model's constants [K/W], [min], [°C], [K].
    k_cu_k_per_a2, tau_cu_min : float
        Copper loss (0: none) [K/A²], [min] (:class:`swgcal.thermal.library.CopperLoss`).
    r2_k_per_w, tau2_min : float
        A second, slow path of the gear's loss (0: none) [K/W], [min]
        (:class:`swgcal.thermal.library.HousingLag`).
    dt_still_k, tau_still_min : float
        Cooling at standstill (0: none) [K], [min]
        (:class:`swgcal.thermal.library.StandstillCooling`).
    k_pw_k, tau_pw_min : float
        Heat of the joint's motor and drive while powered (0: none) [K], [min]
        (:class:`swgcal.thermal.library.PoweredHeat`).
    off_h : float
        The arm powered off (every current and speed 0) for this long in the middle of the
        part before the gap (0: never) [h].
    others_k : float
        The other joints' readings above the room [K]: they are heated too, so the room
        lies below the coolest joint's first reading.
    pause_blocks : int
        The joint stands still (holding current only) through every ``pause_blocks``-th
        block of 4 cycles (0: never).
    fan_k, fan_cycles : float, int
        A fan cooling by ``fan_k`` [K] (lagged 3 min) during every other block of
        ``fan_cycles`` cycles (0: none): outside the library.
    noise_k : float
        White noise on the temperature [K].
    hours_before, gap_h, hours_after : float
        Parts of the log [h].
    """

    r_th_k_per_w: float = 0.5
    tau_min: float = 35.0
    ambient_c: float = 24.0
    initial_k: float = 3.0
    k_cu_k_per_a2: float = 0.0
    tau_cu_min: float = 15.0
    r2_k_per_w: float = 0.0
    tau2_min: float = 150.0
    dt_still_k: float = 0.0
    tau_still_min: float = 20.0
    pause_blocks: int = 0
    k_pw_k: float = 0.0
    tau_pw_min: float = 20.0
    off_h: float = 0.0
    others_k: float = 2.0
    fan_k: float = 0.0
    fan_cycles: int = 12
    noise_k: float = 0.02
    hours_before: float = 1.5
    gap_h: float = 1.0
    hours_after: float = 1.5
    seed: int = 0

    @property
    def start_c(self) -> float:
        """The joint at the first reading [°C] (the base's T_0)."""
        return self.ambient_c + self.initial_k


def synthetic_joint_log(c: SyntheticThermal) -> JointLog:
    """A synthetic joint log of joint 1 (module docstring).

    Returns
    -------
    JointLog
        Name ``synthetic``, the temperature of joint 1 the model's plus noise, the other
        joints' readings constant.
    """
    rng = np.random.default_rng(c.seed)
    n1, n2 = int(c.hours_before * 3600), int(c.hours_after * 3600)
    t = np.concatenate([np.arange(n1), n1 - 1 + c.gap_h * 3600 + np.arange(n2)]).astype(float)
    n = t.size
    cycle = (np.arange(n) // 30 + 1).astype(np.int64)  # a cycle every 30 readings
    block = rng.uniform(0.3, 1.0, size=cycle.max() // 4 + 2)[cycle // 4]  # duty level
    hold = rng.uniform(0.5, 3.0, size=cycle.max() // 6 + 2)[cycle // 6]  # payload's [A]
    phase = np.sin(2 * np.pi * np.arange(n) / 30.0)
    if c.pause_blocks:
        phase[(cycle // 4) % c.pause_blocks == c.pause_blocks - 1] = 0.0
    speed = np.zeros((n, JOINTS))
    current = np.full((n, JOINTS), 0.1)
    speed[:, 1] = block * 2.0 * phase
    current[:, 1] = hold + block * 2.0 * np.abs(phase)
    if c.off_h:
        off = np.abs(t - n1 / 2) < c.off_h * 1800
        speed[off], current[off] = 0.0, 0.0
    temp = np.full((n, JOINTS), c.ambient_c + c.others_k)
    log = JointLog("synthetic", "2026-01-01T08:00:00Z", t, temp, current, speed,
                   np.zeros(n), cycle, np.zeros(n, bool), np.zeros(n, bool),
                   np.array([n1]))
    sig = thermal_signals(log, 1, TORQUE_PER_AMP_NM, GEAR_EFFICIENCY)
    y = FirstOrderJoint().predict(sig, np.array([c.ambient_c, c.ambient_c + c.initial_k,
                                                 c.r_th_k_per_w]), np.array([c.tau_min]))
    for term, gain, tau in ((CopperLoss(), c.k_cu_k_per_a2, c.tau_cu_min),
                            (HousingLag(), c.r2_k_per_w, c.tau2_min),
                            (StandstillCooling(), c.dt_still_k, c.tau_still_min),
                            (PoweredHeat(), c.k_pw_k, c.tau_pw_min)):
        y = y + term.predict(sig, np.array([gain]), np.array([tau]))
    if c.fan_k and c.fan_cycles:
        fan = ((cycle // c.fan_cycles) % 2 == 1).astype(float)
        y = y - c.fan_k * first_order_lag(np.concatenate([[0.0], fan[:-1]]), sig.dt_s, 3.0)
    temp[:, 1] = y + c.noise_k * rng.standard_normal(n)
    return log
