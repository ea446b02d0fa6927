"""The joint's thermal model as fitted terms: the project's first-order model (the base)
and the library of candidate effects it lacks, each with a physical argument and range.

The base is :func:`swgsim.gear.thermal.joint_temperature`'s model, C dT/dt = P − (T −
T_amb)/R_th, τ = R_th C, heated by the gear's loss P: with the loss held constant between
readings (a zero-order hold, as the simulator holds a window's loss), its exact discrete
form is x_k = a_k x_{k−1} + (1 − a_k) P_{k−1}, a_k = exp(−Δt_k/τ) [derived], a unit-gain
low-pass of the loss (:func:`first_order_lag`, one linear recurrence). The temperature
T = T_amb (1 − e^{−(t − t_0)/τ}) + T_0 e^{−(t − t_0)/τ} + R_th · lag_τ(P) is linear in
(T_amb, T_0, R_th) for a given τ: the separable fit of :mod:`swgcal.core` (T_0 the joint at
the first reading, ΔT_0 = T_0 − T_amb the offset reported). Every effect adds columns of
its own (its own time constant where it has one); none changes the base's.

Only physical fits: every linear coefficient is bounded in the fit
(:meth:`~swgcal.terms.FitTerm.linear_bounds`; a coefficient left on a bound is flagged)
and every parameter has a physical range with its source (:attr:`~swgcal.terms.FitTerm.ranges`).
The room: T_amb within :data:`AMBIENT_RANGE_C` and no warmer than the coolest joint's first
reading (every joint is heated, none cooled below its room) [derived]; the joint at the
first reading no cooler than that (so ΔT_0 >= 0); R_th >= 0, τ > 0 (so C > 0); each
effect's gain of its physical sign. Ranges [choice where not sourced]: wide enough for any
small to medium robot joint, so that a fit outside one is an effect absorbing something
else, not a small joint.
"""

from __future__ import annotations

from typing import Any

import numpy as np

from swgsim.base.registry import Registry
from swgsim.gear.terms import Param, linear_recurrence

from ..terms import FitTerm

__all__ = ["AMBIENT_RANGE_C", "R_TH_RANGE_K_PER_W", "THERMAL_LIBRARY", "AmbientDrift",
           "CopperLoss", "FirstOrderJoint", "HousingLag", "NeighbourHeat", "PoweredHeat",
           "StandstillCooling", "first_order_lag"]

_TAU_BOUNDS_MIN = (2.0, 600.0)  # any time constant a fit may take [min] [choice]
#: The room a robot joint works in [°C]: 0-50 °C, a UR3's rated ambient range [Universal
#: Robots, UR3 technical specifications; unverified: no copy in the repository].
AMBIENT_RANGE_C = (0.0, 50.0)
#: A small robot joint's thermal resistance to its room [K/W]: above 0 (a finite
#: conductance), at most 20 [choice: a small servo motor's winding to ambient is a few K/W
#: [unverified]; the loss proxy's unverified k_τ scales R_th, so the range is wide].
R_TH_RANGE_K_PER_W = (0.0, 20.0)
_INF = float("inf")
_SIGN_BOUNDS = {1: (0.0, _INF), -1: (-_INF, 0.0), 0: (-_INF, _INF)}


def first_order_lag(u_held: np.ndarray, dt_s: np.ndarray, tau_min: float) -> np.ndarray:
    """Unit-gain first-order low-pass of an input held constant between samples, exact.

    Parameters
    ----------
    u_held : ndarray, shape (n,)
        Input over the interval ending at each sample (0 for the first) [any unit].
    dt_s : ndarray, shape (n,)
        Length of that interval [s] (0 for the first).
    tau_min : float
        Time constant, > 0 [min].

    Returns
    -------
    ndarray, shape (n,)
        The lagged input at each sample, from 0 before the first [unit of ``u_held``].
    """
    a = np.exp(-dt_s / (60.0 * float(tau_min)))
    return linear_recurrence(a, (1.0 - a) * u_held)


class _Lagged(FitTerm):
    """A term with a time constant τ [min] (in ``tau_range``, started at each of
    ``tau_starts``), by default of one column, ``lag_τ(input)``: the input the signals'
    attribute ``input_name``, its gain of the sign ``gain_sign``."""

    input_name = ""
    tau_range: tuple[float, float] = _TAU_BOUNDS_MIN
    tau_starts: tuple[float, ...] = (30.0,)
    gain_sign = 0  # the gain's physical sign in the fit (+1, -1; 0: either)

    def linear_bounds(self, sig: Any) -> list[tuple[float, float]]:
        return [_SIGN_BOUNDS[self.gain_sign]]

    def columns(self, sig: Any, theta: np.ndarray) -> np.ndarray:
        return first_order_lag(getattr(sig, self.input_name), sig.dt_s, theta[0])[:, None]

    def bounds(self, sig: Any) -> list[tuple[float, float]]:
        return [self.tau_range]

    def starts(self, sig: Any, residual: np.ndarray, idx: np.ndarray) -> list[np.ndarray]:
        return [np.array([t]) for t in self.tau_starts]


class FirstOrderJoint(_Lagged):
    """The project's thermal model (:class:`swgsim.gear.thermal.JointThermal`): the room's
    temperature, the joint's at the first reading decaying towards it with τ, and R_th
    times the lagged loss (module docstring).

    Parameters
    ----------
    name : str, optional
        Instance name (default ``first_order``).
    start_c : float, optional
        Hold T_0 at this value [°C] instead of fitting it: the measured first reading where
        the fitted part does not see the start (the cross-validation fitted after a gap,
        :func:`swgcal.thermal.problem.cross_validate`).
    """

    kind = "first_order"
    linear = (Param("ambient_c", "°C", "room temperature (constant)"),
              Param("start_c", "°C", "the joint at the first reading"),
              Param("r_th_k_per_w", "K/W", "thermal resistance joint -> room"))
    nonlinear = (Param("tau_min", "min", "thermal time constant R_th C", log=True),)
    description = "first-order joint heated by the gear's loss (swgsim.gear.thermal)"
    source = "swgsim.gear.thermal.joint_temperature"
    ranges = {"ambient_c": (*AMBIENT_RANGE_C, "a UR3's rated ambient [unverified]"),
              "initial_k": (0.0, _INF, "a heated joint is not below its room [derived]"),
              "r_th_k_per_w": (*R_TH_RANGE_K_PER_W, "> 0, a small joint [choice]"),
              "tau_min": (*_TAU_BOUNDS_MIN, "a joint's time constants [choice]")}
    tau_starts = (15.0, 40.0, 120.0)

    def __init__(self, name: str | None = None, start_c: float | None = None) -> None:
        super().__init__(name)
        self.start_c = start_c

    def columns(self, sig: Any, theta: np.ndarray) -> np.ndarray:
        decay = np.exp(-(sig.t_s - sig.t_s[0]) / (60.0 * float(theta[0])))
        return np.column_stack([1.0 - decay, decay,
                                first_order_lag(sig.loss_w, sig.dt_s, theta[0])])

    def linear_bounds(self, sig: Any) -> list[tuple[float, float]]:
        """T_amb in :data:`AMBIENT_RANGE_C` and at most the coolest joint's first reading
        (held at the measured room, ``sig.room_c``, where given), T_0 at least the room's
        bound (or held at ``start_c``), R_th >= 0 [°C, °C, K/W]."""
        measured = sig.room_c is not None
        room = float(sig.room_c) if measured else min(AMBIENT_RANGE_C[1], sig.room_max_c)
        ambient = (room, room) if measured else (AMBIENT_RANGE_C[0], room)
        start = (room, _INF) if self.start_c is None else (self.start_c, self.start_c)
        return [ambient, start, (R_TH_RANGE_K_PER_W[0], _INF)]

    def derived(self, coef: np.ndarray, theta: np.ndarray) -> dict[str, float]:
        amb, start, r_th = (float(c) for c in coef)
        return {"ambient_c": amb, "initial_k": start - amb, "r_th_k_per_w": r_th,
                "tau_min": float(theta[0]), "start_c": start}

    def derived_units(self) -> dict[str, str]:
        return {"ambient_c": "°C", "initial_k": "K", "r_th_k_per_w": "K/W", "tau_min": "min",
                "start_c": "°C"}


class CopperLoss(_Lagged):
    """The motor's copper loss R_w I², heating the joint beside the gear: present at
    standstill too, where a joint holds its link against gravity."""

    kind = "copper"
    input_name = "current_sq_a2"
    linear = (Param("k_cu_k_per_a2", "K/A²", "steady rise per squared motor ampere, "
                                             "R_th,cu R_w"),)
    nonlinear = (Param("tau_cu_min", "min", "time constant of the winding's heat path",
                       log=True),)
    signature = "rises with the motor current squared, also at standstill"
    description = "motor copper loss R_w I², lagged"
    source = "Joule heating of the winding [textbook]"
    probes = ("current_squared", "time")
    #: R_w 0.2-5 Ω phase-to-phase of a small servo motor times R_th 0.2-2 K/W gives up to
    #: 10 K/A² [unverified: no UR motor data sheet]; τ of a motor's winding and housing
    #: 2-300 min [choice].
    ranges = {"k_cu_k_per_a2": (0.0, 10.0, "R_w <= 5 Ohm, R_th <= 2 K/W [unverified]"),
              "tau_cu_min": (2.0, 300.0, "a motor's thermal time constants [choice]")}
    tau_starts = (10.0, 40.0)
    gain_sign = 1


class HousingLag(_Lagged):
    """A second, slower time constant: the housing and the link store heat the winding's
    short path does not see (a two-node network)."""

    kind = "housing"
    input_name = "loss_w"
    linear = (Param("r2_k_per_w", "K/W", "thermal resistance of the slow path"),)
    nonlinear = (Param("tau2_min", "min", "slow time constant", log=True),)
    signature = "a warm-up that keeps creeping after the first time constant"
    description = "second, slow first-order path of the gear's loss"
    source = "two-node thermal network [textbook]"
    probes = ("time",)
    ranges = {"r2_k_per_w": (0.0, 5.0, "a small joint's housing [choice]"),
              "tau2_min": (60.0, 600.0, "slower than the joint's own (>= 1 h), a housing of "
                                        "a few kg of aluminium [choice]")}
    tau_range = (30.0, 600.0)
    tau_starts = (120.0, 300.0)
    gain_sign = 1


class NeighbourHeat(_Lagged):
    """Heat from the neighbouring joints through the link: their copper losses, lagged."""

    kind = "neighbour"
    input_name = "neighbour_sq_a2"
    linear = (Param("k_nb_k_per_a2", "K/A²", "rise per squared ampere of the neighbours"),)
    nonlinear = (Param("tau_nb_min", "min", "time constant of the path", log=True),)
    signature = "follows the neighbouring joints' currents"
    description = "neighbours' copper loss (joints j-1, j+1), lagged"
    source = "conduction through the link [textbook]"
    probes = ("neighbour_current_squared", "time")
    ranges = {"k_nb_k_per_a2": (0.0, 2.0, "weaker than a joint's own winding [choice]"),
              "tau_nb_min": (10.0, 600.0, "through the link, slower than the winding "
                                          "[choice]")}
    tau_starts = (60.0,)
    gain_sign = 1


class StandstillCooling(_Lagged):
    """Standstill: no windage and the brakes engaged, the joint cools towards the hall
    differently from what the loss alone says (a negative step, lagged)."""

    kind = "standstill"
    input_name = "still"
    linear = (Param("dt_still_k", "K", "steady change at standstill"),)
    nonlinear = (Param("tau_still_min", "min", "time constant", log=True),)
    signature = "lower after standing still than the loss says"
    description = "standstill indicator, lagged"
    source = "convection changing with motion [textbook]"
    probes = ("speed", "time")
    ranges = {"dt_still_k": (-10.0, 0.0, "cooling, at most the joint's rise [choice]"),
              "tau_still_min": (2.0, 300.0, "a joint's time constants [choice]")}
    gain_sign = -1


class PoweredHeat(_Lagged):
    """Heat of the joint's own motor and drive while the arm is powered, moving or not: the
    servo amplifier's and the encoder's standby loss and the brake's release coil, in the
    joint's housing [unverified: UR's joint electronics are not documented], through a
    path of its own to the sensor (its own time constant)."""

    kind = "powered"
    input_name = "powered"
    linear = (Param("k_pw_k", "K", "steady rise while powered, R_th,pw P_standby"),)
    nonlinear = (Param("tau_pw_min", "min", "time constant of the drive's heat path",
                       log=True),)
    signature = "warmer while powered than the gear's loss says, from power-on"
    description = "the joint's motor and drive while powered (standby loss), lagged"
    source = "a servo drive's quiescent loss and brake coil [textbook]"
    probes = ("time",)
    #: P_standby <= 15 W, a sixth of a UR3's typical 100 W [unverified: UR3 technical
    #: specifications], times R_th <= 2 K/W: at most 30 K [choice].
    ranges = {"k_pw_k": (0.0, 30.0, "P_standby <= 15 W, R_th <= 2 K/W [unverified]"),
              "tau_pw_min": (2.0, 600.0, "a joint's time constants [choice]")}
    tau_starts = (10.0, 60.0)
    gain_sign = 1


class AmbientDrift(FitTerm):
    """The hall warming or cooling over the day: a linear drift of T_amb."""

    kind = "ambient_drift"
    linear = (Param("drift_k_per_h", "K/h", "hall's drift"),)
    signature = "a slow trend over the day"
    description = "hall temperature drifting linearly"
    source = "a hall's day [choice]"
    probes = ("time",)
    ranges = {"drift_k_per_h": (-1.0, 1.0, "a hall drifts a few K over a day, "
                                           "cf. JointThermal.ambient_swing_k 3 K [choice]")}

    def columns(self, sig: Any, theta: np.ndarray) -> np.ndarray:
        return ((sig.t_s - sig.t_s[0]) / 3600.0)[:, None]


#: Candidate effects by key (the base, :class:`FirstOrderJoint`, is not one): a registry
#: of the project's one type (:class:`swgsim.base.registry.Registry`; an effect of your own
#: joins with ``THERMAL_LIBRARY.add(kind, cls)``).
THERMAL_LIBRARY: Registry[type[FitTerm]] = Registry("thermal effect", __name__,
                                                    "THERMAL_LIBRARY", (
    (c.kind, c) for c in (CopperLoss, HousingLag, AmbientDrift, NeighbourHeat,
                          StandstillCooling, PoweredHeat)))
