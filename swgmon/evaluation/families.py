"""Families of benign changes (``monitor.study.families``): each nuisance life of the
evaluation draws its change's law and magnitude from declared ranges, instead of living
one fixed :class:`~swgsim.datasets.conditions.ConditionsConfig` made with the monitor's laws.

:class:`NuisanceFamily` names the parts it draws (:data:`PARTS`) and one range ``[lo, hi]``
per magnitude; :func:`draw_conditions` turns a family and a seed into one life's
conditions, the same for the same seed; :func:`default_families` gives the study's.
Design and sources (every range's origin, the draws' order):
docs/monitor/evaluation.md, "Families of benign changes".
"""

from __future__ import annotations

import dataclasses
import zlib
from collections.abc import Sequence
from dataclasses import dataclass, field

import numpy as np

from swgsim.base.typed import check_range
from swgsim.datasets.conditions import (
    ConditionsConfig,
    DutyChange,
    Regrease,
    RunInConfig,
    TemperatureTrace,
    trace_rise,
)
from swgsim.datasets.growth import (
    DEPTH_AT_ONE_M,
    LAWS,
    RunToFailure,
    arrhenius_factor,
    film_factor,
)
from swgsim.gear.faults import get_fault
from swgsim.gear.thermal import (
    FRICTION_FORMS,
    MONOTONE_FORMS,
    FrictionLaw,
    JointThermal,
    ThermalNetwork,
)
from swgsim.sensing.bridge_drift import (
    TEMPERATURE_SENSOR_FAULTS,
    BridgeDrift,
    TemperatureSensor,
)

__all__ = ["ALL_SENSOR_STATES", "DEFAULT_PARTS", "FAMILY_TAG", "PARTS",
           "RANGES", "SENSOR_STATES", "UR3_COLUMNS", "GrowthFamily", "NuisanceFamily",
           "benchmark_families", "default_families", "draw_conditions", "draw_growth"]

#: The parts of a joint's day a family can draw (docs/monitor/evaluation.md, "Families of benign
#: changes"); the last four are issue 83's, which the monitor was not built on: the joint in
#: two nodes with its motor and drive (``network``), a Coulomb term with a law of its own
#: whose slope changes sign and its own run-in (``coulomb``), the friction in the gear's
#: dynamics (``dynamics``), and a new program holding the duty points for other times
#: (``duty``).
PARTS = ("friction_law", "warm_up", "drift", "ambient", "run_in", "payload", "sensor",
         "regrease", "trace", "network", "coulomb", "dynamics", "duty")
#: The parts a family draws by default: the day's, without the ``trace`` (its file is the
#: user's) and without issue 83's.
DEFAULT_PARTS = PARTS[:8]
#: The parts that need the joint's temperature (refused in a ``still`` family).
THERMAL_PARTS = ("friction_law", "warm_up", "drift", "ambient", "trace", "network", "coulomb")
#: The UR3 CobotOps file's joint temperature columns (its first is named ``T0``).
UR3_COLUMNS = ("Temperature_T0", *(f"Temperature_J{i}" for i in range(1, 6)))
#: States of the temperature sensor a family draws by default: a working sensor, none, or
#: one of the sensor's faults (:data:`swgsim.sensing.bridge_drift.TEMPERATURE_SENSOR_FAULTS`).
SENSOR_STATES = ("present", "missing", *TEMPERATURE_SENSOR_FAULTS[1:])
#: Every state a family may name: those, and a sound sensor that lags the housing or reads
#: with an offset (issue 83; ``sensor_lag_min``, ``sensor_offset_k``).
ALL_SENSOR_STATES = (*SENSOR_STATES, "lagging", "offset")
#: Second word of every family draw's seed, ``default_rng([seed, FAMILY_TAG, key])``.
FAMILY_TAG = 0x5F4A11

#: Range fields: (part, allowed lo, allowed hi, unit, what) - the bounds a range must lie
#: within (:meth:`NuisanceFamily.check`), wider than the defaults. Each magnitude is drawn
#: from a stream keyed by its name (:func:`_keyed`): adding a range, a part or a family
#: moves no existing draw.
RANGES = {
    "ratio_40c": ("friction_law", 0.3, 1.0, "", "FrictionLaw.ratio_40c"),
    "r_th_k_per_w": ("warm_up", 1e-3, 5.0, "K/W", "thermal resistance"),
    "tau_min": ("warm_up", 1.0, 600.0, "min", "thermal time constant"),
    "gauge_mismatch_ue_per_k": ("drift", 0.0, 50.0, "µε/K", "gauge-to-gauge mismatch"),
    "zero_mean_mvv_per_k": ("drift", -1e-2, 1e-2, "mV/V per K", "mean zero drift"),
    "span_mean_per_k": ("drift", -2e-3, 2e-3, "1/K", "mean span drift"),
    "span_sd_per_k": ("drift", 0.0, 1e-3, "1/K", "bridge-to-bridge span spread"),
    "ambient_shift_k": ("ambient", -20.0, 30.0, "K", "the hall's slow change"),
    "ambient_start_h": ("ambient", 1.0, 1e4, "h", "wall-clock start of the change"),
    "ambient_ramp_h": ("ambient", 0.1, 1e3, "h", "duration of the change"),
    "ambient_swing_k": ("ambient", 0.0, 20.0, "K", "day/night amplitude"),
    "run_in_drop": ("run_in", 0.0, 1.0, "", "a new gear's excess friction"),
    "run_in_tau_h": ("run_in", 0.1, 1e3, "h", "run-in time constant"),
    "payload_factor": ("payload", 0.1, 10.0, "", "factor on the acting load"),
    "payload_h": ("payload", 0.0, 1e5, "h", "operating hour of the tool change"),
    "sensor_fault_h": ("sensor", 0.0, 1e5, "h", "operating hour of the sensor's fault"),
    "sensor_drift_k_per_h": ("sensor", -10.0, 10.0, "K per h", "a drifting sensor's rate"),
    "regrease_h": ("regrease", 0.0, 1e5, "h", "operating hour of the re-greasing"),
    "regrease_drop": ("regrease", 0.0, 1.0, "", "excess friction of fresh grease"),
    "regrease_tau_h": ("regrease", 0.1, 1e3, "h", "time constant of running in again"),
    "trace_scale": ("trace", 0.0, 10.0, "", "factor on the measured rise"),
    "grease_r_k_per_w": ("network", 0.005, 0.25, "K/W", "grease to housing, running"),
    "standstill_factor": ("network", 1.0, 20.0, "", "grease to housing at a stop over running"),
    "motor_km_nm_per_sqrt_w": ("network", 0.05, 1.0, "N m/√W", "the motor's constant"),
    "drive_w": ("network", 0.0, 50.0, "W", "the drive's electronics while powered"),
    "coulomb_ratio_40c": ("coulomb", 0.3, 1.0, "", "the Coulomb term's factor at 40 °C"),
    "coulomb_minimum_c": ("coulomb", 45.0, 80.0, "°C", "where the Coulomb law turns"),
    "coulomb_drop": ("coulomb", 0.0, 1.0, "", "the Coulomb term's run-in excess"),
    "coulomb_tau_h": ("coulomb", 0.1, 1e3, "h", "the Coulomb term's run-in time constant"),
    "sensor_lag_min": ("sensor", 0.0, 600.0, "min", "a lagging sensor's time constant"),
    "sensor_offset_k": ("sensor", -10.0, 10.0, "K", "a sensor's calibration offset"),
    "duty_h": ("duty", 0.0, 1e5, "h", "operating hour of the new program"),
    "duty_shift": ("duty", -1.0, 1.0, "", "time moved to high load (+) or low (-)"),
}


def _span(lo: float, hi: float):
    return field(default_factory=lambda: [lo, hi])


@dataclass
class NuisanceFamily:
    """A family of benign changes: the parts drawn and each magnitude's range ``[lo, hi]``
    (units and origins: docs/monitor/evaluation.md, "Families of benign changes").

    Attributes
    ----------
    parts : list of str
        Parts of :data:`PARTS` drawn, at least one (default :data:`DEFAULT_PARTS`).
    still : bool
        Live at the reference temperature (no warm-up, friction law or bridge drift);
        refused with a part of :data:`THERMAL_PARTS`.
    friction_forms : list of str
        Forms the friction law is drawn from, among
        :data:`swgsim.gear.thermal.FRICTION_FORMS` (default the monotone ones,
        :data:`swgsim.gear.thermal.MONOTONE_FORMS`).
    sensor_states : list of str
        States of the temperature sensor drawn from (:data:`SENSOR_STATES`).
    ratio_40c, r_th_k_per_w, tau_min : list of float
        Friction factor at 40 °C [-]; thermal resistance [K/W]; time constant [min].
    gauge_mismatch_ue_per_k, zero_mean_mvv_per_k, span_mean_per_k, span_sd_per_k : list
        The bridges' drift [µε/K, mV/V per K, 1/K, 1/K].
    ambient_shift_k, ambient_start_h, ambient_ramp_h, ambient_swing_k : list of float
        The hall's ramp [K], its start and duration [wall-clock h]; day/night swing [K].
    run_in_drop, run_in_tau_h : list of float
        A new gear's excess friction [-] and its time constant [operating h].
    payload_factor, payload_h : list of float
        Factor on the acting load [-] from operating hour ``payload_h`` [h] on.
    sensor_fault_h, sensor_drift_k_per_h : list of float
        Operating hour of the temperature sensor's fault [h]; a drifting sensor's rate
        [K per operating h].
    regrease_h, regrease_drop, regrease_tau_h : list of float
        Operating hour of a re-greasing [h], its excess friction [-] and time constant
        [operating h].
    trace_path : str
        The measured warm-up's file for the ``trace`` part (a ``;``-separated table,
        :class:`~swgsim.datasets.conditions.TemperatureTrace`); "" without it.
    trace_columns : list of str
        Its temperature columns, one drawn per life.
    trace_scale : list of float
        Factor on the measured rise [-].
    logged : bool
        The re-greasing is in the maintenance log handed to the monitor
        (:class:`swgmon.assessment.gear_monitor.MaintenanceEvent`); refused without the
        ``regrease`` part.
    grease_r_k_per_w, standstill_factor, motor_km_nm_per_sqrt_w, drive_w : list of float
        The joint in two nodes (``network``, :data:`RANGES`).
    coulomb_ratio_40c, coulomb_minimum_c, coulomb_drop, coulomb_tau_h : list of float
        The Coulomb term's own law and run-in (``coulomb``).
    sensor_lag_min, sensor_offset_k : list of float
        A sound sensor's lag [min] and offset [K] (states ``lagging``, ``offset``).
    duty_h, duty_shift : list of float
        A new program from operating hour ``duty_h`` [h] on, its dwells shifted to high
        load (> 0) or low by ``duty_shift`` in [-1, 1]
        (:attr:`swgsim.datasets.conditions.DutyChange.load_shift`).
    """

    parts: list[str] = field(default_factory=lambda: list(DEFAULT_PARTS))
    still: bool = False
    friction_forms: list[str] = field(default_factory=lambda: list(MONOTONE_FORMS))
    sensor_states: list[str] = field(default_factory=lambda: list(SENSOR_STATES))
    ratio_40c: list[float] = _span(0.3, 1.0)
    r_th_k_per_w: list[float] = _span(0.3, 0.5)
    tau_min: list[float] = _span(20.0, 60.0)
    gauge_mismatch_ue_per_k: list[float] = _span(0.1, 2.0)
    zero_mean_mvv_per_k: list[float] = _span(-5e-4, 5e-4)
    span_mean_per_k: list[float] = _span(0.0, 4e-4)
    span_sd_per_k: list[float] = _span(0.0, 1e-4)
    ambient_shift_k: list[float] = _span(-10.0, 15.0)
    ambient_start_h: list[float] = _span(30.0, 120.0)
    ambient_ramp_h: list[float] = _span(6.0, 72.0)
    ambient_swing_k: list[float] = _span(0.0, 6.0)
    run_in_drop: list[float] = _span(0.05, 0.3)
    run_in_tau_h: list[float] = _span(10.0, 60.0)
    payload_factor: list[float] = _span(0.8, 1.2)
    payload_h: list[float] = _span(30.0, 48.0)
    sensor_fault_h: list[float] = _span(30.0, 120.0)
    sensor_drift_k_per_h: list[float] = _span(-0.5, 0.5)
    regrease_h: list[float] = _span(30.0, 48.0)
    regrease_drop: list[float] = _span(0.1, 0.5)
    regrease_tau_h: list[float] = _span(4.0, 24.0)
    trace_path: str = ""
    trace_columns: list[str] = field(default_factory=lambda: list(UR3_COLUMNS))
    trace_scale: list[float] = _span(1.0, 4.0)
    logged: bool = False
    grease_r_k_per_w: list[float] = _span(0.03, 0.12)
    standstill_factor: list[float] = _span(2.0, 8.0)
    motor_km_nm_per_sqrt_w: list[float] = _span(0.1, 0.3)
    drive_w: list[float] = _span(2.0, 10.0)
    coulomb_ratio_40c: list[float] = _span(0.5, 1.0)
    coulomb_minimum_c: list[float] = _span(45.0, 80.0)
    coulomb_drop: list[float] = _span(0.0, 0.3)
    coulomb_tau_h: list[float] = _span(2.0, 20.0)
    sensor_lag_min: list[float] = _span(5.0, 40.0)
    sensor_offset_k: list[float] = _span(-2.0, 2.0)
    duty_h: list[float] = _span(30.0, 48.0)
    duty_shift: list[float] = _span(-1.0, 1.0)

    def check(self, key: str = "NuisanceFamily") -> None:
        """Refuse a family outside its ranges in one line naming ``<key>.<field>`` and
        what it allows.

        Parameters
        ----------
        key : str
            Full name of the family, e.g. ``monitor.study.families.warm_up``.

        Raises
        ------
        ValueError
            An unknown or repeated part, form or sensor state, a ``still`` family with a
            thermal part, or a range not ``[lo, hi]`` with ``lo <= hi`` inside its bounds
            (:data:`RANGES`).
        """
        for name, allowed in (("parts", PARTS), ("friction_forms", FRICTION_FORMS),
                              ("sensor_states", ALL_SENSOR_STATES)):
            got = list(getattr(self, name))
            if not got or len(set(got)) != len(got) or not set(got) <= set(allowed):
                raise ValueError(f"{key}.{name} must list distinct values of "
                                 f"{', '.join(allowed)}, got {got}")
        hot = sorted(set(self.parts) & set(THERMAL_PARTS))
        if self.still and hot:
            raise ValueError(f"{key}.parts: a still family draws none of "
                             f"{', '.join(THERMAL_PARTS)}, got {hot}")
        if "trace" in self.parts:
            if not self.trace_path or not self.trace_columns:
                raise ValueError(f"{key}.trace_path: the trace part needs a measured "
                                 f"warm-up's file and columns, got {self.trace_path!r}")
            for col in self.trace_columns:  # one line naming <key>.trace.path or .column
                trace_rise(TemperatureTrace(self.trace_path, col), f"{key}.trace")
        if self.logged and "regrease" not in self.parts:
            raise ValueError(f"{key}.logged: only a family with the regrease part has a "
                             f"maintenance log to hand over, parts {list(self.parts)}")
        for name, (_, lo, hi, unit, what) in RANGES.items():
            r = list(getattr(self, name))
            try:
                ok = len(r) == 2 and lo <= float(r[0]) <= float(r[1]) <= hi
            except (TypeError, ValueError):
                ok = False
            if not ok:
                raise ValueError(f"{key}.{name} must be [lo, hi], lo <= hi, within "
                                 f"[{lo:g}, {hi:g}]{' ' + unit if unit else ''} ({what}), "
                                 f"got {r}")


def default_families() -> dict[str, NuisanceFamily]:
    """The families an evaluation lives by default: each part alone (with the friction
    law drawn wherever the joint's temperature changes) and all together.

    Returns
    -------
    dict of str to NuisanceFamily
        ``friction_law``, ``warm_up``, ``drift``, ``ambient``, ``run_in`` (still),
        ``payload`` (still), ``sensor`` (missing), ``sensor_stuck``, ``sensor_drift``,
        ``sensor_dropout``, ``regrease`` (still, not in the maintenance log),
        ``regrease_logged`` (still, in it) and ``all`` (every part, the sensor in any of
        its states, nothing logged).
    """
    def with_law(part: str, **kw) -> NuisanceFamily:
        return NuisanceFamily(parts=[part, "friction_law"], **kw)

    return {"friction_law": NuisanceFamily(parts=["friction_law"]),
            "warm_up": with_law("warm_up"),
            "drift": with_law("drift"),
            "ambient": with_law("ambient"),
            "run_in": NuisanceFamily(parts=["run_in"], still=True),
            "payload": NuisanceFamily(parts=["payload"], still=True),
            "sensor": with_law("sensor", sensor_states=["missing"]),
            **{f"sensor_{f}": with_law("sensor", sensor_states=[f])
               for f in TEMPERATURE_SENSOR_FAULTS[1:]},
            "regrease": NuisanceFamily(parts=["regrease"], still=True),
            "regrease_logged": NuisanceFamily(parts=["regrease"], still=True, logged=True),
            "all": NuisanceFamily()}


def benchmark_families() -> dict[str, NuisanceFamily]:
    """The benchmark's families (issue 83): each a day whose physics the monitor was not
    built on - the joint in two nodes with its motor and drive, the sensor on the housing, a
    Coulomb term with a law of its own that turns, the friction in the gear's dynamics, the
    bridges' drift drawn - under a daily warm-up, and each family's change on top.

    Returns
    -------
    dict of str to NuisanceFamily
        ``warm_up``, ``hall`` (the hall's temperature changes), ``regrease`` (not in the
        maintenance log), ``payload``, ``duty`` (a new program), ``sensor_<state>`` for
        every state but a working sensor (missing, stuck, drift, dropout, lagging, offset),
        and ``all`` (every part, the sensor in any state, nothing logged).
    """
    physics = ["network", "coulomb", "dynamics", "friction_law", "drift", "warm_up"]

    def fam(*parts: str, **kw) -> NuisanceFamily:
        return NuisanceFamily(parts=[*physics, *parts], **kw)

    return {"warm_up": fam(), "hall": fam("ambient"), "regrease": fam("regrease"),
            "payload": fam("payload"), "duty": fam("duty"),
            **{f"sensor_{s}": fam("sensor", sensor_states=[s])
               for s in ALL_SENSOR_STATES if s != "present"},
            "all": fam("ambient", "run_in", "payload", "sensor", "regrease", "duty",
                       sensor_states=list(ALL_SENSOR_STATES))}


def _draws(family: NuisanceFamily, seed: int) -> tuple[dict[str, float], str, str]:
    """Every range's value, the friction form and the sensor state for a seed, each from
    a stream keyed by its name (whichever parts the family draws)."""
    values = {name: _keyed(family, name, seed) for name in RANGES}
    return (values, _keyed_choice(family.friction_forms, "friction_form", seed),
            _keyed_choice(family.sensor_states, "sensor_state", seed))


def _stream(seed: int, key: str) -> np.random.Generator:
    """The draw's stream of a seed keyed by a name."""
    return np.random.default_rng([seed, FAMILY_TAG, zlib.crc32(key.encode())])


def _keyed(family: NuisanceFamily, name: str, seed: int) -> float:
    """A :data:`RANGES` magnitude for a seed, from a stream keyed by its name."""
    return float(_stream(seed, name).uniform(*getattr(family, name)))


def _keyed_choice(options: Sequence[str], what: str, seed: int) -> str:
    """One of ``options`` for a seed by rendezvous hashing (Thaler & Ravishankar 1998):
    each option draws a number from a stream keyed by ``what`` and its own name, the
    smallest wins. Adding an option moves only the seeds it now wins, removing one only
    those it won; the order of the list does not matter."""
    return min(options, key=lambda o: float(_stream(seed, f"{what}:{o}").random()))


def _trace_draw(family: NuisanceFamily, seed: int) -> tuple[float, str]:
    """The trace's scale and column for a seed, each keyed by its name."""
    return (_keyed(family, "trace_scale", seed),
            _keyed_choice(family.trace_columns, "trace_column", seed))


def draw_conditions(family: NuisanceFamily, seed: int) -> ConditionsConfig:
    """One life's conditions drawn from a family (docs/monitor/evaluation.md, "Families of
    benign changes"); pure and deterministic.

    Parameters
    ----------
    family : NuisanceFamily
        Checked (:meth:`NuisanceFamily.check`).
    seed : int
        The draw's seed, in [0, 2**32 - 1] (a design or a scored seed of the study).

    Returns
    -------
    ConditionsConfig
        The joint's day: the simulator's defaults (a daily warm-up, the catalogue's
        friction law, the default bridge drift, a temperature sensor) with the family's
        parts drawn; a still family's without temperature.

    Raises
    ------
    ValueError
        ``seed`` not an integer in [0, 2**32 - 1].
    """
    if isinstance(seed, bool) or not isinstance(seed, int | np.integer) \
            or not 0 <= int(seed) <= 2**32 - 1:
        raise ValueError(f"seed must be an integer in [0, 4294967295], got {seed!r}")
    v, form, state = _draws(family, int(seed))
    parts = set(family.parts)
    thermal: dict = {}
    if "warm_up" in parts:
        thermal.update(r_th_k_per_w=v["r_th_k_per_w"], tau_min=v["tau_min"])
    if "ambient" in parts:
        start = v["ambient_start_h"]
        thermal.update(ambient_swing_k=v["ambient_swing_k"], ambient_points=[
            [0.0, 0.0], [start, 0.0], [start + v["ambient_ramp_h"], v["ambient_shift_k"]]])
    sensor = TemperatureSensor()
    if "sensor" in parts and state in ("lagging", "offset"):  # sound, but not the grease
        sensor = dataclasses.replace(sensor, **({"lag_min": v["sensor_lag_min"]}
                                                if state == "lagging"
                                                else {"offset_k": v["sensor_offset_k"]}))
    elif "sensor" in parts and state != "present":
        sensor = None if state == "missing" else dataclasses.replace(
            sensor, fault=state, fault_hour=v["sensor_fault_h"],
            drift_k_per_h=v["sensor_drift_k_per_h"] if state == "drift" else 0.0)
    drift = {}
    if "drift" in parts:
        drift = {k: v[k] for k in ("gauge_mismatch_ue_per_k", "zero_mean_mvv_per_k",
                                   "span_mean_per_k", "span_sd_per_k")}
    cond = ConditionsConfig(
        thermal=dataclasses.replace(JointThermal(), **thermal),
        friction_law=(FrictionLaw(form, v["ratio_40c"]) if "friction_law" in parts
                      else FrictionLaw()),
        run_in=(RunInConfig(drop=v["run_in_drop"], tau_h=v["run_in_tau_h"])
                if "run_in" in parts else None),
        regrease=(Regrease(hours=[v["regrease_h"]], drop=v["regrease_drop"],
                           tau_h=v["regrease_tau_h"]) if "regrease" in parts else None),
        payload=[[v["payload_h"], v["payload_factor"]]] if "payload" in parts else [],
        bridge_drift=dataclasses.replace(BridgeDrift(), **drift),
        temperature_sensor=sensor,
        temperature_trace=(TemperatureTrace(family.trace_path, _trace_draw(family, seed)[1],
                                            scale=v["trace_scale"])
                           if "trace" in parts else None),
        duty_change=(DutyChange(v["duty_h"], load_shift=v["duty_shift"])
                     if "duty" in parts else None))
    cond = _issue_83_parts(cond, parts, v)
    if family.still:
        cond = dataclasses.replace(cond, thermal=None, viscosity=False, bridge_drift=None)
    return cond


def _issue_83_parts(cond: ConditionsConfig, parts: set[str], v: dict[str, float]
                    ) -> ConditionsConfig:
    """The physics of issue 83 on a drawn day: the joint in two nodes, a Coulomb term of its
    own (law, and run-in and re-greasing where drawn), the friction in the dynamics."""
    if "network" in parts:
        net = ThermalNetwork(grease_r_k_per_w=v["grease_r_k_per_w"],
                             standstill_factor=v["standstill_factor"],
                             motor_km_nm_per_sqrt_w=v["motor_km_nm_per_sqrt_w"],
                             drive_w=v["drive_w"])
        cond = dataclasses.replace(cond, thermal=dataclasses.replace(cond.thermal, network=net))
    if "coulomb" in parts:
        apart = {"coulomb_drop": v["coulomb_drop"], "coulomb_tau_h": v["coulomb_tau_h"]}
        cond = dataclasses.replace(
            cond, coulomb_law=FrictionLaw("u_shaped", v["coulomb_ratio_40c"],
                                          v["coulomb_minimum_c"]),
            run_in=None if cond.run_in is None else dataclasses.replace(cond.run_in, **apart),
            regrease=(None if cond.regrease is None
                      else dataclasses.replace(cond.regrease, **apart)))
    if "dynamics" in parts:
        cond = dataclasses.replace(cond, viscous_in_dynamics=True)
    return cond


@dataclass
class GrowthFamily:
    """Growth laws a prognosis does not assume (issue 85): each life to failure draws
    its law's constants from these ranges, every one from a stream keyed by its name, the
    fault, the gear and the seed (:func:`draw_growth`); the prognosis keeps the nominal
    law (one Paris m, no threshold, the film factor, the nominal failure severity).
    Sources and the ranges' origins: docs/monitor/prognosis.md, "Out-of-model lives".

    Attributes
    ----------
    paris_m : list of float
        Paris' m of a crack's life, [lo, hi] within [1, 6] ([2.5, 4]: steels' m
        scatter there, Barsom and Rolfe [unverified: recalled]). C moves with m about a
        pivot (the C-m correlation, Cortie and Garrett, Eng. Fract. Mech. 30 (1988) 49-58
        [unverified: recalled]): the crack grows at the nominal law's rate at the pivot
        ΔK, Y Δσ √(π a) at the data set's mean load and the geometric mean of the onset's
        and the failure's depths.
    threshold_share : list of float
        ΔK_th over the pivot ΔK, [lo, hi] within [0, 1) ([0, 0.5] [choice]: from none to
        a threshold that stops growth at the light loads of the duty).
    activation_kj_per_mol : list of float
        Q of the Arrhenius factor on the wear rate in place of the film factor, [lo, hi]
        within [1, 200] kJ/mol ([20, 60] [choice: tribo-oxidation, below the 100-200 of
        static oxidation; Quinn, Wear 18 (1971) 413-419 [unverified: recalled]]); the
        wear coefficient moves so that both laws wear alike at ``pivot_c``.
    pivot_c : float
        The grease temperature at which a drawn wear law and the nominal one wear alike,
        in [-40, 150] °C (40 [choice: a working joint's grease, about 20 K above its
        hall, docs/DATASET.md, "Gear lives"]).
    failure_spread : float
        σ of a lognormal factor on the failure severity, per life, in [0, 1] (0.1
        [choice]), capped at the fault's range.
    """

    paris_m: list[float] = _span(2.5, 4.0)
    threshold_share: list[float] = _span(0.0, 0.5)
    activation_kj_per_mol: list[float] = _span(20.0, 60.0)
    pivot_c: float = 40.0
    failure_spread: float = 0.1

    def check(self, key: str = "GrowthFamily") -> None:
        """Refuse a range not ``[lo, hi]`` with lo <= hi within its bounds, in one line
        naming the key.

        Raises
        ------
        ValueError
            As above, ``failure_spread`` outside [0, 1] or ``pivot_c`` outside
            [-40, 150] °C.
        """
        for name, lo, hi, hi_open in (("paris_m", 1.0, 6.0, False),
                                      ("threshold_share", 0.0, 1.0, True),
                                      ("activation_kj_per_mol", 1.0, 200.0, False)):
            r = getattr(self, name)
            if len(r) != 2 or not r[0] <= r[1]:
                raise ValueError(f"{key}.{name} must be [lo, hi] with lo <= hi, got {r}")
            for i, v in enumerate(r):
                check_range(v, lo, hi, f"{key}.{name}[{i}]", hi_open=hi_open)
        check_range(self.failure_spread, 0.0, 1.0, f"{key}.failure_spread")
        check_range(self.pivot_c, -40.0, 150.0, f"{key}.pivot_c", "°C")


def draw_growth(family: GrowthFamily, fault: str, nominal: RunToFailure, initial: float,
                pivot_load_nm: float, gear: int, seed: int, attempt: int = 0) -> RunToFailure:
    """One life's law drawn from a growth family (:class:`GrowthFamily`); pure and
    deterministic, each constant from its own keyed stream (adding a constant moves no
    other draw).

    Parameters
    ----------
    family : GrowthFamily
        Checked.
    fault : str
        A fault of :data:`swgsim.datasets.growth.LAWS`.
    nominal : RunToFailure
        The law the prognosis takes (its m, C, wear coefficient, failure severity).
    initial : float
        The severity at the onset [-].
    pivot_load_nm : float
        The load of the C-m pivot, > 0 [N m] (the data set's mean).
    gear, seed : int
        The life's gear instance and seed.
    attempt : int
        The draw's number, >= 0: a life drawn again (its length outside the plan,
        :func:`~.prognosis_evaluation.life_of`) takes the streams of its next attempt;
        attempt 0 keys as before attempts existed, so no earlier draw moves.

    Returns
    -------
    RunToFailure
        A crack's: m, C about the pivot, ΔK_th; a wear's: the Arrhenius law and its
        coefficient at the pivot temperature; both: the
        failure severity times exp(``failure_spread`` z), within (initial, the fault's
        top].
    """
    key = f"growth:{fault}:{gear}:" + (f"{attempt}:" if attempt else "")

    def u(name: str, lo_hi: list[float]) -> float:
        return float(_stream(seed, key + name).uniform(*lo_hi))

    fail = nominal.failure_severity(fault)
    z = float(_stream(seed, key + "failure").standard_normal())
    top = float(get_fault(fault).severity_range[1])
    drawn = float(np.clip(fail * np.exp(family.failure_spread * z), initial + 1e-3 * fail, top))
    if fault in LAWS["archard"]:  # the same rate at the pivot temperature
        q = u("activation", family.activation_kj_per_mol)
        at = float(film_factor(np.array(family.pivot_c), nominal.film_exponent)
                   / arrhenius_factor(np.array(family.pivot_c), q))
        return dataclasses.replace(nominal, failure=drawn, activation_kj_per_mol=q,
                                   wear_coeff_m_per_nm_rev=nominal.wear_coeff_m_per_nm_rev * at)
    m = u("paris_m", family.paris_m)
    d1 = DEPTH_AT_ONE_M[fault]
    pivot = float(nominal.shape_factor * nominal.stress_mpa_per_nm * pivot_load_nm * np.sqrt(
        np.pi * np.sqrt(initial * fail) * d1))  # ΔK at the mean load, mid-life [MPa √m]
    return dataclasses.replace(nominal, failure=drawn, paris_m=m,
                               paris_c=nominal.paris_c * pivot ** (nominal.paris_m - m),
                               threshold_sif=u("threshold", family.threshold_share) * pivot)
