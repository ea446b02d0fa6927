"""A healthy joint's changing day: temperature, run-in, payload and the bridges' drift.

``dataset.life.conditions`` (:class:`ConditionsConfig`; None, the default: nothing changes
but the fault, every preset's content as before) gives a life the variation a real joint
lives through while its gear stays healthy, each with a sourced magnitude
(:mod:`swgsim.gear.thermal`, :mod:`swgsim.sensing.bridge_drift`):

* **temperature**: operating days with stops, a cold start after each, a first-order
  warm-up towards a rise set by the power the gear loses at its operating point, and a
  hall that can drift (:func:`swgsim.gear.thermal.joint_temperature`);
* **friction**: its temperature law, the grease's viscosity law
  (:func:`swgsim.gear.thermal.friction_scale`) or one drawn from a family of smooth monotone
  laws (:class:`swgsim.gear.thermal.FrictionLaw`), the run-in of a new gear
  (:func:`swgsim.gear.thermal.run_in_factor`) and its running in again after each
  re-greasing in service (:func:`swgsim.gear.thermal.regrease_factor`);
* **payload**: a heavier (or lighter) tool from set hours on, the acting load at every
  duty point times a factor, the commanded points unchanged;
* **bridges**: each bridge's zero and span drift with the temperature, per gear
  (:func:`swgsim.sensing.bridge_drift.draw_bridge_drift`);
* **temperature sensor**: the joint's reading, ``temperature_c`` of every window
  (None: the stream has no temperature), and its fault from a set hour on, stuck, drifting
  or lost (NaN readings; :class:`swgsim.sensing.bridge_drift.TemperatureSensor`): the
  reading alone is wrong, the joint's true temperature and all it drives stay.

How a window gets them (:func:`window_conditions`, used by
:class:`swgsim.datasets.life.LifeSimulator`): its record is that of the nominal gear at
the acting load (a payload factor's own record, simulated like any other,
:mod:`swgsim.datasets.records`); the friction factor changes the window's efficiency by
the ratio of the model's steady efficiencies
(:func:`swgsim.gear.thermal.steady_efficiency`), and not its gauge signals, which the chain takes
from the torque the gear delivers (:mod:`swgsim.gear.chain`): measured, a 25 K warmer gear moves the
efficiency by 80-240 healthy standard deviations and every gauge feature by at most 1.1
(the residual of s0 at 4000 rpm, 70 N m) - held constant [stated simplification]. What
stays constant:
the thermal model's parameters over a life, the gear's stiffness and backlash (the
catalogue gives no temperature dependence), the sensor's calibration offset.

Randomness: the bridges' coefficients from ``SeedSequence(seed, spawn_key=(gear,
2**21))`` (a property of the gear, the same in all its lives), the sensor's noise from
``spawn_key=(gear, life_seed, 2**22)``, drawn for the whole schedule at once; neither
touches a window's own stream.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from swgsim.base.typed import check_range
from swgsim.gear.faults import ChainParams
from swgsim.gear.thermal import (
    REF_TEMP_C,
    REGREASE_DROP,
    REGREASE_TAU_H,
    RUN_IN_DROP,
    RUN_IN_TAU_H,
    TEMP_RANGE_C,
    FrictionLaw,
    JointThermal,
    joint_temperature,
    loss_power_w,
    regrease_factor,
    run_in_factor,
    steady_efficiency,
)
from swgsim.sensing.bridge_drift import (
    BridgeDrift,
    TemperatureSensor,
    draw_bridge_drift,
    measure_temperature,
)

__all__ = ["ConditionsConfig", "Regrease", "RunInConfig", "WindowConditions", "check_conditions",
           "efficiency_ratio", "window_conditions"]


@dataclass
class RunInConfig:
    """Friction of a new gear running in (:func:`swgsim.gear.thermal.run_in_factor`).

    Attributes
    ----------
    drop : float
        Excess friction of a new gear, in [0, 1] [-].
    tau_h : float
        Time constant, > 0 [operating h].
    """

    drop: float = RUN_IN_DROP
    tau_h: float = RUN_IN_TAU_H


@dataclass
class Regrease:
    """Re-greasing in service: the friction steps up and runs in again
    (:func:`swgsim.gear.thermal.regrease_factor`; the latest re-greasing counts).

    Attributes
    ----------
    hours : list of float
        Operating hours of the re-greasings, increasing, inside the life [h].
    drop : float
        Excess friction just after a re-greasing, in [0, 1] [-] (0.3) [choice: fresh
        grease churns until it has redistributed].
    tau_h : float
        Time constant of running in again, > 0 [operating h] (8: over in about a day)
        [choice].
    """

    hours: list[float]
    drop: float = REGREASE_DROP
    tau_h: float = REGREASE_TAU_H


@dataclass
class ConditionsConfig:
    """What changes while the gear stays healthy (module docstring).

    Attributes
    ----------
    thermal : JointThermal or None
        The joint's temperature over the life; None: it stays at the catalogue's
        reference temperature (20 °C).
    viscosity : bool
        Friction follows the temperature, by ``friction_law``.
    friction_law : FrictionLaw
        How (default: the grease's viscosity law, :func:`swgsim.gear.thermal.friction_scale`);
        an evaluation draws it from the family.
    run_in : RunInConfig or None
        A new gear's friction running in from hour 0; None: the gear is run in.
    regrease : Regrease or None
        Re-greasings in service, each followed by a run-in; None: none.
    payload : list of [float, float]
        ``[operating hour, factor]`` pairs, hours increasing: from each hour on, the acting
        load at every duty point is the commanded one times the factor (> 0); before the
        first, 1.
    bridge_drift : BridgeDrift or None
        The bridges' zero and span drift with temperature; None: none.
    temperature_sensor : TemperatureSensor or None
        The joint's temperature reading (``temperature_c``); None: the stream has none.
    """

    thermal: JointThermal | None = field(default_factory=JointThermal)
    viscosity: bool = True
    friction_law: FrictionLaw = field(default_factory=FrictionLaw)
    run_in: RunInConfig | None = None
    regrease: Regrease | None = None
    payload: list[list[float]] = field(default_factory=list)
    bridge_drift: BridgeDrift | None = field(default_factory=BridgeDrift)
    temperature_sensor: TemperatureSensor | None = field(default_factory=TemperatureSensor)


def check_conditions(cfg: ConditionsConfig, hours: float, key: str) -> None:
    """Refuse conditions outside their ranges, in one line naming the key.

    Parameters
    ----------
    cfg : ConditionsConfig
    hours : float
        The life's length [h] (payload steps must lie inside it).
    key : str
        Full name, e.g. ``dataset.life.conditions``.

    Raises
    ------
    ValueError
    """
    if cfg.thermal is not None:
        cfg.thermal.check(f"{key}.thermal")
    cfg.friction_law.check(f"{key}.friction_law")
    if cfg.run_in is not None:
        check_range(cfg.run_in.drop, 0.0, 1.0, f"{key}.run_in.drop")
        check_range(cfg.run_in.tau_h, 0.0, 1e5, f"{key}.run_in.tau_h", "h", lo_open=True)
    if cfg.regrease is not None:
        _check_regrease(cfg.regrease, hours, f"{key}.regrease")
    last = -np.inf
    for i, step in enumerate(cfg.payload):
        if len(step) != 2:
            raise ValueError(f"{key}.payload[{i}] must be [hour, factor], got {step}")
        check_range(step[0], 0.0, hours, f"{key}.payload[{i}][0]", "h",
                    why="an operating hour inside the life")
        check_range(step[1], 0.0, 10.0, f"{key}.payload[{i}][1]", lo_open=True,
                    why="factor on the acting load")
        if step[0] <= last:
            raise ValueError(f"{key}.payload: hours must increase, got "
                             f"{[s[0] for s in cfg.payload]}")
        last = step[0]
    if cfg.bridge_drift is not None:
        cfg.bridge_drift.check(f"{key}.bridge_drift")
    if cfg.temperature_sensor is not None:
        cfg.temperature_sensor.check(f"{key}.temperature_sensor")


def _check_regrease(cfg: Regrease, hours: float, key: str) -> None:
    """Refuse re-greasing hours outside the life or not increasing, a drop or time
    constant out of range, in one line naming ``<key>.<field>``."""
    if len(cfg.hours) == 0:
        raise ValueError(f"{key}.hours must name at least one operating hour (no "
                         f"re-greasing: {key}: null)")
    for i, h in enumerate(cfg.hours):
        check_range(h, 0.0, hours, f"{key}.hours[{i}]", "h",
                    why="an operating hour inside the life")
    if any(b <= a for a, b in zip(cfg.hours[:-1], cfg.hours[1:], strict=True)):
        raise ValueError(f"{key}.hours must increase, got {list(cfg.hours)}")
    check_range(cfg.drop, 0.0, 1.0, f"{key}.drop")
    check_range(cfg.tau_h, 0.0, 1e5, f"{key}.tau_h", "h", lo_open=True)


@dataclass(frozen=True)
class WindowConditions:
    """The conditions of every window of a life's schedule.

    Attributes
    ----------
    temperature_c : ndarray, shape (W,)
        The joint's true temperature [°C].
    reading_c : ndarray, shape (W,) or None
        The temperature sensor's reading [°C] (None without a sensor; NaN where its fault
        is a dropout).
    friction : ndarray, shape (W,)
        Factor on the load-independent friction (viscosity, run-in, re-greasing) [-].
    mu_factor : ndarray, shape (W,)
        Factor on the mesh's load-proportional friction μ (run-in, re-greasing) [-].
    payload : ndarray, shape (W,)
        Factor on the acting load [-].
    zero_mvv_per_k, span_per_k : ndarray, shape (5,)
        The gear's bridge drift coefficients (zeros without drift).
    drift_ref_c : float
        Temperature of no drift [°C].
    """

    temperature_c: np.ndarray
    reading_c: np.ndarray | None
    friction: np.ndarray
    mu_factor: np.ndarray
    payload: np.ndarray
    zero_mvv_per_k: np.ndarray
    span_per_k: np.ndarray
    drift_ref_c: float

    def bridge_gain_offset(self, rows: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Each window's bridge gain and zero offset, shapes (n, 5) and (n, 5) [-, mV/V]:
        the drift at the window's temperature."""
        dt = (self.temperature_c[rows] - self.drift_ref_c)[:, None]
        return 1.0 + self.span_per_k[None, :] * dt, self.zero_mvv_per_k[None, :] * dt


def _payload(cfg: ConditionsConfig, hours: np.ndarray) -> np.ndarray:
    out = np.ones_like(hours)
    for h, f in cfg.payload:
        out[hours >= h] = f
    return out


def window_conditions(cfg: ConditionsConfig, hours: np.ndarray, n_in_rpm: np.ndarray,
                      t_out_nm: np.ndarray, gear: ChainParams, seed: int, gear_id: int,
                      life_seed: int) -> WindowConditions:
    """The conditions of a life's windows (module docstring).

    Parameters
    ----------
    cfg : ConditionsConfig
        Checked (:func:`check_conditions`).
    hours : ndarray, shape (W,)
        Operating hours of the windows, increasing [h].
    n_in_rpm, t_out_nm : ndarray, shape (W,)
        Each window's commanded speed [rpm] and load [N m].
    gear : ChainParams
        The healthy gear (its loss heats the joint).
    seed, gear_id, life_seed : int
        The data set's seed, the gear, the life (random streams, module docstring).

    Returns
    -------
    WindowConditions
    """
    payload = _payload(cfg, hours)
    if cfg.thermal is not None:
        loss = loss_power_w(gear.gear, np.abs(n_in_rpm), np.abs(t_out_nm) * payload)
        temp = joint_temperature(hours, loss, cfg.thermal)
        _check_joint_temperature(temp, hours, cfg.thermal)
    else:
        temp = np.full(hours.shape, REF_TEMP_C)
    run_in = (run_in_factor(hours, cfg.run_in.drop, cfg.run_in.tau_h)
              if cfg.run_in is not None else np.ones_like(hours))
    if cfg.regrease is not None:
        rg = cfg.regrease
        run_in = run_in * regrease_factor(hours, rg.hours, rg.drop, rg.tau_h)
    friction = (cfg.friction_law.factor(temp) if cfg.viscosity else 1.0) * run_in
    reading = None
    if cfg.temperature_sensor is not None:
        ss = np.random.SeedSequence(int(seed), spawn_key=(int(gear_id), int(life_seed), 2**22))
        reading = measure_temperature(temp, cfg.temperature_sensor, np.random.default_rng(ss),
                                      hours=hours)
    zero, span, ref = np.zeros(5), np.zeros(5), REF_TEMP_C
    if cfg.bridge_drift is not None:
        ss = np.random.SeedSequence(int(seed), spawn_key=(int(gear_id), 2**21))
        zero, span = draw_bridge_drift(cfg.bridge_drift, np.random.default_rng(ss))
        ref = float(cfg.bridge_drift.ref_c)
    return WindowConditions(temp, reading, np.asarray(friction, float), run_in, payload,
                            zero, span, ref)


def _check_joint_temperature(temp: np.ndarray, hours: np.ndarray, th: JointThermal) -> None:
    """Refuse a joint temperature outside the viscosity law's range in one line naming
    the thermal model's fields that set it (the hall and the loss times
    ``r_th_k_per_w``)."""
    lo, hi = TEMP_RANGE_C
    bad = np.flatnonzero((temp < lo) | (temp > hi))
    if bad.size:
        i = int(bad[0])
        raise ValueError(f"conditions.thermal: the joint reaches {temp[i]:.4g} °C at "
                         f"operating hour {hours[i]:.4g} (the hall, ambient_c "
                         f"{th.ambient_c:g} °C, plus the gear's loss times r_th_k_per_w "
                         f"{th.r_th_k_per_w:g} K/W); the viscosity law takes "
                         f"[{lo:g}, {hi:g}] °C")


def efficiency_ratio(gear: ChainParams, n_in_rpm, t_out_nm, friction: np.ndarray,
                     mu_factor: np.ndarray) -> np.ndarray:
    """The factor a window's efficiency changes by under its friction: the model's steady
    efficiency at the acting friction over that at the nominal one, at the record's
    speed and load, shape of ``friction`` [-]
    (:func:`swgsim.gear.thermal.steady_efficiency`)."""
    n = np.abs(np.asarray(n_in_rpm, float))
    t = np.abs(np.asarray(t_out_nm, float))
    nominal = steady_efficiency(gear.gear, n, t)
    acting = steady_efficiency(gear.gear, n, t, friction, mu_factor)
    with np.errstate(divide="ignore", invalid="ignore"):
        return np.where(nominal > 0, acting / nominal, 1.0)
